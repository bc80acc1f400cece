//! Elements derived from a cloth's triangle surface: hinges over interior edges and
//! membrane triangles, oriented by the grain.

use glam::Vec3;

use crate::components::{
    BendingDesc, BendingHinges, BendingLawDesc, MembraneDesc, MembraneTriangles, SpringKind, Springs,
};
use crate::memory::release;
use crate::solver::elements::bending::quadratic_weights;
use crate::solver::elements::hinge::hinge_angle;
use crate::solver::elements::{
    BendingFace, BendingLaw, BendingRigidity, BendingSurface, MembraneElement, NO_HINGE, QuadraticBending,
};

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
    release(directed);
    edges
}

/// The largest rest angle of a hinge [rad] that quadratic bending takes as flat (0.06°).
const FLAT_REST: f32 = 1e-3;

/// Bending over a surface at rest positions `x`: a hinge on every interior edge and a
/// face for every triangle with at least one, its coefficients in the warp/weft frame
/// (warp along `warp`, projected on each triangle); for quadratic bending only the
/// constant Jacobian they make ([`QuadraticBending`]). Quadratic bending is refused, with
/// what to do, where the surface is not flat at rest or a triangle beside a hinge has no
/// area.
pub fn build_bending(
    x: &[Vec3],
    triangles: &[[u32; 3]],
    bending: &BendingDesc,
    warp: Vec3,
) -> Result<BendingHinges, String> {
    let law = match bending.law {
        BendingLawDesc::Linear | BendingLawDesc::Quadratic => BendingLaw::Linear,
        BendingLawDesc::Zheng { kappa0 } => BendingLaw::Zheng { kappa0, kappa_r: ZHENG_REGULARISATION * kappa0 },
    };
    let rigidity = BendingRigidity {
        warp: bending.warp,
        weft: bending.weft,
        twist: bending.twist.unwrap_or(0.5 * (bending.warp * bending.weft).sqrt()),
    };
    let mut result = BendingHinges { law, rigidity, ..BendingHinges::default() };
    // The hinge on each side of each triangle, side k running from corner k to corner k+1.
    let mut sides = vec![[NO_HINGE; 3]; triangles.len()];
    // Sized up front: grown by doubling, the element arrays kept up to twice their length
    // for the whole run.
    let edges = interior_edges(triangles);
    result.vertices.reserve_exact(edges.len());
    result.rest_angle.reserve_exact(edges.len());
    result.faces.reserve_exact(triangles.len());
    for edge in &edges {
        let h = result.vertices.len() as u32;
        let vertices = [edge.o1, edge.o2, edge.i, edge.j];
        result.vertices.push(vertices);
        result.rest_angle.push(hinge_angle(vertices.map(|v| x[v as usize])));
        for t in edge.triangles {
            let tri = triangles[t as usize];
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                if (a, b) == (edge.i, edge.j) || (a, b) == (edge.j, edge.i) {
                    sides[t as usize][k] = h;
                }
            }
        }
    }
    release(edges);
    for (t, tri) in triangles.iter().enumerate() {
        let hinges = sides[t];
        if hinges.iter().all(|&h| h == NO_HINGE) {
            continue;
        }
        let p = tri.map(|v| x[v as usize]);
        let normal = (p[1] - p[0]).cross(p[2] - p[0]);
        let area = 0.5 * normal.length();
        let n = normal.normalize_or_zero();
        let u = (warp - warp.dot(n) * n).normalize_or_zero();
        let v = n.cross(u);
        let coefficients = std::array::from_fn(|k| {
            let side = p[(k + 1) % 3] - p[k];
            let m = side.cross(n).normalize_or_zero();
            let (m1, m2) = (m.dot(u), m.dot(v));
            side.length() / (2.0 * area) * Vec3::new(m1 * m1, m2 * m2, 2.0 * m1 * m2)
        });
        let mut vertices = Vec::with_capacity(6);
        for &h in hinges.iter().filter(|&&h| h != NO_HINGE) {
            for v in result.vertices[h as usize] {
                if !vertices.contains(&v) {
                    vertices.push(v);
                }
            }
        }
        let corners = std::array::from_fn(|k| {
            if hinges[k] == NO_HINGE {
                return [0; 4];
            }
            result.vertices[hinges[k] as usize]
                .map(|v| vertices.iter().position(|&w| w == v).expect("listed above") as u8)
        });
        let first = vertices[0];
        vertices.resize(6, first);
        result.faces.push(BendingFace {
            hinges,
            coefficients,
            area,
            vertices: vertices.try_into().expect("six entries"),
            corners,
        });
    }
    release(sides);
    if bending.law == BendingLawDesc::Quadratic {
        let weights: Vec<[f32; 4]> = result
            .vertices
            .iter()
            .zip(&result.rest_angle)
            .map(|(hinge, &angle)| {
                let p = hinge.map(|v| x[v as usize]);
                let at = 0.5 * (p[2] + p[3]);
                if angle.abs() > FLAT_REST {
                    return Err(format!(
                        "quadratic bending needs a cloth flat at rest, and the edge at {at} m bends {:.2}° at rest: \
                         use law: Linear for a curved rest shape",
                        angle.to_degrees()
                    ));
                }
                quadratic_weights(p).ok_or_else(|| format!("a triangle beside the edge at {at} m has no area"))
            })
            .collect::<Result<_, _>>()?;
        // The faces' constant Jacobian is all a step needs of them.
        let surface = BendingSurface { quadratic: &weights, ..result.view() };
        let quadratic = QuadraticBending::assemble(x, &surface, warp);
        let BendingHinges { vertices, rest_angle, faces, rigidity, .. } = result;
        release(vertices);
        release(rest_angle);
        release(faces);
        release(weights);
        return Ok(BendingHinges { law, rigidity, quadratic, ..BendingHinges::default() });
    }
    Ok(result)
}

