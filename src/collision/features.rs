//! A polyhedral collider's sharp features against cloth (E5, Z5). The body-contact kernel
//! keeps cloth *vertices* out of a body; against a smooth body that suffices, but a box,
//! a convex hull or a triangle mesh has edges and corners that slip between the
//! vertices: a cloth edge cuts across a table's rim while both its ends rest outside,
//! and a box's corner pokes through a cloth triangle without touching any of its
//! corners. So the collider's sharp convex edges meet the cloth's edges, and its corners
//! the cloth's triangles, as the cloth–cloth pairs of [`super::self_contact`] do, with
//! the collider's side infinitely heavy (Zheng eq. 3.30):
//!
//! - a pair whose closest points, at the end of the step, lie inside both primitives and
//!   closer than the contact thickness, or whose paths met during the step (the
//!   coplanarity cubic of [`Sweep`]), is pushed apart along the normal both primitives
//!   share (the cross product of the two edges, or the cloth triangle's normal) to the
//!   contact thickness, on the side the cloth came from, or on the other where that one
//!   lies inside the body (behind every face at the feature);
//! - the push moves the cloth's vertices by their weights in the pair and their inverse
//!   masses (pinned vertices stay), and its change of the step's mean velocity is added
//!   to their velocities, as self-contact does.
//!
//! Everything happens in the body's frame at the end of the step, where the body is
//! still: the cloth's start positions are carried along by the body's motion over the
//! step, as the vertex trace of [`super::body_contact`] does, so a moving box meets the
//! cloth with its leading edges. These contacts are frictionless; the vertices' contacts
//! on the faces give the friction. A prop takes the opposite of the pushes, after the
//! step whose solve balanced it ([`super::coupling`]): a box resting on a hammock then
//! keeps the cloth off its rim but jitters a little.

use std::collections::BTreeMap;

use glam::{Quat, Vec3};
use parry3d::shape::SharedShape;
use rayon::prelude::*;

use super::body_contact::{BodyLoad, ContactTotals};
use super::bvh::{Aabb, Bvh};
use super::collider::ColliderState;
use super::primitives::{Sweep, closest_between_segments, closest_on_triangle};
use crate::solver::PARALLEL_MIN_LEN;
use crate::solver::gather::Gather;

/// Cosine of the smallest angle between two faces' normals that makes their common edge
/// sharp (15°). A cloth edge of length `l` across a ridge of exterior angle `θ` cuts
/// below it by at most about `l θ / 4`: at 15° and 1 cm edges, under a millimetre, within
/// any contact thickness; the edges of a finely tessellated smooth body stay out of the
/// tests.
const SHARP_COS: f32 = 0.966;
/// Cosine above which two sharp edges at a vertex count as one straight ridge, which
/// pokes nothing: the vertex is a corner only where its sharp edges turn.
const RIDGE_COS: f32 = 0.99;
/// Passes over the candidate pairs: a push can bring a neighbouring pair into contact.
const PASSES: u32 = 4;
/// Distance within which a cloth edge's path meets a feature, for the cubic [m].
const HIT_TOLERANCE: f32 = 1e-6;

/// The sharp features of a polyhedral collider, in its local frame, with a tree over each
/// kind.
#[derive(Debug, Clone)]
pub struct SharpFeatures {
    points: Vec<Vec3>,
    /// Convex edges whose faces meet at more than 15°.
    edges: Vec<[u32; 2]>,
    /// Each sharp edge's two faces' outward normals: the body near the edge lies behind
    /// both.
    edge_normals: Vec<[Vec3; 2]>,
    /// Vertices where sharp edges turn.
    corners: Vec<u32>,
    /// The outward normals of the faces at the corners, each corner's in turn
    /// (`corner_normal_ends` says where each ends).
    corner_normals: Vec<Vec3>,
    corner_normal_ends: Vec<u32>,
    edge_tree: Bvh,
    corner_tree: Bvh,
}

impl SharpFeatures {
    /// The sharp features of a cuboid, convex hull or triangle mesh (closed, consistently
    /// wound); none for smooth shapes (planes, spheres, capsules, cylinders), whose
    /// surface the vertex contacts already follow, or for a polyhedron with no sharp edge.
    pub fn of_shape(shape: &SharedShape) -> Option<SharpFeatures> {
        let (points, triangles) = if let Some(cuboid) = shape.as_cuboid() {
            cuboid.to_trimesh()
        } else if let Some(hull) = shape.as_convex_polyhedron() {
            hull.to_trimesh()
        } else if let Some(mesh) = shape.as_trimesh() {
            (mesh.vertices().to_vec(), mesh.indices().to_vec())
        } else {
            return None;
        };
        Self::from_triangles(points, &triangles)
    }

