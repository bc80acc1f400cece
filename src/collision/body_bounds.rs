//! How far each cloth vertex may move, and to which side, so that no move within its
//! bound carries it into a solid body: the bodies' part of the conservative bounds that
//! block descent keeps every iteration within ([`Bound`]), beside the cloth's own
//! ([`super::motion_bounds`]).
//!
//! The bodies stand where the step ends and do not move during a solve, so, unlike two
//! pieces of cloth, only the vertex moves. Against its nearest convex body a vertex keeps
//! to the half-space beyond the plane tangent to the body's surface grown by the contact
//! thickness, through its nearest point: the body lies wholly behind that plane, so the
//! vertex may slide along the surface as far as it likes and never come within the
//! thickness of it. Against any other body (a second one near it, or a mesh, which need
//! not be convex) it keeps within a ball about where the bound was measured: the distance
//! to the body less the thickness, and at least half the distance, so that a vertex
//! resting within the thickness of a mesh still moves, never through the surface itself
//! (the contact stage after the step restores the thickness). A vertex found inside a
//! body keeps to the plane through itself: it may come out but not go deeper.

use glam::{Vec3, Vec4};
use rayon::prelude::*;

use super::body_contact::{CAUGHT, ContactBody};
use super::bvh::Aabb;
use super::motion_bounds::Bound;
use crate::solver::PARALLEL_MIN_LEN;

/// The bound's [`Bound::slack`] as a fraction of the contact thickness: half what the
/// contact stage lets pass as round-off ([`CAUGHT`]).
const SLACK: f32 = 0.5 * CAUGHT;

/// Narrows each `bounds[i]`, measured about the vertex at `x[i]`, so that no move within
/// it comes closer to any of the `bodies` than its contact thickness, or into a mesh.
/// Bounds that already keep a vertex farther from a body's bounding box are left alone.
/// A vertex whose bound already keeps to a plane (a still layer's under it,
/// [`super::motion_bounds`]) keeps off every body by a ball: its neighbours' bounds count
/// on that plane, which a body's must not replace.
pub fn limit(bodies: &[ContactBody], x: &[Vec3], bounds: &mut [Bound]) {
    if bodies.is_empty() {
        return;
    }
    x.par_iter().zip(bounds.par_iter_mut()).with_min_len(PARALLEL_MIN_LEN).for_each(|(&p, bound)| {
        // The plane of the nearest convex body (or of the body the vertex is inside): its
        // clearance, the plane, and the ball that stands in for it if a nearer one comes.
        let mut nearest: Option<(f32, Vec4, f32, f32)> = None;
        let mut radius = bound.radius;
        let planed = bound.plane != Vec4::ZERO;
        for body in bodies {
            let pose = &body.state.pose;
            let thickness = body.thickness;
            let ball = |distance: f32| (distance - thickness).max(0.5 * distance);
            let aabb = body.shape.compute_aabb(pose);
            let outside_box = Aabb { min: aabb.mins, max: aabb.maxs }.distance(&Aabb::around([p]));
            if ball(outside_box) >= radius {
                continue;
            }
            let near = body.surface_near(p);
            // A vertex exactly on the surface has no side to keep to.
            let Some(normal) = near.outward else {
                radius = 0.0;
                continue;
            };
            let inside = near.signed < 0.0;
            if planed || (!inside && !body.shape.is_convex()) {
                radius = radius.min(ball(near.signed).max(0.0));
                continue;
            }
            let clearance = near.signed - thickness;
            let instead = if inside { 0.0 } else { ball(near.signed) };
            // The plane lies the slack short of the thickness, so that a vertex put on its
            // slack rests at the thickness; through the vertex if that is nearer, so that
            // measuring again never lets it deeper.
            let slack = SLACK * thickness;
            let plane = normal.extend(normal.dot(p) - (clearance + slack).max(0.0));
            match nearest {
                Some((closest, ..)) if closest <= clearance => radius = radius.min(instead),
                Some((_, _, farther, _)) => {
                    radius = radius.min(farther);
                    nearest = Some((clearance, plane, instead, slack));
                }
                None => nearest = Some((clearance, plane, instead, slack)),
            }
        }
        bound.radius = radius;
        if let Some((_, plane, _, slack)) = nearest {
            bound.plane = plane;
            bound.slack = slack;
        }
    });
}

/// The convex body a vertex at `p` rests on, if any: one whose surface it lies within the
/// contact thickness of, and the slack a bound's plane puts beyond it; its outward normal
/// there, its velocity there and its friction.
pub fn resting_on(bodies: &[ContactBody], p: Vec3) -> Option<(Vec3, Vec3, f32)> {
    bodies.iter().filter(|body| body.shape.is_convex()).find_map(|body| {
        let near = body.surface_near(p);
        let resting = near.signed > 0.0 && near.signed <= body.thickness * (1.0 + CAUGHT);
        let normal = near.outward.filter(|_| resting)?;
        Some((normal, body.state.velocity_at(near.point), body.friction))
    })
}

