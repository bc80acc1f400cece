//! Builders that turn descriptions into cloth data: grids, meshes from OBJ files, pin
//! selections and cuts.

pub mod grid;
pub mod mesh;
pub mod pins;
pub mod tear;

use glam::{Affine3A, EulerRot, Quat, Vec3};
use serde::{Deserialize, Serialize};

use crate::components::{Particles, Springs, Triangles};

/// The structure of a freshly built cloth, before it becomes an entity.
#[derive(Debug, Clone, PartialEq)]
pub struct ClothData {
    /// Particles at rest.
    pub particles: Particles,
    /// Springs at rest length.
    pub springs: Springs,
    /// Surface triangles.
    pub triangles: Triangles,
    /// `(columns, rows)` for grids.
    pub grid: Option<(u32, u32)>,
}

/// Placement of a cloth in the world: rotate (Euler angles, X then Y then Z, in degrees),
/// then scale uniformly, then translate.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Placement {
    /// Where the cloth's local origin goes [m].
    pub translation: Vec3,
    /// Rotation about X, then Y, then Z [degrees].
    pub rotation_deg: Vec3,
    /// Uniform scale [-], > 0.
    pub scale: f32,
}

impl Default for Placement {
    fn default() -> Self {
        Self {
            translation: Vec3::ZERO,
            rotation_deg: Vec3::ZERO,
            scale: 1.0,
        }
    }
}

impl Placement {
    /// The affine map from the cloth's local frame to the world.
    pub fn to_affine(self) -> Affine3A {
        let r = self.rotation_deg * (std::f32::consts::PI / 180.0);
        Affine3A::from_scale_rotation_translation(
            Vec3::splat(self.scale),
            Quat::from_euler(EulerRot::XYZ, r.x, r.y, r.z),
            self.translation,
        )
    }
}