    /// The sharp features of a closed mesh. Its winding may be either way round; the sign
    /// of its volume says which.
    pub fn from_triangles(points: Vec<Vec3>, triangles: &[[u32; 3]]) -> Option<SharpFeatures> {
        let corner = |t: [u32; 3]| t.map(|k| points[k as usize]);
        let volume: f32 = triangles.iter().map(|&t| corner(t)[0].dot(corner(t)[1].cross(corner(t)[2]))).sum();
        let outward = if volume < 0.0 { -1.0 } else { 1.0 };
        let normal = |t: [u32; 3]| {
            let [a, b, c] = corner(t);
            outward * (b - a).cross(c - a).normalize_or_zero()
        };
        let mut faces: BTreeMap<[u32; 2], Vec<usize>> = BTreeMap::new();
        for (f, t) in triangles.iter().enumerate() {
            for (p, q) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                faces.entry([p.min(q), p.max(q)]).or_default().push(f);
            }
        }
        let (edges, edge_normals): (Vec<[u32; 2]>, Vec<[Vec3; 2]>) = faces
            .into_iter()
            .filter_map(|(edge, faces)| {
                let &[f, g] = faces.as_slice() else {
                    return None;
                };
                let (nf, ng) = (normal(triangles[f]), normal(triangles[g]));
                // g's vertex off this edge lies below f's plane where the edge is convex.
                let apex = triangles[g].into_iter().find(|k| !edge.contains(k)).expect("a triangle has a third vertex");
                let convex = nf.dot(points[apex as usize] - points[edge[0] as usize]) < 0.0;
                (convex && nf.dot(ng) < SHARP_COS).then_some((edge, [nf, ng]))
            })
            .unzip();
        if edges.is_empty() {
            return None;
        }
        let direction = |[p, q]: [u32; 2], from: u32| {
            let to = if p == from { q } else { p };
            (points[to as usize] - points[from as usize]).normalize_or_zero()
        };
        let mut corners: Vec<u32> = edges.iter().flatten().copied().collect();
        corners.sort_unstable();
        corners.dedup();
        corners.retain(|&k| {
            let at: Vec<Vec3> = edges.iter().filter(|e| e.contains(&k)).map(|&e| direction(e, k)).collect();
            at.iter().enumerate().any(|(i, a)| at[i + 1..].iter().any(|b| a.dot(*b).abs() < RIDGE_COS))
        });
        let mut at_corner: BTreeMap<u32, Vec<Vec3>> = corners.iter().map(|&k| (k, Vec::new())).collect();
        for &t in triangles {
            for k in t {
                if let Some(normals) = at_corner.get_mut(&k) {
                    // A flat face made of several triangles counts once.
                    let n = normal(t);
                    if normals.iter().all(|m| m.dot(n) < RIDGE_COS) {
                        normals.push(n);
                    }
                }
            }
        }
        // In the map's order, which is the corners' (sorted above).
        let mut corner_normals = Vec::new();
        let mut corner_normal_ends = Vec::with_capacity(corners.len());
        for normals in at_corner.into_values() {
            corner_normals.extend(normals);
            corner_normal_ends.push(corner_normals.len() as u32);
        }
        let edge_boxes: Vec<Aabb> = edges.iter().map(|e| Aabb::around(e.iter().map(|&k| points[k as usize]))).collect();
        let corner_boxes: Vec<Aabb> = corners.iter().map(|&k| Aabb::around([points[k as usize]])).collect();
        Some(SharpFeatures {
            edge_tree: Bvh::build(&edge_boxes),
            corner_tree: Bvh::build(&corner_boxes),
            points,
            edges,
            edge_normals,
            corners,
            corner_normals,
            corner_normal_ends,
        })
    }

    /// Number of sharp edges.
    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }

    /// Number of corners.
    pub fn corner_count(&self) -> usize {
        self.corners.len()
    }

    /// The outward normals of the faces at corner `k`.
    fn corner_faces(&self, k: usize) -> &[Vec3] {
        let start = k.checked_sub(1).map_or(0, |before| self.corner_normal_ends[before] as usize);
        &self.corner_normals[start..self.corner_normal_ends[k] as usize]
    }
}