#[cfg(test)]
pub(crate) mod tests {
    use parry3d::math::Pose3;
    use parry3d::shape::SharedShape;

    use super::*;
    use crate::collision::collider::{ColliderState, ContactResponse};
    use crate::collision::motion_bounds::tests::Lcg;

    /// The contact thickness of the test bodies [m].
    pub(crate) const THICKNESS: f32 = 0.001;

    /// A still body of `shape` at `at`, frictionless, [`THICKNESS`] thick.
    pub(crate) fn body(shape: SharedShape, at: Vec3) -> ContactBody {
        ContactBody {
            shape,
            state: ColliderState { pose: Pose3::from_translation(at), linear: Vec3::ZERO, angular: Vec3::ZERO },
            friction: 0.0,
            thickness: THICKNESS,
            response: ContactResponse::Slide,
            prop: false,
        }
    }

    /// The signed distance from `p` to the body's surface [m].
    fn signed(body: &ContactBody, p: Vec3) -> f32 {
        body.surface_near(p).signed
    }

    /// A unit cube as a triangle mesh: convex, but a mesh, which the bounds do not take
    /// as convex.
    fn cube_mesh(half: f32) -> SharedShape {
        let vertices: Vec<Vec3> = (0..8u32)
            .map(|k| glam::UVec3::new(k & 1, (k >> 1) & 1, (k >> 2) & 1).as_vec3() * 2.0 * half - half)
            .collect();
        let faces = [[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4], [2, 6, 3], [3, 6, 7]];
        let sides = [[0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5]];
        let indices: Vec<[u32; 3]> = faces.iter().chain(&sides).copied().collect();
        SharedShape::trimesh(vertices, indices).expect("a closed cube")
    }

    #[test]
    fn moves_within_the_bounds_keep_the_thickness_from_convex_bodies_and_out_of_meshes() {
        let bodies = [
            body(SharedShape::ball(0.1), Vec3::ZERO),
            body(SharedShape::cuboid(0.05, 0.02, 0.05), Vec3::new(0.25, 0.0, 0.0)),
            body(cube_mesh(0.05), Vec3::new(-0.25, 0.0, 0.0)),
        ];
        let mut rng = Lcg(3);
        let mut random = || 2.0 * Vec3::new(rng.next(), rng.next(), rng.next()) - Vec3::ONE;
        // Points around the bodies, some within the thickness of them, none inside.
        let x: Vec<Vec3> = (0..4000)
            .map(|_| 0.2 * random() * Vec3::new(2.0, 1.0, 1.0))
            .filter(|p| bodies.iter().all(|b| signed(b, *p) > 0.0))
            .collect();
        let mut bounds = vec![Bound::within(0.05); x.len()];
        limit(&bodies, &x, &mut bounds);
        let (mut moved, mut far) = (0, 0);
        for (p, bound) in x.iter().zip(&bounds) {
            for _ in 0..8 {
                let step = 0.05 * random();
                let end = *p + bound.allowed(*p, *p, step) * step;
                moved += usize::from(end != *p);
                for b in &bodies {
                    let (before, after) = (signed(b, *p), signed(b, end));
                    if b.shape.is_convex() {
                        // A vertex starting within the thickness may stay there, and go no
                        // deeper than the slack short of it.
                        let least = before.min(THICKNESS * (1.0 - SLACK));
                        assert!(after >= least - 1e-6, "{p} to {end}: {after} from {before}");
                    } else {
                        assert!(after > 0.0, "{p} to {end} entered the mesh");
                        if before >= 2.0 * THICKNESS {
                            assert!(after >= THICKNESS - 1e-6, "{p} to {end}: {after} from {before}");
                        }
                    }
                }
                far += usize::from(end.distance(*p) > 0.01);
            }
        }
        // The bounds do not stop everything: most moves go some way, many a centimetre.
        assert!(moved > 28_000 && far > 10_000, "{moved} moves, {far} over 1 cm");
    }

    #[test]
    fn a_vertex_resting_on_a_sphere_slides_along_it_and_not_into_it() {
        let sphere = body(SharedShape::ball(0.1), Vec3::ZERO);
        let p = Vec3::new(0.0, 0.1 + THICKNESS, 0.0);
        let mut bounds = [Bound::FREE];
        limit(std::slice::from_ref(&sphere), &[p], &mut bounds);
        let bound = bounds[0];
        // Along the surface the whole move, however long; into it, the slack only.
        assert_eq!(bound.allowed(p, p, Vec3::new(0.05, 0.0, 0.0)), 1.0);
        assert_eq!(bound.allowed(p, p, Vec3::new(0.0, 0.02, 0.03)), 1.0);
        let into = bound.allowed(p, p, Vec3::new(0.0, -0.01, 0.0));
        assert!((0.01 * into - SLACK * THICKNESS).abs() < 1e-7, "{into}");
        // Put the slack above the plane, it rests at the thickness.
        assert!((bound.room(p) - bound.slack).abs() < 1e-7);
        assert!((bound.slack - SLACK * THICKNESS).abs() < 1e-9);
    }
}
