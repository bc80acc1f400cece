//! Choosing particles: by index, by a named region of a grid, or by a box.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::grid::grid_index;
use crate::components::ParticleLayout;

/// A corner of a grid cloth. Rows run along the grid's local +Y (bottom is row 0),
/// columns along local +X (left is column 0).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum GridCorner {
    /// Column 0, row 0.
    BottomLeft,
    /// Last column, row 0.
    BottomRight,
    /// Column 0, last row.
    TopLeft,
    /// Last column, last row.
    TopRight,
}

/// An edge of a grid cloth (see [`GridCorner`] for the orientation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum GridEdge {
    /// Row 0.
    Bottom,
    /// The last row.
    Top,
    /// Column 0.
    Left,
    /// The last column.
    Right,
}

/// A set of particles of one cloth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum PinSelection {
    /// Particles by number.
    Indices(Vec<u32>),
    /// Named corners of a grid.
    Corners(Vec<GridCorner>),
    /// A whole edge of a grid.
    Edge(GridEdge),
    /// Every particle inside an axis-aligned box, in world coordinates [m].
    InBox {
        /// Lower corner [m].
        min: Vec3,
        /// Upper corner [m].
        max: Vec3,
    },
    /// Every particle within `radius` [m] of `centre` (world coordinates): a clamp disk
    /// like Cusick's pedestal.
    WithinRadius {
        /// Centre [m].
        centre: Vec3,
        /// Radius [m].
        radius: f32,
    },
}

/// Why a selection selects nothing sensible.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SelectionError {
    /// An index is not a particle of the cloth.
    #[error("particle {index} does not exist: the cloth has {count} particles (0 to {last})", last = .count.saturating_sub(1))]
    OutOfRange {
        /// The index given.
        index: u32,
        /// How many particles there are.
        count: usize,
    },
    /// A mesh vertex that no face uses, so it is no particle.
    #[error("vertex {index} of the mesh is on no face, so it is not part of the cloth")]
    NotOnSurface {
        /// The index given.
        index: u32,
    },
    /// A named corner or edge on a cloth that is not a grid.
    #[error("corners and edges are named on grid cloths only; use Indices, InBox or WithinRadius for a mesh")]
    NotAGrid,
    /// A region with no particle inside.
    #[error("the {region} contains no particle")]
    Empty {
        /// The region, in words.
        region: String,
    },
}

impl PinSelection {
    /// The particles selected, sorted and unique, among `positions` of a cloth laid out as
    /// `layout` (grid regions; indices in the source mesh's numbering).
    pub fn resolve(&self, positions: &[Vec3], layout: &ParticleLayout) -> Result<Vec<u32>, SelectionError> {
        let count = positions.len();
        let grid = layout.grid;
        let mut chosen = match self {
            PinSelection::Indices(indices) => {
                let range = if layout.renumbered.is_empty() { count } else { layout.renumbered.len() };
                indices
                    .iter()
                    .map(|&index| match layout.particle(index) {
                        _ if index as usize >= range => Err(SelectionError::OutOfRange { index, count: range }),
                        u32::MAX => Err(SelectionError::NotOnSurface { index }),
                        particle => Ok(particle),
                    })
                    .collect::<Result<_, _>>()?
            }
            PinSelection::Corners(corners) => {
                let (columns, rows) = grid.ok_or(SelectionError::NotAGrid)?;
                corners
                    .iter()
                    .map(|corner| match corner {
                        GridCorner::BottomLeft => grid_index(columns, 0, 0),
                        GridCorner::BottomRight => grid_index(columns, columns - 1, 0),
                        GridCorner::TopLeft => grid_index(columns, 0, rows - 1),
                        GridCorner::TopRight => grid_index(columns, columns - 1, rows - 1),
                    })
                    .collect()
            }
            PinSelection::Edge(edge) => {
                let (columns, rows) = grid.ok_or(SelectionError::NotAGrid)?;
                match edge {
                    GridEdge::Bottom => (0..columns).map(|c| grid_index(columns, c, 0)).collect(),
                    GridEdge::Top => (0..columns).map(|c| grid_index(columns, c, rows - 1)).collect(),
                    GridEdge::Left => (0..rows).map(|r| grid_index(columns, 0, r)).collect(),
                    GridEdge::Right => (0..rows).map(|r| grid_index(columns, columns - 1, r)).collect(),
                }
            }
            PinSelection::InBox { min, max } => within(
                positions,
                |p| p.cmpge(*min).all() && p.cmple(*max).all(),
                || format!("box from {min} to {max}"),
            )?,
            PinSelection::WithinRadius { centre, radius } => within(
                positions,
                |p| p.distance(*centre) <= *radius,
                || format!("ball of radius {radius} m around {centre}"),
            )?,
        };
        chosen.sort_unstable();
        chosen.dedup();
        Ok(chosen)
    }
}

/// The particles at positions where `inside` holds; an error naming the region if none.
fn within(
    positions: &[Vec3],
    inside: impl Fn(Vec3) -> bool,
    region: impl Fn() -> String,
) -> Result<Vec<u32>, SelectionError> {
    let chosen: Vec<u32> = (0..positions.len() as u32).filter(|&i| inside(positions[i as usize])).collect();
    if chosen.is_empty() { Err(SelectionError::Empty { region: region() }) } else { Ok(chosen) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn named_regions_of_a_three_by_two_grid() {
        let positions = vec![Vec3::ZERO; 6];
        let grid = ParticleLayout { grid: Some((3, 2)), renumbered: Vec::new() };
        let resolve = |s: PinSelection| s.resolve(&positions, &grid).expect("valid");
        assert_eq!(resolve(PinSelection::Corners(vec![GridCorner::TopRight, GridCorner::BottomLeft])), vec![0, 5]);
        assert_eq!(resolve(PinSelection::Edge(GridEdge::Top)), vec![3, 4, 5]);
        assert_eq!(resolve(PinSelection::Edge(GridEdge::Right)), vec![2, 5]);
        assert_eq!(
            PinSelection::Indices(vec![6]).resolve(&positions, &grid),
            Err(SelectionError::OutOfRange { index: 6, count: 6 })
        );
        let mesh = ParticleLayout::default();
        assert_eq!(PinSelection::Edge(GridEdge::Top).resolve(&positions, &mesh), Err(SelectionError::NotAGrid));
        let renumbered = ParticleLayout { grid: None, renumbered: vec![5, 4, 3, 2, 1, 0] };
        assert_eq!(PinSelection::Indices(vec![0, 1]).resolve(&positions, &renumbered), Ok(vec![4, 5]));
    }

    #[test]
    fn a_box_selects_the_particles_inside_it() {
        let positions = vec![Vec3::ZERO, Vec3::ONE, Vec3::splat(2.0)];
        let chosen = PinSelection::InBox { min: Vec3::splat(0.5), max: Vec3::splat(3.0) }
            .resolve(&positions, &ParticleLayout::default());
        assert_eq!(chosen, Ok(vec![1, 2]));
        let chosen = PinSelection::WithinRadius { centre: Vec3::ZERO, radius: 1.8 }
            .resolve(&positions, &ParticleLayout::default());
        assert_eq!(chosen, Ok(vec![0, 1]));
        let none = PinSelection::WithinRadius { centre: Vec3::splat(9.0), radius: 0.1 }
            .resolve(&positions, &ParticleLayout::default());
        assert!(none.is_err_and(|e| e.to_string().contains("ball of radius 0.1 m")));
    }
}
