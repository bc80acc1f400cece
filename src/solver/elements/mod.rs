//! The element library: every interaction as an element that gives its energy, its
//! forces and its 3×3 derivative blocks ∂f/∂x and ∂f/∂v, so that explicit, implicit and
//! block-descent solvers share one implementation. Each element is tested against finite
//! differences of its own energy and forces.

pub mod bending;
pub mod block;
pub mod columns;
pub mod couplings;
pub mod dual;
pub mod half;
pub mod hinge;
pub mod membrane;
pub mod quadratic;
pub mod spring;

#[cfg(test)]
pub(crate) mod testing;

pub use bending::{BendingFace, BendingLaw, BendingRigidity, BendingSurface, NO_HINGE};
pub use block::{BlockPattern, ElementPositions, SymmetricBlockMatrix, VelocityJacobian};
pub use couplings::{ConstantCouplings, WeightedCouplings};
pub use half::{HalfBlock, StoredBlock};
pub use membrane::{MembraneElement, MembraneMaterial};
pub use quadratic::QuadraticBending;
pub use spring::SpringElement;
