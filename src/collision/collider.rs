//! Collider shapes (parry3d) and their motion: static, or following keyframes.

use glam::{EulerRot, Quat, Vec3};
use parry3d::math::Pose3;
use parry3d::shape::SharedShape;
use serde::{Deserialize, Serialize};

use crate::builders::mesh::TriangleMesh;

/// The shape of a collider, in its local frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum ColliderShape {
    /// The half-space below the plane through the collider's origin with outward `normal`.
    Plane {
        /// Outward normal (local frame).
        normal: Vec3,
    },
    /// A ball.
    Sphere {
        /// Radius [m].
        radius: f32,
    },
    /// A capsule along local Y.
    Capsule {
        /// Half the distance between the end centres [m].
        half_height: f32,
        /// Radius [m].
        radius: f32,
    },
    /// A box.
    Cuboid {
        /// Half extents along local X, Y, Z [m].
        half_extents: Vec3,
    },
    /// A cylinder along local Y.
    Cylinder {
        /// Half height [m].
        half_height: f32,
        /// Radius [m].
        radius: f32,
    },
    /// The convex hull of points [m].
    ConvexHull {
        /// The points.
        points: Vec<Vec3>,
    },
    /// A closed triangle mesh from an OBJ file (relative to the scene's folder).
    Mesh {
        /// Path of the OBJ file.
        path: String,
    },
}

/// How cloth responds to touching a collider.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub enum ContactResponse {
    /// It slides with Coulomb friction and may lift off (Zheng's impulse response).
    #[default]
    Slide,
    /// It stays where it touched, moving with the body (Bricis's restrain-on-contact, B5).
    Stick,
    /// Durupınar's four regimes with two distance thresholds (D11), after Pelechano.
    Regimes(Regimes),
}

/// Durupınar's response regimes (D11). Distances are measured from the body's surface
/// grown by the contact thickness. Beyond `outside` nothing happens (case 0). Within it a
/// penalty pressure pushes the cloth out (case 1). Within `surface` the approach velocity is
/// also corrected, after Vassilev and Spanlang: `v = C_fric v_t − C_refl v_n + v_body`
/// (case 2). A particle found behind the surface, or whose path crossed it, is put back on
/// the surface and gets the same velocity correction (case 3, interference).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Regimes {
    /// T_outside: reach of the penalty pressure [m].
    pub outside: f32,
    /// T_surface: distance under which the velocity is corrected [m]; below `outside`.
    pub surface: f32,
    /// Penalty pressure per metre of depth inside `outside` [Pa/m]. A cloth of areal
    /// density ρ rests where the depth is ρ g / stiffness.
    pub stiffness: f32,
    /// Penalty pressure per unit of approach speed [Pa·s/m], so that the cloth does not
    /// bounce on the penalty for ever. Critical damping is 2 √(stiffness · ρ).
    #[serde(default)]
    pub damping: f32,
    /// C_fric: fraction of the tangential velocity a correction keeps [-].
    #[serde(default = "one")]
    pub tangential: f32,
    /// C_refl: fraction of the approach velocity a correction reflects [-].
    #[serde(default)]
    pub restitution: f32,
}

fn one() -> f32 {
    1.0
}

impl ContactResponse {
    /// How far beyond the contact thickness this response acts [m].
    pub fn reach(&self) -> f32 {
        match self {
            ContactResponse::Regimes(regimes) => regimes.outside,
            ContactResponse::Slide | ContactResponse::Stick => 0.0,
        }
    }
}

/// Why a shape could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ShapeError {
    /// The hull of the points is degenerate.
    #[error("the convex hull of these points is flat or empty; give at least four points not on one plane")]
    DegenerateHull,
    /// The mesh is not usable.
    #[error("the collider mesh is not usable: {0}")]
    Mesh(String),
}

impl ColliderShape {
    /// The parry3d shape; `mesh` supplies the triangles of a [`ColliderShape::Mesh`].
    pub fn build(&self, mesh: Option<&TriangleMesh>) -> Result<SharedShape, ShapeError> {
        Ok(match self {
            ColliderShape::Plane { normal } => SharedShape::halfspace(normal.normalize()),
            ColliderShape::Sphere { radius } => SharedShape::ball(*radius),
            ColliderShape::Capsule { half_height, radius } => SharedShape::capsule_y(*half_height, *radius),
            ColliderShape::Cuboid { half_extents } => {
                SharedShape::cuboid(half_extents.x, half_extents.y, half_extents.z)
            }
            ColliderShape::Cylinder { half_height, radius } => SharedShape::cylinder(*half_height, *radius),
            ColliderShape::ConvexHull { points } => {
                SharedShape::convex_hull(points).ok_or(ShapeError::DegenerateHull)?
            }
            ColliderShape::Mesh { .. } => {
                let mesh = mesh.ok_or_else(|| ShapeError::Mesh("no mesh was read".into()))?;
                SharedShape::trimesh_with_flags(
                    mesh.positions.clone(),
                    mesh.triangles.clone(),
                    parry3d::shape::TriMeshFlags::ORIENTED | parry3d::shape::TriMeshFlags::MERGE_DUPLICATE_VERTICES,
                )
                .map_err(|e| ShapeError::Mesh(format!("{e:?}")))?
            }
        })
    }
}

