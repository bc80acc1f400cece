//! Builders that turn descriptions into cloth data: grids, meshes from OBJ files, pin
//! selections and cuts.

pub mod disk;
pub mod grid;
pub mod mesh;
pub mod pins;
pub mod surface;
pub mod tear;

use glam::{Affine3A, EulerRot, Quat, Vec3};
use serde::{Deserialize, Serialize};

use crate::components::{BendingHinges, ClothMaterial, MembraneTriangles, Particles, Springs, Triangles};

/// The structure of a freshly built cloth, before it becomes an entity.
#[derive(Debug, Clone, PartialEq)]
pub struct ClothData {
    /// Particles at rest.
    pub particles: Particles,
    /// Springs at rest length.
    pub springs: Springs,
    /// Surface triangles.
    pub triangles: Triangles,
    /// Bending hinges (empty unless the material has bending).
    pub hinges: BendingHinges,
    /// Membrane triangles (empty unless the material has a membrane).
    pub membranes: MembraneTriangles,
    /// `(columns, rows)` for grids.
    pub grid: Option<(u32, u32)>,
}

impl ClothData {
    /// Adds the material's hinges and membrane triangles over the surface, with the warp
    /// along `warp` (world frame).
    pub fn add_surface_elements(&mut self, material: &ClothMaterial, warp: Vec3) {
        let (x, triangles) = (&self.particles.position, &self.triangles.indices);
        if let Some(bending) = &material.bending {
            self.hinges = surface::build_bending(x, triangles, bending, warp);
        }
        if let Some(membrane) = material.membrane {
            self.membranes = surface::build_membranes(x, triangles, membrane, warp);
        }
    }
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
        Self { translation: Vec3::ZERO, rotation_deg: Vec3::ZERO, scale: 1.0 }
    }
}

impl Placement {
    /// The warp direction in the world for a grain angle `grain_deg` in the local XY plane.
    pub fn warp(self, grain_deg: f32) -> Vec3 {
        let g = grain_deg.to_radians();
        self.to_affine().transform_vector3(Vec3::new(g.cos(), g.sin(), 0.0)).normalize()
    }

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
