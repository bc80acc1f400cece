//! Finite elements of a cloth beside its springs: bending hinges and membrane triangles.

use bevy_ecs::prelude::*;

use crate::solver::elements::{BendingLaw, HingeElement, MembraneElement, MembraneMaterial};

/// Bending hinges over the interior edges of the cloth's surface (B3, Z2).
#[derive(Component, Debug, Clone, PartialEq)]
pub struct BendingHinges {
    /// `[o₁, o₂, i, j]` of each hinge (see [`crate::solver::elements::hinge`]).
    pub vertices: Vec<[u32; 4]>,
    /// Rest angle, rigidity, area and width of each hinge.
    pub elements: Vec<HingeElement>,
    /// The moment–curvature law shared by all hinges.
    pub law: BendingLaw,
}

impl Default for BendingHinges {
    fn default() -> Self {
        Self { vertices: Vec::new(), elements: Vec::new(), law: BendingLaw::Linear }
    }
}

/// Membrane triangles: anisotropic St. Venant–Kirchhoff in the warp/weft frame (Z2).
#[derive(Component, Debug, Clone, PartialEq)]
pub struct MembraneTriangles {
    /// Particle indices of each triangle.
    pub indices: Vec<[u32; 3]>,
    /// Rest state of each triangle.
    pub elements: Vec<MembraneElement>,
    /// Membrane constants shared by all triangles.
    pub material: MembraneMaterial,
}

impl Default for MembraneTriangles {
    fn default() -> Self {
        Self {
            indices: Vec::new(),
            elements: Vec::new(),
            material: MembraneMaterial { d1: 0.0, d2: 0.0, d3: 0.0, d4: 0.0 },
        }
    }
}