/// A placement: translation [m] and rotation (XYZ Euler angles [degrees]).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Pose {
    /// Position of the local origin [m].
    pub translation: Vec3,
    /// Rotation about X, then Y, then Z [degrees].
    pub rotation_deg: Vec3,
}

impl Pose {
    fn rotation(&self) -> Quat {
        let r = self.rotation_deg * (std::f32::consts::PI / 180.0);
        Quat::from_euler(EulerRot::XYZ, r.x, r.y, r.z)
    }

    /// The parry3d pose.
    pub fn to_pose3(self) -> Pose3 {
        Pose3::from_parts(self.translation, self.rotation())
    }
}

/// How a collider moves.
#[derive(Debug, Clone, PartialEq)]
pub enum ColliderMotion {
    /// It stays where it is.
    Static(Pose),
    /// Piecewise linear in translation and spherical-linear in rotation between keyframes
    /// `(time [s], pose)`, sorted by time; before the first and after the last it rests.
    Keyframes(Vec<(f32, Pose)>),
    /// Moved by another simulation (a rigid prop): its state as that simulation last set
    /// it, whatever the time asked.
    Driven(ColliderState),
}

/// Where a collider is at an instant and how its surface moves.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ColliderState {
    /// Pose.
    pub pose: Pose3,
    /// Velocity of its origin [m/s].
    pub linear: Vec3,
    /// Angular velocity [rad/s].
    pub angular: Vec3,
}

impl ColliderState {
    /// The state of a rapier body now.
    pub fn of_body(body: &rapier3d::prelude::RigidBody) -> ColliderState {
        let pose = *body.position();
        ColliderState { pose, linear: body.velocity_at_point(pose.translation), angular: body.angvel() }
    }

    /// Velocity of the collider's material at world point `p` [m/s].
    pub fn velocity_at(&self, p: Vec3) -> Vec3 {
        self.linear + self.angular.cross(p - self.pose.translation)
    }
}

impl ColliderMotion {
    /// The state at time `t` [s].
    pub fn state_at(&self, t: f32) -> ColliderState {
        match self {
            ColliderMotion::Static(pose) => {
                ColliderState { pose: pose.to_pose3(), linear: Vec3::ZERO, angular: Vec3::ZERO }
            }
            ColliderMotion::Driven(state) => *state,
            ColliderMotion::Keyframes(keys) => {
                let rest =
                    |pose: &Pose| ColliderState { pose: pose.to_pose3(), linear: Vec3::ZERO, angular: Vec3::ZERO };
                let (first, last) = (&keys[0], &keys[keys.len() - 1]);
                if t <= first.0 {
                    return rest(&first.1);
                }
                if t >= last.0 {
                    return rest(&last.1);
                }
                let k = keys.windows(2).position(|w| t < w[1].0).expect("t is inside the keyframes");
                let ((t0, a), (t1, b)) = (&keys[k], &keys[k + 1]);
                let s = (t - t0) / (t1 - t0);
                let (ra, rb) = (a.rotation(), b.rotation());
                let translation = a.translation.lerp(b.translation, s);
                let delta = rb * ra.inverse();
                let (axis, angle) = delta.to_axis_angle();
                ColliderState {
                    pose: Pose3::from_parts(translation, ra.slerp(rb, s)),
                    linear: (b.translation - a.translation) / (t1 - t0),
                    angular: axis * angle / (t1 - t0),
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keyframes_interpolate_position_and_give_the_segment_velocity() {
        let a = Pose { translation: Vec3::ZERO, rotation_deg: Vec3::ZERO };
        let b = Pose { translation: Vec3::new(2.0, 0.0, 0.0), rotation_deg: Vec3::new(0.0, 90.0, 0.0) };
        let motion = ColliderMotion::Keyframes(vec![(1.0, a), (3.0, b)]);
        let mid = motion.state_at(2.0);
        assert!((mid.pose.translation - Vec3::X).length() < 1e-6);
        assert!((mid.linear - Vec3::X).length() < 1e-6);
        assert!((mid.angular - Vec3::new(0.0, std::f32::consts::FRAC_PI_4, 0.0)).length() < 1e-5);
        assert_eq!(motion.state_at(0.0).linear, Vec3::ZERO);
        let sliding = ColliderMotion::Keyframes(vec![(0.0, a), (1.0, Pose { translation: Vec3::X, ..a })]);
        let state = sliding.state_at(0.5);
        assert_eq!(state.angular, Vec3::ZERO, "no rotation, no angular velocity");
        assert!(state.velocity_at(Vec3::new(3.0, 2.0, 1.0)).abs_diff_eq(Vec3::X, 1e-6));
        assert!((motion.state_at(5.0).pose.translation - 2.0 * Vec3::X).length() < 1e-6);
    }
}
