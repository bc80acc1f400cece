//! Pure kernels over slices: forces, integrators, constraints, contact, probes. Nothing
//! here touches the ECS, so every kernel can be tested and benchmarked on plain data.

pub mod cfl;
pub mod coarse_springs;
pub mod contact_springs;
pub mod descent;
pub mod elements;
pub mod filter;
pub mod floating;
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
pub mod spring_couplings;
pub mod strain_limit;
pub mod warm_start;

use glam::Vec3;
use rayon::prelude::*;

/// Below this many items a parallel loop runs on one thread: splitting costs more than it
/// saves on small cloths. 512 before: the multigrid's coarse levels of a few hundred nodes
/// ran on one thread, and hang_64 took 10.3 ms a frame against 9.6 to 9.9 at 128 (its
/// solve 3.9 against 3.4 to 3.5), hang_128 41.6 to 43.1 against 39.3 to 40.1, with
/// hang_256 and sphere_64 within the noise (alternating runs, two threads); 1 024 and
/// 2 048 were slower (hang_64 11.8 to 12.2 and 12.5 to 12.6 against 11.6 to 11.8 at 512).
/// The frames do not depend on it.
pub(crate) const PARALLEL_MIN_LEN: usize = 128;

/// Adds `row(i)` to each `out[i]`, in parallel: a matrix's part whose rows are formed one
/// by one (constant couplings, lumps, a prolongated correction) added to a product.
pub(crate) fn add_rows(out: &mut [Vec3], row: impl Fn(usize) -> Vec3 + Sync) {
    out.par_iter_mut().with_min_len(PARALLEL_MIN_LEN).enumerate().for_each(|(i, out)| *out += row(i));
}