/// The cloth as the feature contacts see it.
#[derive(Debug, Clone, Copy)]
pub struct ClothSurface<'a> {
    /// Edges of its triangles, each once.
    pub edges: &'a [[u32; 2]],
    /// Its triangles.
    pub triangles: &'a [[u32; 3]],
    /// Inverse masses with pinned particles at zero [1/kg].
    pub free_inv_mass: &'a [f32],
    /// Positions at the start of the step [m].
    pub start: &'a [Vec3],
}

/// A candidate pair whose boxes over the step meet.
#[derive(Debug, Clone, Copy)]
enum Candidate {
    /// A cloth edge and a sharp edge (indices).
    Edge(u32, u32),
    /// A cloth triangle and a corner (indices).
    Corner(u32, u32),
}

/// Buffers kept from step to step.
#[derive(Debug, Default)]
pub struct FeatureScratch {
    /// The cloth's start positions in the body's frame at the end of the step, carried
    /// along by the body's motion.
    start: Vec<Vec3>,
    /// Its end positions in that frame.
    end: Vec<Vec3>,
    candidates: Vec<Candidate>,
    gather: Gather<Candidate>,
}

/// A push found for a pair: the cloth vertices and their weights in the pair, the normal
/// (body frame, pointing to where the cloth belongs) and how far along it the cloth's
/// point must move [m].
struct Push {
    vertices: [u32; 3],
    weights: [f32; 3],
    normal: Vec3,
    depth: f32,
}

impl SharpFeatures {
    /// Pushes the cloth's edges off this body's sharp edges and its triangles off its
    /// corners at the end of a step of `h` [s] that took the cloth from `cloth.start` to
    /// `x`, with the body at `state` at the step's end; `thickness` is the distance kept
    /// [m]. Moves `x` and changes `v` by what the pushes changed the step's mean velocity,
    /// and returns the pushes' impulses on the cloth as contact totals and as the load
    /// the body gave (which a prop takes back).
    pub fn resolve(
        &self,
        state: &ColliderState,
        thickness: f32,
        h: f32,
        cloth: ClothSurface<'_>,
        x: &mut [Vec3],
        v: &mut [Vec3],
        scratch: &mut FeatureScratch,
    ) -> (ContactTotals, BodyLoad) {
        let mut totals = ContactTotals::default();
        let mut load = BodyLoad::default();
        let pose = state.pose;
        cloth
            .start
            .par_iter()
            .with_min_len(PARALLEL_MIN_LEN)
            .map(|&s| pose.inverse_transform_point(s + h * state.velocity_at(s)))
            .collect_into_vec(&mut scratch.start);
        x.par_iter()
            .with_min_len(PARALLEL_MIN_LEN)
            .map(|&p| pose.inverse_transform_point(p))
            .collect_into_vec(&mut scratch.end);
        self.candidates(cloth, thickness, scratch);
        let rotation: Quat = pose.rotation;
        for _ in 0..PASSES {
            let mut pushed = false;
            for &candidate in &scratch.candidates {
                let Some(push) = self.push(candidate, cloth, thickness, &scratch.start, &scratch.end) else {
                    continue;
                };
                let Push { vertices, weights, normal, depth } = push;
                let inv = vertices.map(|k| cloth.free_inv_mass[k as usize]);
                let denominator: f32 = (0..3).map(|k| weights[k] * weights[k] * inv[k]).sum();
                if denominator <= 0.0 {
                    continue;
                }
                let lambda = depth / denominator;
                let mut impulse = Vec3::ZERO;
                for k in 0..3 {
                    let i = vertices[k] as usize;
                    if inv[k] == 0.0 || weights[k] == 0.0 {
                        continue;
                    }
                    let local = weights[k] * inv[k] * lambda * normal;
                    let moved = rotation * local;
                    scratch.end[i] += local;
                    x[i] += moved;
                    v[i] += moved / h;
                    impulse += moved / (h * inv[k]);
                    load.add(&BodyLoad::at(x[i], moved / (h * inv[k])));
                }
                totals.impulse += impulse;
                totals.normal_impulse += impulse.length();
                pushed = true;
            }
            if !pushed {
                break;
            }
        }
        (totals, load)
    }

