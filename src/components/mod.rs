//! The components of a garment entity: hot data as structure-of-arrays columns indexed by
//! particle number, plus derived caches. See [`Particles`], [`Springs`], [`Triangles`],
//! [`Pins`], [`BendingHinges`], [`MembraneTriangles`], [`UserForces`] and [`ClothTopology`].

mod cloth;
mod collider;
mod elements;
mod particles;
mod pins;
mod prop;
mod springs;
mod topology;
mod triangles;
mod user_forces;

pub use cloth::{BendingDesc, BendingLawDesc, Cloth, ClothMaterial, MembraneDesc, ParticleLayout, SpringCoefficients};
pub use collider::{Collider, ContactStats, SelfCollision, SelfTouching, Touching};
pub(crate) use elements::retain_kept;
pub use elements::{BendingHinges, MembraneTriangles, StrainLimit};
pub use particles::Particles;
pub use pins::{Grip, Grips, Pins};
pub use prop::{Prop, RigidStandIn};
pub use springs::{SpringKind, Springs};
pub use topology::{ClothElements, ClothTopology, Csr, RenderMesh, SolverParts, SolverWorkspace};
pub use triangles::Triangles;
pub use user_forces::UserForces;