/// How close to the warp or weft an edge must run to count as a warp or weft edge: 10°.
const GRAIN_ALIGNMENT: f32 = 0.985;

/// The edges whose strain a strain limit bounds. With `grain_only`: the structural
/// springs if there are any, else the triangle sides along the warp or the weft, else every
/// side (a mesh with no edges along the grain). Otherwise: every spring if there are any,
/// else every triangle side. Returns pairs and rest lengths.
pub fn limited_edges(
    x: &[Vec3],
    springs: &Springs,
    triangles: &[[u32; 3]],
    warp: Vec3,
    grain_only: bool,
) -> (Vec<[u32; 2]>, Vec<f32>) {
    let length = |[i, j]: [u32; 2]| (x[i as usize] - x[j as usize]).length();
    let structural: Vec<[u32; 2]> = springs
        .pairs
        .iter()
        .zip(&springs.kind)
        .filter(|(_, k)| !grain_only || **k == SpringKind::Structural)
        .map(|(p, _)| *p)
        .collect();
    if !structural.is_empty() {
        let rest = structural.iter().map(|&p| length(p)).collect();
        return (structural, rest);
    }
    let mut sides: Vec<[u32; 2]> =
        triangles.iter().flat_map(|&[a, b, c]| [[a, b], [b, c], [c, a]]).map(|[i, j]| [i.min(j), i.max(j)]).collect();
    sides.sort_unstable();
    sides.dedup();
    let along_grain = |[i, j]: [u32; 2]| {
        let d = (x[j as usize] - x[i as usize]).normalize_or_zero();
        let normal = warp.cross(d).length();
        // |cos| to the warp, or to the weft (|sin| to the warp, within the plane).
        d.dot(warp).abs() >= GRAIN_ALIGNMENT || normal >= GRAIN_ALIGNMENT && d.dot(warp).abs() <= 1.0 - GRAIN_ALIGNMENT
    };
    let aligned: Vec<[u32; 2]> = sides.iter().copied().filter(|&p| grain_only && along_grain(p)).collect();
    let chosen = if aligned.is_empty() { sides } else { aligned };
    let rest = chosen.iter().map(|&p| length(p)).collect();
    (chosen, rest)
}

