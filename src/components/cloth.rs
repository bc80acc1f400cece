//! The garment marker and its material.

use bevy_ecs::prelude::*;
use serde::{Deserialize, Serialize};

use crate::solver::elements::MembraneMaterial;

/// A simulated piece of cloth: one entity that owns all of its particles.
#[derive(Component, Debug, Clone, PartialEq)]
pub struct Cloth {
    /// Name from the scene; edits and messages refer to the cloth by it.
    pub name: String,
    /// How the cloth's particles relate to the way the user names them.
    pub layout: ParticleLayout,
    /// Distance its mid-surface keeps from solid bodies [m].
    pub thickness: f32,
}

/// What particle numbers mean to a user: grid regions, and the numbering of a mesh file.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ParticleLayout {
    /// Grid resolution `(columns, rows)` when the cloth was built as a grid, so that named
    /// regions (corners, edges) keep their meaning; `None` for cloths built from meshes.
    pub grid: Option<(u32, u32)>,
    /// For renumbered cloths, the particle number of each vertex of the source mesh (the
    /// numbers a scene uses); empty when particles keep the source numbering.
    pub renumbered: Vec<u32>,
}

impl ParticleLayout {
    /// The particle that a user's particle number refers to.
    pub fn particle(&self, source: u32) -> u32 {
        self.renumbered.get(source as usize).copied().unwrap_or(source)
    }
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

/// Membrane stiffness: Zheng's four constants, or an isotropic sheet.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum MembraneDesc {
    /// `d1` warp, `d2` weft, `d3` coupling, `d4` shear [N/m] (Zheng eq. 2.13).
    Anisotropic {
        /// Warp stiffness [N/m].
        d1: f32,
        /// Weft stiffness [N/m].
        d2: f32,
        /// Coupling [N/m].
        d3: f32,
        /// Shear stiffness [N/m].
        d4: f32,
    },
    /// Plane stress with 2-D Young's modulus [N/m] (modulus × thickness) and Poisson ratio.
    Isotropic {
        /// 2-D Young's modulus [N/m].
        young: f32,
        /// Poisson ratio [-], in [0, 0.5).
        poisson: f32,
    },
}

impl MembraneDesc {
    /// The constants of the membrane law.
    pub fn material(self) -> MembraneMaterial {
        match self {
            MembraneDesc::Anisotropic { d1, d2, d3, d4 } => MembraneMaterial { d1, d2, d3, d4 },
            MembraneDesc::Isotropic { young, poisson } => MembraneMaterial::isotropic(young, poisson),
        }
    }
}

/// A moment–curvature law for the bending hinges.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum BendingLawDesc {
    /// `m = B κ`.
    Linear,
    /// Zheng's `m = 2 B₀ √(κ₀|κ|)` up to κ₀ [1/m], then `B₀(|κ| + κ₀)`; the rigidities are B₀.
    Zheng {
        /// Knee curvature κ₀ [1/m].
        kappa0: f32,
    },
    /// `m = B κ` for small bends of a surface flat at rest, in Bergou et al.'s quadratic
    /// form (2006): each hinge's angle measured by a fixed linear combination of its four
    /// vertices, so the forces are linear in the positions and the Jacobian constant.
    /// Agrees with `Linear` to second order in each hinge's angle where the cloth does not
    /// stretch; about half the cost of a step's assembly on the hang scenes.
    Quadratic,
}

impl BendingLawDesc {
    /// The law's name, as a scene writes it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Linear => "Linear",
            Self::Zheng { .. } => "Zheng",
            Self::Quadratic => "Quadratic",
        }
    }
}

/// Bending over the hinges of the surface, by direction.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BendingDesc {
    /// Rigidity for bending along the warp [N·m] (per unit width: N·m²/m); the value a
    /// cantilever test of a strip cut along the warp measures.
    pub warp: f32,
    /// Rigidity for bending along the weft [N·m].
    pub weft: f32,
    /// Twist rigidity [N·m]; `½ √(warp · weft)` when not given.
    #[serde(default)]
    pub twist: Option<f32>,
    /// The law; linear unless given.
    #[serde(default = "linear_law")]
    pub law: BendingLawDesc,
}

fn linear_law() -> BendingLawDesc {
    BendingLawDesc::Linear
}

/// The physical description of a cloth, as the scene gave it: any combination of Provot
/// springs, membrane triangles and bending hinges. The element constants on the cloth
/// are derived from it when the cloth is built.
#[derive(Component, Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClothMaterial {
    /// Areal density [kg/m²]; each particle carries the mass of the area it represents.
    pub density: f32,
    /// Structural springs along warp and weft (grid rows and columns, mesh edges).
    #[serde(default)]
    pub stretch: Option<SpringCoefficients>,
    /// Shear springs across the diagonals of each grid cell (grids only).
    #[serde(default)]
    pub shear: Option<SpringCoefficients>,
    /// Bend springs that skip one particle (grids) or join the far vertices of two
    /// triangles sharing an edge (meshes).
    #[serde(default)]
    pub bend: Option<SpringCoefficients>,
    /// Membrane triangles (stretch and shear as a continuum).
    #[serde(default)]
    pub membrane: Option<MembraneDesc>,
    /// Bending hinges over interior edges.
    #[serde(default)]
    pub bending: Option<BendingDesc>,
}
