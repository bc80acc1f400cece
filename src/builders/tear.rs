//! Cutting a cloth along a plane.

use glam::Vec3;

use crate::components::{Springs, Triangles};

/// A cut: the plane through `point` with normal `normal`, limited to `radius` [m] around
/// `point` when given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cut {
    /// A point on the cutting plane [m].
    pub point: Vec3,
    /// The plane's normal (any length but zero).
    pub normal: Vec3,
    /// Reach of the cut around `point` [m]; `None` cuts the whole plane.
    pub radius: Option<f32>,
}

impl Cut {
    /// Whether the segment or polygon with corners `corners` straddles the cut: corners on
    /// both sides of the plane (a corner on the plane counts as the positive side) and its
    /// centre within reach.
    fn severs(&self, corners: &[Vec3]) -> bool {
        let positive = corners
            .iter()
            .filter(|c| (**c - self.point).dot(self.normal) >= 0.0)
            .count();
        if positive == 0 || positive == corners.len() {
            return false;
        }
        let centre = corners.iter().sum::<Vec3>() / corners.len() as f32;
        let along_plane = {
            let offset = centre - self.point;
            let n = self.normal.normalize();
            offset - offset.dot(n) * n
        };
        self.radius.is_none_or(|r| along_plane.length() <= r)
    }
}

/// Removes the springs and triangles that `cut` severs at positions `x`. Returns how many
/// springs and how many triangles were removed.
pub fn tear(
    cut: &Cut,
    x: &[Vec3],
    springs: &mut Springs,
    triangles: &mut Triangles,
) -> (usize, usize) {
    let pairs = springs.pairs.clone();
    let removed_springs = springs.remove_where(|s| cut.severs(&pairs[s].map(|p| x[p as usize])));
    let before = triangles.len();
    triangles
        .indices
        .retain(|t| !cut.severs(&t.map(|p| x[p as usize])));
    (removed_springs, before - triangles.len())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::components::SpringKind;

    #[test]
    fn a_cut_removes_only_what_crosses_it_within_reach() {
        let x = [
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(0.0, 5.0, 0.0),
            Vec3::new(1.0, 5.0, 0.0),
        ];
        let mut springs = Springs::default();
        springs.push([0, 1], 1.0, 1.0, 0.0, SpringKind::Structural);
        springs.push([2, 3], 1.0, 1.0, 0.0, SpringKind::Structural);
        springs.push([0, 2], 5.0, 1.0, 0.0, SpringKind::Structural);
        let mut triangles = Triangles {
            indices: vec![[0, 1, 3]],
        };
        let cut = Cut {
            point: Vec3::new(0.5, 0.0, 0.0),
            normal: Vec3::X,
            radius: Some(1.0),
        };
        assert_eq!(tear(&cut, &x, &mut springs, &mut triangles), (1, 0));
        assert_eq!(springs.pairs, vec![[2, 3], [0, 2]]);
        let everywhere = Cut {
            radius: None,
            ..cut
        };
        assert_eq!(tear(&everywhere, &x, &mut springs, &mut triangles), (1, 1));
    }
}
