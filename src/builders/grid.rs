//! Rectangular grid cloth with Provot's structural, shear and bend springs (D1).

use glam::{Affine3A, Vec3};

use super::ClothData;
use crate::components::{
    BendingHinges, ClothMaterial, MembraneTriangles, ParticleLayout, Particles, SpringCoefficients, SpringKind,
    Springs, Triangles,
};
use crate::solver::geometry::lumped_masses;

/// Index of the particle in column `column` and row `row` of a grid `columns` wide.
#[inline]
pub fn grid_index(columns: u32, column: u32, row: u32) -> u32 {
    row * columns + column
}

/// Builds a `width × height` [m] grid of `columns × rows` particles in the local XY plane,
/// centred on the local origin (columns along +X, rows along +Y), placed by `placement`.
/// Each cell is split along the same diagonal, counter-clockwise seen from +Z.
pub fn build_grid(
    size: (f32, f32),
    resolution: (u32, u32),
    placement: Affine3A,
    material: &ClothMaterial,
) -> ClothData {
    let (columns, rows) = resolution;
    let (width, height) = size;
    let mut positions = Vec::with_capacity((columns * rows) as usize);
    for row in 0..rows {
        for column in 0..columns {
            let local = Vec3::new(
                width * (column as f32 / (columns - 1) as f32 - 0.5),
                height * (row as f32 / (rows - 1) as f32 - 0.5),
                0.0,
            );
            positions.push(placement.transform_point3(local));
        }
    }
    let at = |column, row| grid_index(columns, column, row);

    let mut triangles = Vec::with_capacity(2 * ((columns - 1) * (rows - 1)) as usize);
    for row in 0..rows - 1 {
        for column in 0..columns - 1 {
            let (a, b, c, d) = (at(column, row), at(column + 1, row), at(column + 1, row + 1), at(column, row + 1));
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }

    let mut springs = Springs::default();
    let mut add = |i: u32, j: u32, coefficients: Option<SpringCoefficients>, kind| {
        if let Some(c) = coefficients {
            let rest = (positions[i as usize] - positions[j as usize]).length();
            springs.push([i, j], rest, c.stiffness, c.damping, kind);
        }
    };
    for row in 0..rows {
        for column in 0..columns {
            let here = at(column, row);
            if column + 1 < columns {
                add(here, at(column + 1, row), material.stretch, SpringKind::Structural);
            }
            if row + 1 < rows {
                add(here, at(column, row + 1), material.stretch, SpringKind::Structural);
            }
            if column + 1 < columns && row + 1 < rows {
                add(here, at(column + 1, row + 1), material.shear, SpringKind::Shear);
                add(at(column + 1, row), at(column, row + 1), material.shear, SpringKind::Shear);
            }
            if column + 2 < columns {
                add(here, at(column + 2, row), material.bend, SpringKind::Bend);
            }
            if row + 2 < rows {
                add(here, at(column, row + 2), material.bend, SpringKind::Bend);
            }
        }
    }

    let masses = lumped_masses(&positions, &triangles, material.density);
    ClothData {
        particles: Particles::at_rest(positions, masses),
        springs,
        triangles: Triangles { indices: triangles },
        hinges: BendingHinges::default(),
        membranes: MembraneTriangles::default(),
        layout: ParticleLayout { grid: Some(resolution), renumbered: Vec::new() },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn material() -> ClothMaterial {
        let c = Some(SpringCoefficients { stiffness: 100.0, damping: 0.1 });
        ClothMaterial { density: 0.2, stretch: c, shear: c, bend: c, membrane: None, bending: None }
    }

    #[test]
    fn provot_topology_has_the_expected_spring_counts() {
        let (n, m) = (5u32, 4u32);
        let cloth = build_grid((1.0, 0.75), (n, m), Affine3A::IDENTITY, &material());
        let count = |kind| cloth.springs.kind.iter().filter(|k| **k == kind).count() as u32;
        assert_eq!(count(SpringKind::Structural), (n - 1) * m + n * (m - 1));
        assert_eq!(count(SpringKind::Shear), 2 * (n - 1) * (m - 1));
        assert_eq!(count(SpringKind::Bend), (n - 2) * m + n * (m - 2));
        assert_eq!(cloth.triangles.len() as u32, 2 * (n - 1) * (m - 1));
        assert!((cloth.particles.total_mass() - 0.2 * 0.75).abs() < 1e-6);
        assert!((cloth.springs.rest_length[0] - 0.25).abs() < 1e-6);
    }
}
