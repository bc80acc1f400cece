//! Elements derived from a cloth's triangle surface: hinges over interior edges and
//! membrane triangles, oriented by the grain.

use glam::Vec3;

use crate::components::{BendingDesc, BendingHinges, BendingLawDesc, MembraneDesc, MembraneTriangles};
use crate::solver::elements::dual::V3;
use crate::solver::elements::hinge::dihedral_angle;
use crate::solver::elements::{BendingLaw, HingeElement, MembraneElement};
use crate::solver::geometry::triangle_area;

/// Regularisation of Zheng's law, as a fraction of κ₀: below κ₀/100 the law is linear.
const ZHENG_REGULARISATION: f32 = 0.01;

/// An interior edge `i → j` as the first of its two triangles runs it, with the vertex
/// opposite it in that triangle (`o1`) and in the other (`o2`), and both triangles.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct InteriorEdge {
    /// Edge start.
    pub i: u32,
    /// Edge end.
    pub j: u32,
    /// Opposite vertex in the triangle running `i → j`.
    pub o1: u32,
    /// Opposite vertex in the other triangle.
    pub o2: u32,
    /// The two triangles.
    pub triangles: [u32; 2],
}

/// The interior edges of a triangle surface (edges with exactly two triangles), in
/// ascending order of their vertex pair; boundary and non-manifold edges are skipped.
pub fn interior_edges(triangles: &[[u32; 3]]) -> Vec<InteriorEdge> {
    // (edge, triangle, edge start as that triangle runs it, opposite vertex)
    let mut directed: Vec<([u32; 2], u32, u32, u32)> = triangles
        .iter()
        .enumerate()
        .flat_map(|(t, &[a, b, c])| {
            [(a, b, c), (b, c, a), (c, a, b)].map(|(i, j, o)| ([i.min(j), i.max(j)], t as u32, i, o))
        })
        .collect();
    directed.sort_unstable();
    let mut edges = Vec::new();
    let mut start = 0;
    while start < directed.len() {
        let key = directed[start].0;
        let end = start + directed[start..].iter().take_while(|d| d.0 == key).count();
        if end - start == 2 {
            let (first, second) = (directed[start], directed[start + 1]);
            let (i, j) = if first.2 == key[0] { (key[0], key[1]) } else { (key[1], key[0]) };
            edges.push(InteriorEdge { i, j, o1: first.3, o2: second.3, triangles: [first.1, second.1] });
        }
        start = end;
    }
    edges
}

/// Bending hinges over the interior edges of a surface at rest positions `x`, with the
/// rigidity of each interpolated between warp and weft by the direction it bends in:
/// `B = B_warp cos²φ + B_weft sin²φ`, φ between the bending direction (in the surface,
/// across the edge) and the warp.
pub fn build_hinges(x: &[Vec3], triangles: &[[u32; 3]], bending: &BendingDesc, warp: Vec3) -> BendingHinges {
    let law = match bending.law {
        BendingLawDesc::Linear => BendingLaw::Linear,
        BendingLawDesc::Zheng { kappa0 } => BendingLaw::Zheng { kappa0, kappa_r: ZHENG_REGULARISATION * kappa0 },
    };
    let mut hinges = BendingHinges { law, ..BendingHinges::default() };
    for edge in interior_edges(triangles) {
        let vertices = [edge.o1, edge.o2, edge.i, edge.j];
        let p = vertices.map(|v| x[v as usize]);
        let area: f32 = edge
            .triangles
            .iter()
            .map(|&t| {
                let [a, b, c] = triangles[t as usize].map(|v| x[v as usize]);
                triangle_area(a, b, c)
            })
            .sum();
        let e = p[3] - p[2];
        let normal = ((p[3] - p[2]).cross(p[0] - p[2]) + (p[2] - p[3]).cross(p[1] - p[3])).normalize_or_zero();
        let across = e.cross(normal).normalize_or_zero();
        let in_plane_warp = (warp - warp.dot(normal) * normal).normalize_or_zero();
        let cos2 = across.dot(in_plane_warp).powi(2);
        hinges.vertices.push(vertices);
        hinges.elements.push(HingeElement {
            rest_angle: dihedral_angle(p.map(|q| V3(q.to_array()))),
            rigidity: bending.warp * cos2 + bending.weft * (1.0 - cos2),
            area,
            width: area / e.length(),
        });
    }
    hinges
}

/// Membrane triangles over a surface at rest positions `x`, warp along `warp`.
/// Degenerate triangles (which builders refuse before this) are skipped.
pub fn build_membranes(x: &[Vec3], triangles: &[[u32; 3]], membrane: MembraneDesc, warp: Vec3) -> MembraneTriangles {
    let mut membranes = MembraneTriangles { material: membrane.material(), ..MembraneTriangles::default() };
    for tri in triangles {
        if let Some(element) = MembraneElement::from_rest(tri.map(|v| x[v as usize]), warp) {
            membranes.indices.push(*tri);
            membranes.elements.push(element);
        }
    }
    membranes
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_square_of_two_triangles_has_one_hinge_across_its_diagonal() {
        let edges = interior_edges(&[[0, 1, 2], [0, 2, 3]]);
        assert_eq!(edges, vec![InteriorEdge { i: 2, j: 0, o1: 1, o2: 3, triangles: [0, 1] }]);
    }

    #[test]
    fn hinge_rigidity_follows_the_bending_direction() {
        // Edge along Y: bending across it runs along X, the warp: full warp rigidity.
        let x = [Vec3::new(-1.0, 0.5, 0.0), Vec3::new(1.0, 0.5, 0.0), Vec3::ZERO, Vec3::Y];
        let bending = BendingDesc { warp: 4.0, weft: 1.0, law: BendingLawDesc::Linear };
        let hinges = build_hinges(&x, &[[2, 3, 0], [3, 2, 1]], &bending, Vec3::X);
        assert_eq!(hinges.vertices, vec![[0, 1, 2, 3]]);
        let h = hinges.elements[0];
        assert!((h.rigidity - 4.0).abs() < 1e-6 && h.rest_angle.abs() < 1e-6);
        assert!((h.area - 1.0).abs() < 1e-6 && (h.width - 1.0).abs() < 1e-6);
        let across = build_hinges(&x, &[[2, 3, 0], [3, 2, 1]], &bending, Vec3::Y);
        assert!((across.elements[0].rigidity - 1.0).abs() < 1e-6);
    }
}
