//! Cutting a cloth along a plane.

use glam::Vec3;

use super::surface::build_bending;
use crate::components::{
    BendingDesc, BendingHinges, BendingLawDesc, MembraneTriangles, Springs, StrainLimit, Triangles, retain_kept,
};
use crate::solver::elements::NO_HINGE;

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
        let positive = corners.iter().filter(|c| (**c - self.point).dot(self.normal) >= 0.0).count();
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

/// What a cut removed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Torn {
    /// Springs removed.
    pub springs: usize,
    /// Surface triangles removed.
    pub triangles: usize,
    /// Bending hinges removed.
    pub hinges: usize,
    /// Membrane triangles removed.
    pub membranes: usize,
}

/// Removes every spring, triangle, hinge, membrane triangle and limited edge that `cut`
/// severs at positions `x`. Quadratic bending, kept only as its faces' Jacobian, is built
/// again at the rest positions `rest` over the triangles left.
pub fn tear(
    cut: &Cut,
    x: &[Vec3],
    rest: &[Vec3],
    springs: &mut Springs,
    triangles: &mut Triangles,
    hinges: &mut BendingHinges,
    membranes: &mut MembraneTriangles,
    limit: &mut StrainLimit,
) -> Torn {
    let severs = |corners: &[u32]| cut.severs(&corners.iter().map(|&p| x[p as usize]).collect::<Vec<_>>());
    let pairs = springs.pairs.clone();
    let removed_springs = springs.remove_where(|s| severs(&pairs[s]));
    let before = triangles.len();
    triangles.indices.retain(|t| !severs(t));
    let keep: Vec<bool> = limit.pairs.iter().map(|p| !severs(p)).collect();
    retain_parallel(&mut limit.pairs, &mut limit.rest_length, &keep);
    let hinges_before = hinges.hinge_count();
    match hinges.is_quadratic() {
        true => *hinges = quadratic_over(hinges, rest, &triangles.indices),
        false => cut_bending(hinges, |corners| severs(corners)),
    }
    let keep: Vec<bool> = membranes.indices.iter().map(|t| !severs(t)).collect();
    let membranes_before = membranes.indices.len();
    membranes.retain(&keep);
    Torn {
        springs: removed_springs,
        triangles: before - triangles.len(),
        hinges: hinges_before - hinges.hinge_count(),
        membranes: membranes_before - membranes.indices.len(),
    }
}

/// `bending`'s quadratic bending over `triangles` at rest positions `rest`: a hinge on
/// each interior edge left, and a face on each triangle left beside one.
fn quadratic_over(bending: &BendingHinges, rest: &[Vec3], triangles: &[[u32; 3]]) -> BendingHinges {
    let r = bending.rigidity;
    let desc = BendingDesc { warp: r.warp, weft: r.weft, twist: Some(r.twist), law: BendingLawDesc::Quadratic };
    build_bending(rest, triangles, &desc, bending.quadratic.warp)
        .expect("every hinge left was one of the cloth's, flat with two triangles of area when it was built")
}

/// Removes the hinges and faces that `severs`, renumbering the faces' hinges; a face
/// keeps its remaining sides.
fn cut_bending(hinges: &mut BendingHinges, severs: impl Fn(&[u32]) -> bool) {
    let keep: Vec<bool> = hinges.vertices.iter().map(|h| !severs(h)).collect();
    let mut renumber = vec![NO_HINGE; keep.len()];
    let mut next = 0;
    for (h, &kept) in keep.iter().enumerate() {
        if kept {
            renumber[h] = next;
            next += 1;
        }
    }
    retain_parallel(&mut hinges.vertices, &mut hinges.rest_angle, &keep);
    hinges.faces.retain_mut(|face| {
        for h in &mut face.hinges {
            if *h != NO_HINGE {
                *h = renumber[*h as usize];
            }
        }
        face.hinges.iter().any(|&h| h != NO_HINGE) && !severs(&face.vertices)
    });
}

/// Keeps the entries of two parallel columns where `keep` is true.
fn retain_parallel<A, B>(a: &mut Vec<A>, b: &mut Vec<B>, keep: &[bool]) {
    retain_kept(a, keep);
    retain_kept(b, keep);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::components::SpringKind;

    #[test]
    fn a_cut_removes_only_what_crosses_it_within_reach() {
        let x = [Vec3::ZERO, Vec3::X, Vec3::new(0.0, 5.0, 0.0), Vec3::new(1.0, 5.0, 0.0)];
        let mut springs = Springs::default();
        springs.push([0, 1], 1.0, 1.0, 0.0, SpringKind::Structural);
        springs.push([2, 3], 1.0, 1.0, 0.0, SpringKind::Structural);
        springs.push([0, 2], 5.0, 1.0, 0.0, SpringKind::Structural);
        let mut triangles = Triangles { indices: vec![[0, 1, 3]] };
        let cut = Cut { point: Vec3::new(0.5, 0.0, 0.0), normal: Vec3::X, radius: Some(1.0) };
        let (mut hinges, mut membranes, mut limit) =
            (BendingHinges::default(), MembraneTriangles::default(), StrainLimit::default());
        let torn = tear(&cut, &x, &x, &mut springs, &mut triangles, &mut hinges, &mut membranes, &mut limit);
        assert_eq!((torn.springs, torn.triangles), (1, 0));
        assert_eq!(springs.pairs, vec![[2, 3], [0, 2]]);
        let everywhere = Cut { radius: None, ..cut };
        let torn = tear(&everywhere, &x, &x, &mut springs, &mut triangles, &mut hinges, &mut membranes, &mut limit);
        assert_eq!((torn.springs, torn.triangles), (1, 1));
    }
}
