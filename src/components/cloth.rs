//! The garment marker and its material.

use bevy_ecs::prelude::*;
use serde::{Deserialize, Serialize};

/// A simulated piece of cloth: one entity that owns all of its particles.
#[derive(Component, Debug, Clone, PartialEq)]
pub struct Cloth {
    /// Name from the scene; edits and messages refer to the cloth by it.
    pub name: String,
    /// Grid resolution `(columns, rows)` when the cloth was built as a grid, so that named
    /// regions (corners, edges) keep their meaning; `None` for cloths built from meshes.
    pub grid: Option<(u32, u32)>,
}

/// Stiffness and damping of one family of springs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpringCoefficients {
    /// Hooke stiffness of each spring [N/m].
    pub stiffness: f32,
    /// Damping along the spring [N·s/m], acting on the relative velocity of its ends.
    #[serde(default)]
    pub damping: f32,
}

/// The physical description of a cloth, as the scene gave it. The per-spring values in
/// [`Springs`](crate::components::Springs) are derived from it when the cloth is built.
#[derive(Component, Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClothMaterial {
    /// Areal density [kg/m²]; each particle carries the mass of the area it represents.
    pub density: f32,
    /// Structural springs along warp and weft (grid rows and columns, mesh edges).
    pub stretch: SpringCoefficients,
    /// Shear springs across the diagonals of each grid cell (grids only).
    pub shear: SpringCoefficients,
    /// Bend springs that skip one particle (grids) or join the far vertices of two
    /// triangles sharing an edge (meshes).
    pub bend: SpringCoefficients,
}