    /// Lists the pairs whose boxes over the step, grown by the thickness, meet.
    fn candidates(&self, cloth: ClothSurface<'_>, thickness: f32, scratch: &mut FeatureScratch) {
        let FeatureScratch { start, end, candidates, gather } = scratch;
        let (start, end) = (&*start, &*end);
        let swept = |vertices: &[u32]| {
            Aabb::around(vertices.iter().flat_map(|&k| [start[k as usize], end[k as usize]])).inflated(thickness)
        };
        let moves = |vertices: &[u32]| vertices.iter().any(|&k| cloth.free_inv_mass[k as usize] > 0.0);
        let edges = cloth.edges.len();
        gather.run(edges + cloth.triangles.len(), candidates, |i, out| {
            if let Some(t) = i.checked_sub(edges) {
                let triangle = &cloth.triangles[t];
                if moves(triangle) {
                    self.corner_tree.query(&swept(triangle), |k| out.push(Candidate::Corner(t as u32, k)));
                }
            } else {
                let edge = &cloth.edges[i];
                if moves(edge) {
                    self.edge_tree.query(&swept(edge), |k| out.push(Candidate::Edge(i as u32, k)));
                }
            }
        });
    }

    /// The push a candidate needs, if its primitives are closer than `thickness` at the
    /// end of the step (`end`) or their paths from `start` met.
    fn push(
        &self,
        candidate: Candidate,
        cloth: ClothSurface<'_>,
        thickness: f32,
        start: &[Vec3],
        end: &[Vec3],
    ) -> Option<Push> {
        let inside = |w: f32| w > 0.0 && w < 1.0;
        match candidate {
            Candidate::Edge(e, k) => {
                let [a, b] = cloth.edges[e as usize];
                let [p, q] = self.edges[k as usize].map(|k| self.points[k as usize]);
                let (a0, b0, a1, b1) = (start[a as usize], start[b as usize], end[a as usize], end[b as usize]);
                let (s, u) = closest_between_segments(a1, b1, p, q);
                let near = inside(s) && inside(u) && a1.lerp(b1, s).distance(p.lerp(q, u)) < thickness;
                let (s, u) = if near {
                    (s, u)
                } else {
                    Sweep { start: [a0, b0, p, q], end: [a1, b1, p, q] }.edge_edge_hit(HIT_TOLERANCE)?.1
                };
                if !(inside(s) && inside(u)) {
                    return None;
                }
                let point = p.lerp(q, u);
                let normal = side((b0 - a0).cross(q - p), (b1 - a1).cross(q - p), a0.lerp(b0, s) - point)?;
                let normal = outside(normal, &self.edge_normals[k as usize]);
                let depth = thickness - normal.dot(a1.lerp(b1, s) - point);
                (depth > 0.0).then_some(Push { vertices: [a, b, a], weights: [1.0 - s, s, 0.0], normal, depth })
            }
            Candidate::Corner(t, k) => {
                let triangle = cloth.triangles[t as usize];
                let [a0, b0, c0] = triangle.map(|i| start[i as usize]);
                let [a1, b1, c1] = triangle.map(|i| end[i as usize]);
                let point = self.points[self.corners[k as usize] as usize];
                let w = closest_on_triangle(point, a1, b1, c1);
                let at = |w: [f32; 3], [a, b, c]: [Vec3; 3]| w[0] * a + w[1] * b + w[2] * c;
                let near = w.iter().all(|&w| w > 0.0) && at(w, [a1, b1, c1]).distance(point) < thickness;
                let w = if near {
                    w
                } else {
                    Sweep { start: [point, a0, b0, c0], end: [point, a1, b1, c1] }.point_triangle_hit(HIT_TOLERANCE)?.1
                };
                if !w.iter().all(|&w| w > 0.0) {
                    return None;
                }
                let normal = side((b0 - a0).cross(c0 - a0), (b1 - a1).cross(c1 - a1), at(w, [a0, b0, c0]) - point)?;
                let normal = outside(normal, self.corner_faces(k as usize));
                let depth = thickness - normal.dot(at(w, [a1, b1, c1]) - point);
                (depth > 0.0).then_some(Push { vertices: triangle, weights: w, normal, depth })
            }
        }
    }
}

