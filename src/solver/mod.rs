//! Pure kernels over slices: forces, integrators, constraints, contact, probes. Nothing
//! here touches the ECS, so every kernel can be tested and benchmarked on plain data.

pub mod cfl;
pub mod contact_springs;
pub mod descent;
pub mod elements;
pub mod forces;
pub mod gather;
pub mod geometry;
pub mod health;
pub mod implicit;
pub mod integrate;
pub mod multigrid;
pub mod ordering;
pub mod pins;
pub mod pipeline;
pub mod probes;
pub mod reduce;
pub mod strain_limit;

/// Below this many items a parallel loop runs on one thread: splitting costs more than it
/// saves on small cloths.
pub(crate) const PARALLEL_MIN_LEN: usize = 512;
