//! Finite elements of a cloth beside its springs: bending hinges and membrane triangles.

use bevy_ecs::prelude::*;

use crate::solver::elements::{
    BendingFace, BendingLaw, BendingRigidity, BendingSurface, MembraneElement, MembraneMaterial, QuadraticBending,
};

/// Bending over the cloth's surface (B3, Z2): hinges on interior edges and the faces whose
/// curvature their angles make (see [`crate::solver::elements::bending`]); under quadratic
/// bending only the constant Jacobian they make, the hinges and faces left empty.
#[derive(Component, Debug, Clone, PartialEq)]
pub struct BendingHinges {
    /// `[o₁, o₂, i, j]` of each hinge (see [`crate::solver::elements::hinge`]).
    pub vertices: Vec<[u32; 4]>,
    /// Rest angle of each hinge [rad].
    pub rest_angle: Vec<f32>,
    /// The faces that bend.
    pub faces: Vec<BendingFace>,
    /// The moment–curvature law.
    pub law: BendingLaw,
    /// Rigidities by direction.
    pub rigidity: BendingRigidity,
    /// Quadratic bending's constant Jacobian (`law: Quadratic`), empty otherwise.
    pub quadratic: QuadraticBending,
}

impl Default for BendingHinges {
    fn default() -> Self {
        Self {
            vertices: Vec::new(),
            rest_angle: Vec::new(),
            faces: Vec::new(),
            law: BendingLaw::Linear,
            rigidity: BendingRigidity { warp: 0.0, weft: 0.0, twist: 0.0 },
            quadratic: QuadraticBending::default(),
        }
    }
}

impl BendingHinges {
    /// Whether the bending is quadratic: forces linear in the positions, and a constant
    /// Jacobian.
    pub fn is_quadratic(&self) -> bool {
        !self.quadratic.is_empty()
    }

    /// Number of hinges (interior edges that bend).
    pub fn hinge_count(&self) -> usize {
        match self.is_quadratic() {
            true => self.quadratic.hinge_count(),
            false => self.vertices.len(),
        }
    }

    /// The surface as the bending kernels see it (their faces, not quadratic bending's
    /// Jacobian).
    pub fn view(&self) -> BendingSurface<'_> {
        BendingSurface {
            hinges: &self.vertices,
            rest_angle: &self.rest_angle,
            faces: &self.faces,
            law: self.law,
            rigidity: self.rigidity,
            quadratic: &[],
        }
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

/// Edges whose strain is limited after every step (Z8).
#[derive(Component, Debug, Clone, Default, PartialEq)]
pub struct StrainLimit {
    /// Limited particle pairs: warp and weft edges.
    pub pairs: Vec<[u32; 2]>,
    /// Their rest lengths [m].
    pub rest_length: Vec<f32>,
    /// Largest strain allowed [-]; no limit when the list is empty.
    pub max_strain: f32,
    /// Most projection sweeps per step.
    pub iterations: u32,
}