/// The unit normal at the end of the step (along `end`) pointing to the side of the
/// feature the cloth was on at the start (`offset` from the feature, measured along
/// `start`): the side it must end on. None where either normal is degenerate (parallel
/// edges, a collapsed triangle) or the cloth started on the feature.
fn side(start: Vec3, end: Vec3, offset: Vec3) -> Option<Vec3> {
    let (start, end) = (start.try_normalize()?, end.try_normalize()?);
    let before = start.dot(offset);
    if before == 0.0 {
        return None;
    }
    let sign = before.signum() * start.dot(end).signum();
    Some(sign * end)
}

/// `normal`, or its opposite where it points into the body: behind every face at the
/// feature (`faces`, their outward normals), where a push along it would leave the cloth
/// inside. The side the cloth came from is inside where a step began with it already
/// across the feature (its vertices put back onto the faces on either side of a rim, an
/// edge between them left cutting the rim): held there, it stayed across for the rest of
/// the run.
fn outside(normal: Vec3, faces: &[Vec3]) -> Vec3 {
    if faces.iter().all(|f| f.dot(normal) < 0.0) { -normal } else { normal }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube() -> SharpFeatures {
        let shape = SharedShape::cuboid(0.5, 0.5, 0.5);
        SharpFeatures::of_shape(&shape).expect("a cube has sharp edges")
    }

    /// A body at rest at the origin.
    fn still() -> ColliderState {
        ColliderState { pose: parry3d::math::Pose3::IDENTITY, linear: Vec3::ZERO, angular: Vec3::ZERO }
    }

    /// One free cloth triangle that starts the step at `start`.
    fn one_triangle(start: &[Vec3; 3]) -> ClothSurface<'_> {
        ClothSurface { edges: &[[0, 1], [1, 2], [0, 2]], triangles: &[[0, 1, 2]], free_inv_mass: &[1.0; 3], start }
    }

    #[test]
    fn a_cube_has_twelve_edges_and_eight_corners_and_a_ball_none() {
        let cube = cube();
        assert_eq!((cube.edge_count(), cube.corner_count()), (12, 8));
        assert!(SharpFeatures::of_shape(&SharedShape::ball(1.0)).is_none());
        // An octahedron wound the other way round: the sign of its volume corrects it.
        let points = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        let mut triangles = Vec::new();
        for (a, b) in [(0, 2), (2, 1), (1, 3), (3, 0)] {
            triangles.push([a, 4, b]);
            triangles.push([b, 5, a]);
        }
        let octahedron = SharpFeatures::from_triangles(points, &triangles).expect("sharp");
        assert_eq!((octahedron.edge_count(), octahedron.corner_count()), (12, 6));
    }

    /// A cloth edge falling across the top edge of a cube, with both its ends clear of the
    /// cube at the end of the step (one above the top face's plane, one beside the side
    /// face's), is stopped at the contact thickness off the cube's edge.
    #[test]
    fn a_cloth_edge_falling_across_a_cube_edge_is_kept_off_it() {
        let cube = cube();
        let state = still();
        // Across the edge at y = z = 0.5 (along x): from over the top to beside the side.
        let start = [Vec3::new(0.1, 0.8, 0.45), Vec3::new(0.1, 0.45, 0.8)];
        let fall = Vec3::new(0.0, -0.15, -0.15);
        let mut x = start.map(|p| p + fall);
        let mut v = [fall / 0.01; 2];
        let thickness = 0.01;
        let cloth = ClothSurface { edges: &[[0, 1]], triangles: &[], free_inv_mass: &[1.0, 1.0], start: &start };
        let (totals, load) =
            cube.resolve(&state, thickness, 0.01, cloth, &mut x, &mut v, &mut FeatureScratch::default());
        assert!(totals.impulse != Vec3::ZERO, "a push was given");
        let edge_line = |p: Vec3| Vec3::new(0.0, p.y - 0.5, p.z - 0.5);
        let middle = edge_line(x[0].lerp(x[1], 0.5));
        let outward = Vec3::new(0.0, 1.0, 1.0).normalize();
        assert!((middle.dot(outward) - thickness).abs() < 1e-4, "the edge's middle is {middle} off the cube's edge");
        // The impulse reported is the momentum the pushes gave the cloth.
        let given: Vec3 = v.iter().map(|v| *v - fall / 0.01).sum();
        assert!((given - totals.impulse).length() < 1e-3 * given.length());
        // The body's load is the same impulse, with its moment taken where it was given:
        // both ends pushed alike, so about the edge's middle there is none.
        assert!((load.impulse - totals.impulse).length() < 1e-6);
        assert!(load.moment_about(x[0].lerp(x[1], 0.5)).length() < 1e-4 * given.length(), "{load:?}");
    }

    /// A cloth edge that begins a step already across a cube's edge (its middle 2 mm
    /// inside the cube, its ends clear of it, as vertex contacts on the two faces leave
    /// it) is pushed out to the contact thickness outside, not kept on the side it came
    /// from.
    #[test]
    fn a_cloth_edge_left_across_a_cube_edge_is_pushed_out() {
        let cube = cube();
        let state = still();
        let inside = 0.002;
        let start = [Vec3::new(0.1, 0.8 - inside, 0.2 - inside), Vec3::new(0.1, 0.2 - inside, 0.8 - inside)];
        let (mut x, mut v) = (start, [Vec3::ZERO; 2]);
        let thickness = 0.005;
        let cloth = ClothSurface { edges: &[[0, 1]], triangles: &[], free_inv_mass: &[1.0, 1.0], start: &start };
        cube.resolve(&state, thickness, 0.01, cloth, &mut x, &mut v, &mut FeatureScratch::default());
        let middle = x[0].lerp(x[1], 0.5) - Vec3::new(0.1, 0.5, 0.5);
        let outward = Vec3::new(0.0, 1.0, 1.0).normalize();
        assert!((middle.dot(outward) - thickness).abs() < 1e-4, "the edge's middle is {middle} off the cube's edge");
    }

    /// A cloth triangle that begins a step with a cube's corner 2 mm through it (its
    /// vertices clear of the cube) is pushed out to the contact thickness over the corner.
    #[test]
    fn a_triangle_left_on_a_cube_corner_is_pushed_out() {
        let cube = cube();
        let state = still();
        let (corner, normal) = (Vec3::splat(0.5), Vec3::ONE.normalize());
        let u = Vec3::new(1.0, -1.0, 0.0).normalize();
        let w = normal.cross(u);
        let start = [0.0f32, 120.0, 240.0].map(|angle| {
            let (sin, cos) = angle.to_radians().sin_cos();
            corner - 0.002 * normal + 0.5 * (cos * u + sin * w)
        });
        let (mut x, mut v) = (start, [Vec3::ZERO; 3]);
        let thickness = 0.005;
        let cloth = one_triangle(&start);
        cube.resolve(&state, thickness, 0.01, cloth, &mut x, &mut v, &mut FeatureScratch::default());
        let over = (x[0] + x[1] + x[2]) / 3.0 - corner;
        assert!((over.dot(normal) - thickness).abs() < 1e-4, "the triangle ends {over} off the corner");
    }

    /// A cube moving up into a resting cloth triangle meets it with its top corner, which
    /// would pass through the triangle between its vertices: the triangle is pushed ahead
    /// of the corner and ends a thickness above it.
    #[test]
    fn a_rising_corner_lifts_a_triangle_it_would_poke_through() {
        let cube = cube();
        // Rotated so that one corner points straight up, moving up at 1 m/s.
        let up = Quat::from_rotation_arc(Vec3::ONE.normalize(), Vec3::Y);
        let h = 0.05;
        let apex = 3f32.sqrt() * 0.5;
        let state = ColliderState {
            pose: parry3d::math::Pose3::from_parts(Vec3::ZERO, up),
            linear: Vec3::Y,
            angular: Vec3::ZERO,
        };
        // A wide triangle resting just above the apex's start (which is apex − h).
        let y = apex - 0.02;
        let start = [Vec3::new(-1.0, y, -1.0), Vec3::new(1.0, y, -1.0), Vec3::new(0.0, y, 1.0)];
        let mut x = start;
        let mut v = [Vec3::ZERO; 3];
        let thickness = 0.005;
        let cloth = one_triangle(&start);
        cube.resolve(&state, thickness, h, cloth, &mut x, &mut v, &mut FeatureScratch::default());
        // The apex lies under the point with weights (¼, ¼, ½).
        let over = 0.25 * (x[0] + x[1]) + 0.5 * x[2];
        assert!((over.y - (apex + thickness)).abs() < 1e-4, "the triangle ends at {over} over the apex at {apex}");
        assert!(v.iter().all(|v| v.y > 0.0), "and moves up with it");
    }
}