/// Membrane triangles over a surface at rest positions `x`, warp along `warp`.
/// Degenerate triangles (which builders refuse before this) are skipped.
pub fn build_membranes(x: &[Vec3], triangles: &[[u32; 3]], membrane: MembraneDesc, warp: Vec3) -> MembraneTriangles {
    let mut membranes = MembraneTriangles::with_capacity(membrane.material(), triangles.len());
    for tri in triangles {
        if let Some(element) = MembraneElement::from_rest(tri.map(|v| x[v as usize]), warp) {
            membranes.push(*tri, element);
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

    /// A 5 × 4 grid of 1 cm cells in the XY plane: its rest positions and triangles.
    fn strip() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let (columns, rows, s) = (5, 4, 0.01f32);
        let rest: Vec<Vec3> =
            (0..columns * rows).map(|i| Vec3::new((i % columns) as f32 * s, (i / columns) as f32 * s, 0.0)).collect();
        let at = |c: usize, r: usize| (r * columns + c) as u32;
        let mut triangles = Vec::new();
        for r in 0..rows - 1 {
            for c in 0..columns - 1 {
                triangles.push([at(c, r), at(c + 1, r), at(c + 1, r + 1)]);
                triangles.push([at(c, r), at(c + 1, r + 1), at(c, r + 1)]);
            }
        }
        (rest, triangles)
    }

    /// The strip's rest positions bent about Y with curvature `kappa` [1/m].
    fn cylinder(rest: &[Vec3], kappa: f32) -> Vec<Vec3> {
        rest.iter().map(|p| Vec3::new((p.x * kappa).sin() / kappa, p.y, (1.0 - (p.x * kappa).cos()) / kappa)).collect()
    }

    /// The strip's bent area: every triangle sees one bent side except the outer half of
    /// each end column, whose bent side would be the free boundary [m²].
    const BENT_AREA: f32 = 3.0 * 3.0 * 1e-4;

    #[test]
    fn a_cylinder_bent_along_the_warp_stores_half_b_kappa_squared_per_area() {
        // Bent with curvature 20 /m.
        let (rest, triangles) = strip();
        let desc = BendingDesc { warp: 3e-5, weft: 1e-5, twist: None, law: BendingLawDesc::Linear };
        let bending = build_bending(&rest, &triangles, &desc, Vec3::X).expect("flat");
        let kappa = 20.0f32;
        let bent = cylinder(&rest, kappa);
        let view = bending.view();
        let mut delta = vec![0.0; bending.vertices.len()];
        view.angles(&bent, &mut delta);
        let energy: f32 = (0..bending.faces.len()).map(|f| view.face_energy(f, &delta)).sum();
        let expected = 0.5 * 3e-5 * kappa * kappa * BENT_AREA;
        assert!((energy / expected - 1.0).abs() < 1e-3, "energy {energy:e}, continuum {expected:e}");
        // Across the weft the weft rigidity applies.
        let across = build_bending(&rest, &triangles, &desc, Vec3::Y).expect("flat");
        let view = across.view();
        view.angles(&bent, &mut delta);
        let energy: f32 = (0..across.faces.len()).map(|f| view.face_energy(f, &delta)).sum();
        assert!((energy / (expected / 3.0) - 1.0).abs() < 1e-3, "weft energy {energy:e}");
    }

    #[test]
    fn a_cylinder_under_quadratic_bending_stores_the_isometric_measure_of_its_angles() {
        // On this grid a hinge's weights measure its angle θ by how far the edge stands
        // off the midpoint of its two opposite vertices: on a cylinder
        // `2 R (1 − cos θ) / s = θ c²`, `c = 2 sin(θ/2) / θ`, θ = κ s the angle between
        // neighbouring cells. So the cylinder stores `½ B κ² A c⁴`: 0.67 % less than the
        // continuum at θ = 0.2, 0.01 % at θ = 0.025.
        let (rest, triangles) = strip();
        let desc = BendingDesc { warp: 3e-5, weft: 1e-5, twist: None, law: BendingLawDesc::Quadratic };
        let bending = build_bending(&rest, &triangles, &desc, Vec3::X).expect("flat");
        for kappa in [20.0f32, 2.5] {
            let bent = cylinder(&rest, kappa);
            let energy = bending.quadratic.energy(&bent) as f32;
            let theta = kappa * 0.01;
            let chord = 2.0 * (0.5 * theta).sin() / theta;
            let expected = 0.5 * 3e-5 * kappa * kappa * BENT_AREA * chord.powi(4);
            assert!((energy / expected - 1.0).abs() < 2e-4, "κ = {kappa}: energy {energy:e}, expected {expected:e}");
        }
    }
}
