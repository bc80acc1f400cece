//! Smoothed-aggregation multigrid (Vaněk, Mandel & Brezina 1996): the preconditioner that
//! lets conjugate gradients solve a stiff cloth's implicit step in tens of iterations
//! instead of hundreds.
//!
//! Block Jacobi only reaches a particle's neighbours per iteration, so the slow, smooth
//! modes of a large stiff sheet (the whole sheet swinging and stretching under its weight)
//! take as many iterations as the sheet is wide. Multigrid solves those modes on coarser
//! copies of the cloth: particles are grouped into aggregates of a neighbourhood each, an
//! aggregate moves as a rigid body (the tentative prolongator: three translations and
//! three rotations about its centre per aggregate, two coarse nodes), one damped Jacobi
//! step smooths that prolongator so that neighbouring aggregates blend, and the coarse
//! matrix is the Galerkin product `Pᵀ A P` (the finest level's matrix is the system with
//! the bending's couplings across an edge lumped onto the diagonal, see
//! [`Multigrid::prepare`]). Levels repeat until a few dozen nodes remain, solved exactly
//! by dense Cholesky. A symmetric V-cycle with block-Jacobi-preconditioned
//! Chebyshev smoothing (6 × 6 blocks of an aggregate's translation and rotation below the
//! finest level) is then a fixed, symmetric positive definite preconditioner.
//!
//! The smoother is the bottleneck of the cycle: visiting the coarse levels twice (a
//! W-cycle) saved 2 % of the iterations on hang_128, a third smoothing product 19 %.
//! Chebyshev steps aimed at the top eighth of `D⁻¹ A`'s spectrum damp it better than
//! damped Jacobi steps for the same products: 20 %, 22 % and 19 % fewer iterations on the
//! hang bench scenes at 64², 128² and 256². They need the spectral radius from above
//! (beyond its interval the polynomial amplifies), so the power iterations run until the
//! estimate settles and the interval's top has a wider margin.
//!
//! The rotations matter because at a frame-sized step the system is nearly the sheet's
//! stiffness alone (`h² k` is some 10⁴ times the mass), whose soft modes are the rigid
//! motions, turns included: a sheet bending in its plane turns each patch of it. With
//! translations alone the hang bench scenes took 45, 77 and 111 iterations a step at
//! 64², 128² and 256² particles; with rotations 24, 45 and 63.
//!
//! Contact springs between layers of a heap couple vertices that no aggregate groups
//! together. The finest level holds their diagonal blocks (in the system), the coarse
//! levels the springs whole, summed into a sparse matrix beside their Galerkin matrices
//! ([`CoarseSprings`]): with the diagonal blocks alone, a coarse level took the motion of
//! two layers together along their normal for as stiff as the springs, and could not
//! correct it. fold_64 stepped as sphere_64_adaptive is (`step_motion: 0.25`, multigrid)
//! took 497 312 iterations over its 180 frames with the diagonal blocks alone, 12 533
//! with the springs whole (29 November 2026).
//!
//! The grouping depends only on the block pattern, so [`Hierarchy`] is built once per
//! topology. The numbers ([`Multigrid`]) are kept from system to system: the system of a
//! step differs little from the last one's, so only the finest smoother is rebuilt for
//! each, and the prolongators and coarse matrices only when the iterations they give have
//! grown (see [`Multigrid::prepare`]), or for every system while levels one system old
//! prove too weak, as they do at frame-sized steps on a swinging sheet (see
//! [`Multigrid::record`]). Constraint filters `S` (pins, contact normals) act
//! on the finest level: the prolongator is filtered, `S P`, and the current filter is
//! applied again to what is restricted and prolongated, so coarse corrections never move a
//! pinned particle or cross a contact normal, even with a prolongator built under another
//! filter. Every kernel is a parallel loop over rows or blocks with a
//! fixed order inside, so the result does not depend on the number of threads.

use glam::{Mat3, Mat3A, Vec3, Vec3A, Vec4};
use rayon::prelude::*;

use super::coarse_springs::CoarseSprings;
use super::elements::block::{SymmetricBlock, block_product, by_parts, times};
use super::elements::half::row_product;
use super::elements::spring::{outer, skew};
use super::elements::{BlockPattern, HalfBlock, StoredBlock, SymmetricBlockMatrix, WeightedCouplings};
use super::filter::{Filters, free_inverse};
use super::implicit::StepSystem;
use super::pipeline::pipelined;
use super::spring_couplings::SpringCouplings;
use super::{PARALLEL_MIN_LEN, add_rows};
use crate::components::Csr;
use crate::memory::release;

/// Levels stop coarsening at this many nodes; the coarsest system is then factored
/// densely (3 × 48 unknowns: a few hundred thousand flops).
const COARSEST_NODES: usize = 48;

/// A coarsening that keeps more than this share of the nodes has stalled (a pattern with
/// no neighbours left to group), and the hierarchy stops there.
const MIN_REDUCTION: f32 = 0.7;

/// The largest coarsest level factored densely (a 600-unknown Cholesky, 7·10⁷ flops).
const DENSE_LIMIT: usize = 200;

/// Most power iterations per system for the spectral radius of the Jacobi-preconditioned
/// matrix. They start from the last system's dominant mode, and the first one's estimate
/// is measured against the last system's radius, so on hang_256's finest level 1.85 a
/// system reach [`POWER_TOLERANCE`] over 40 frames, where two were the least (its coarse
/// levels take three to six);
/// from an arbitrary start on a 256² sheet four gave 2.1 against a radius of 3.2, twelve
/// 3.0.
const MAX_POWER_ITERATIONS: usize = 30;

/// Relative change of the spectral radius estimate at which the power iterations stop.
const POWER_TOLERANCE: f64 = 0.01;

/// Factor on the estimated spectral radius for the top of the Chebyshev smoother's
/// interval. Beyond its interval the Chebyshev polynomial grows instead of damping, and
/// the power iterations' estimate is from below: at hang_64's first paired level it was
/// 28 % below an estimate of 200 iterations. A degree-2 step over an interval of ratio 8
/// amplifies beyond 1.125 times the interval's top, so 1.3 holds for estimates down to
/// 0.68 ρ; 1.15 took 3 to 9 % fewer iterations on the hang bench scenes, but holds only
/// down to 0.77 ρ. (The prolongator's Jacobi weight takes the estimate as it is, see
/// [`Level::smoother`].)
const CHEBYSHEV_MARGIN: f32 = 1.3;

/// Top over bottom of the Chebyshev smoother's interval: the eigenvalues of `D⁻¹ A` it
/// damps, the upper part of the spectrum that the coarse levels leave to it.
const CHEBYSHEV_RATIO: f32 = 8.0;

/// An aggregate's rotation about an axis is kept as a coarse unknown where its points'
/// spread about the axis is at least this share of the largest: a line of points does
/// not turn about itself, and an unknown that hardly moves anything is all round-off.
const MIN_SPREAD: f32 = 1e-3;

/// Jacobi rotation sweeps for a 3 × 3 symmetric eigenproblem (quadratic convergence:
/// round-off within four or five).
const JACOBI_SWEEPS: usize = 6;

/// Degree of the Chebyshev smoother (products with the level's matrix per smoothing)
/// before and after each coarse correction, for a system that is not a heap
/// ([`HEAP_SMOOTHING_DEGREE`]).
const SMOOTHING_DEGREE: usize = 2;

/// The smoother's degree for a heap: a system with at least one acting contact spring
/// for every [`HEAP_SHARE`] particles, layers of cloth lying on layers.
/// The layers' moving together is a slow mode that the free sheet does not have, and
/// that the coarse levels hold only as well as their aggregates allow. Over five starts
/// (thirteenth session), a third product each way took fold_64_adaptive from 44 763
/// iterations to 34 802, and its median frame from 49 to 26 ms. Each iteration costs
/// about a quarter more, so it pays only where it saves more than that: degree 3
/// wherever contact restricted a particle or a spring acted made sphere_64_adaptive's
/// resting drape (14 to 22 acting springs on 4 096 particles) take 16.4 iterations a
/// frame against 21.4 in the same state, for the same time, and its median frame 2 %
/// longer over five starts (mean 15.8 against 15.4 ms); on a free sheet it costs more
/// than it saves (hang_64: 6.7 iterations a frame against 7.1, 5 to 10 % more time).
const HEAP_SMOOTHING_DEGREE: usize = 3;

/// One acting contact spring for every this many particles makes a system a heap
/// ([`HEAP_SMOOTHING_DEGREE`]): fold_64_adaptive's heap holds 78 to 548 springs on its
/// 4 096 particles (about 225 at rest), sphere_64_adaptive's drape 14 to 22 at rest (78
/// at most, as it lands).
const HEAP_SHARE: usize = 64;

/// Below this many pairs the paired smoothers' inverses are formed on one thread: a pair
/// costs as much as some sixteen rows of a vector loop ([`PARALLEL_MIN_LEN`]).
const PAIRS_MIN_LEN: usize = PARALLEL_MIN_LEN / 16;

/// Fine rows of `A S P` formed at a time for the Galerkin product. Formed whole, `A S P`
/// was the largest array of the levels (1.7 MB, 420 bytes a particle, on the 64² hang
/// scene); two chunks of 512 rows are some 0.4 MB.
const PRODUCT_ROWS: usize = 512;

/// The coarse levels are rebuilt once a solve takes more than this many iterations
/// beyond the first solve after they were built: about what a rebuild costs (on hang_64
/// its smoothers, prolongators and Galerkin products took 1.25 ms a step, an iteration
/// 0.46 ms), so that old levels are kept only while they cost less than new ones. Kept
/// until they took half as many again as new ones (plus two), the hang bench scenes took
/// 10 %, 9 % and 5 % more iterations at 32², 64² and 256² (432 against 390 in 60 frames,
/// 1 089 against 987 in 120, 793 against 752 in 60), and the same at 128².
const REBUILD_SLACK: u32 = 2;

/// Systems that rebuild the coarse levels each, without trying the last ones, once the
/// first solve with one-system-old levels took too many iterations. Then one system tries
/// them again, so a sheet that comes to rest goes back to keeping its levels.
const REBUILD_RUN: u32 = 32;

/// The structure of the levels: which nodes group into which aggregate, and the block
/// patterns of the prolongators and coarse matrices. Depends only on the block patterns.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Hierarchy {
    /// The finest level's pattern, the couplings of the particles that share a triangle or
    /// a spring, where the system's pattern holds the bending's, across an edge, as well
    /// (see [`Multigrid::prepare`]); laid out for a [`SymmetricBlockMatrix`]. `None` where
    /// the system's pattern is the finest level's (its bending's couplings kept beside
    /// it), which would otherwise be held twice: 48 bytes a particle.
    fine: Option<BlockPattern>,
    /// From the finest level down, each coarsening of the level above.
    coarsenings: Vec<Coarsening>,
    /// Nodes of the coarsest level.
    coarsest: usize,
}

/// One level's grouping into the next, coarser level: each aggregate becomes two nodes,
/// `2J` its translation and `2J + 1` its rotation about its centre.
#[derive(Debug, Clone, PartialEq)]
struct Coarsening {
    /// Whether this level's nodes come in pairs (translation, rotation) of one point: every
    /// level but the particles'.
    paired: bool,
    /// Per point of this level (particle, or pair of nodes), its aggregate.
    aggregate: Vec<u32>,
    /// Per aggregate, how many points it groups.
    members: Vec<u32>,
    /// Blocks of the smoothed prolongator `P` (rows: this level, columns: the coarser one):
    /// row `i` holds both nodes of the aggregates of `i`'s neighbours.
    prolongation: BlockPattern,
    /// How `(S P)ᵀ t` is summed.
    restriction: Restriction,
    /// Blocks of `A P`.
    product: BlockPattern,
    /// Blocks of the coarser level's matrix `Pᵀ A P`, laid out for a
    /// [`SymmetricBlockMatrix`].
    coarse: BlockPattern,
}

impl Hierarchy {
    /// The levels below `fine`, the finest level's pattern, until [`COARSEST_NODES`]
    /// remain or the grouping stalls: the particles grouped by their neighbourhoods in
    /// `neighbours` (every coupling of the system, those kept beside it too), then the
    /// pairs of nodes of each aggregate by the neighbourhoods of either. The system's wider rows make larger aggregates than
    /// `fine`'s would: grouped by `fine`, hang_64 took 31 iterations a frame against 8.
    /// `system` is the pattern of the systems the levels will be prepared for.
    pub fn build(neighbours: &BlockPattern, fine: &BlockPattern, system: &BlockPattern) -> Self {
        let mut coarsenings: Vec<Coarsening> = Vec::new();
        let mut current = fine.clone();
        while current.rows() > COARSEST_NODES {
            let paired = !coarsenings.is_empty();
            let point = |k: u32| if paired { k / 2 } else { k };
            let (aggregate, count) = if paired {
                aggregate(&BlockPattern::from_rows(current.rows() / 2, |p, row| {
                    row.extend(current.row(2 * p).iter().chain(current.row(2 * p + 1)).map(|&k| point(k)));
                }))
            } else {
                aggregate(neighbours)
            };
            if (2 * count) as f32 > MIN_REDUCTION * current.rows() as f32 {
                break;
            }
            let mut members = vec![0; count];
            for &a in &aggregate {
                members[a as usize] += 1;
            }
            let count = 2 * count;
            let prolongation = BlockPattern::from_rows(current.rows(), |i, row| {
                for &k in current.row(i) {
                    let c = 2 * aggregate[point(k) as usize];
                    row.extend([c, c + 1]);
                }
            });
            let product = BlockPattern::from_rows(current.rows(), |i, row| {
                for &k in current.row(i) {
                    row.extend_from_slice(prolongation.row(k as usize));
                }
            });
            let slot_columns: Vec<[u32; 1]> = prolongation.columns.iter().map(|&c| [c]).collect();
            // `P` by columns: for coarse node `c`, the rows of `P` with a block in column `c`.
            let by_columns = Csr::from_items(count, &slot_columns);
            release(slot_columns);
            let rows_of: Vec<u32> = by_columns.items.iter().map(|&s| prolongation.row_of(s as usize) as u32).collect();
            let coarse = BlockPattern::from_rows(count, |c, row| {
                for &fine in &rows_of[by_columns.range(c)] {
                    row.extend_from_slice(product.row(fine as usize));
                }
            });
            let coarse = coarse.with_upper();
            current = coarse.clone();
            let restriction = Restriction::new(&prolongation, count, by_columns, rows_of);
            coarsenings.push(Coarsening { paired, aggregate, members, prolongation, restriction, product, coarse });
        }
        let same = fine.offsets == system.offsets && fine.columns == system.columns;
        Self { fine: (!same).then(|| fine.clone().with_upper()), coarsest: current.rows(), coarsenings }
    }

    /// Nodes per level, finest first.
    #[cfg(test)]
    fn sizes(&self) -> Vec<usize> {
        let mut sizes: Vec<usize> = self.coarsenings.iter().map(|c| c.prolongation.rows()).collect();
        sizes.push(self.coarsest);
        sizes
    }
}

/// Rows of `P` whose terms of the restriction `(S P)ᵀ t` one task adds up
/// ([`Restriction::ByRows`]).
const RESTRICTION_ROWS: usize = 1024;

/// Levels of at least this many rows restrict by rows ([`Restriction::ByRows`]); smaller
/// ones gather by coarse node, their `P` within the cache.
const RESTRICT_BY_ROWS: usize = 16_384;

/// How the restriction `(S P)ᵀ t` is summed. Gathered by coarse node, each column's
/// blocks are read from rows apart: on the 256² hang scene that took 0.68 ms of a V-cycle,
/// against 0.25 for the prolongation, which reads the same blocks by rows. Summed by rows
/// instead, it took 1 024 rows to a task, each task adding its rows' terms, rows in order,
/// into a buffer of its own over the coarse nodes it reaches (an aggregate's
/// neighbourhood is local, so a short range), and each coarse node then adding up the
/// buffers that reach it, in chunk order, so the sums do not depend on the number of
/// threads: hang_256 87 to 92 ms a frame against 101 to 103 (solving 54 to 61 against
/// 70 to 72). On hang_64 the same took a frame 5 % longer, its `P` in the cache and its
/// small levels paying a second parallel loop, so levels below [`RESTRICT_BY_ROWS`] rows
/// still gather.
#[derive(Debug, Clone, PartialEq)]
enum Restriction {
    /// Per coarse node `c`, the slots of `P` in column `c` (`slots`) and their rows
    /// (`rows`, one per slot), in row order.
    ByColumns { slots: Csr, rows: Vec<u32> },
    /// Per chunk of [`RESTRICTION_ROWS`] rows, the first coarse node it reaches
    /// (`first`) and where its buffer begins (`bounds`, and after the last their total
    /// length); per coarse node, the chunks that reach it, in order (`chunks`).
    ByRows { first: Vec<u32>, bounds: Vec<usize>, chunks: Csr },
}

impl Restriction {
    /// The restriction of `p`, whose columns `count` coarse nodes, given `p`'s slots by
    /// columns and each one's row.
    ///
    /// The lists it does not keep, a slot each of a large `P`, are released
    /// ([`release`]).
    fn new(p: &BlockPattern, count: usize, slots: Csr, rows: Vec<u32>) -> Self {
        match p.rows() < RESTRICT_BY_ROWS {
            true => Self::ByColumns { slots, rows },
            false => {
                slots.release();
                release(rows);
                Self::by_rows(p, count)
            }
        }
    }

    /// The restriction of `p` by chunks of its rows ([`Restriction::ByRows`]).
    fn by_rows(p: &BlockPattern, count: usize) -> Self {
        let (mut first, mut bounds, mut reached) = (Vec::new(), vec![0], Vec::new());
        for start in (0..p.rows()).step_by(RESTRICTION_ROWS) {
            let columns = &p.columns[p.slots_of(start..p.rows().min(start + RESTRICTION_ROWS))];
            let (low, high) = match (columns.iter().min(), columns.iter().max()) {
                (Some(&low), Some(&high)) => (low, high + 1),
                _ => (0, 0),
            };
            first.push(low);
            bounds.push(bounds[reached.len()] + (high - low) as usize);
            reached.push(low..high);
        }
        let mut offsets = Vec::with_capacity(count + 1);
        let mut items = Vec::new();
        offsets.push(0);
        for c in 0..count as u32 {
            items.extend((0..reached.len() as u32).filter(|&k| reached[k as usize].contains(&c)));
            offsets.push(items.len() as u32);
        }
        Self::ByRows { first, bounds, chunks: Csr { offsets, items } }
    }

    /// `out = Pᵀ t`, for `P`'s `blocks` over `p`, with `buffer` for the chunks' sums.
    fn apply<B: StoredBlock>(
        &self,
        p: &BlockPattern,
        blocks: &[B],
        t: &[Vec3],
        buffer: &mut Vec<Vec3>,
        out: &mut [Vec3],
    ) {
        let transposed = |block: &B, v: Vec3| Vec3::from(block.transposed_times(Vec3A::from(v)));
        match self {
            Self::ByColumns { slots, rows } => {
                out.par_iter_mut().with_min_len(PARALLEL_MIN_LEN).enumerate().for_each(|(c, out)| {
                    *out = slots.range(c).fold(Vec3::ZERO, |sum, k| {
                        sum + transposed(&blocks[slots.items[k] as usize], t[rows[k] as usize])
                    });
                });
            }
            Self::ByRows { first, bounds, chunks } => {
                buffer.resize(bounds.last().copied().unwrap_or(0), Vec3::ZERO);
                by_parts(buffer, bounds, |k, _, buffer| {
                    buffer.fill(Vec3::ZERO);
                    let start = k * RESTRICTION_ROWS;
                    for i in start..p.rows().min(start + RESTRICTION_ROWS) {
                        for s in p.slots(i) {
                            buffer[(p.columns[s] - first[k]) as usize] += transposed(&blocks[s], t[i]);
                        }
                    }
                });
                let buffer = &*buffer;
                out.par_iter_mut().with_min_len(PARALLEL_MIN_LEN).enumerate().for_each(|(c, out)| {
                    *out = chunks.row(c).iter().fold(Vec3::ZERO, |sum, &k| {
                        let k = k as usize;
                        sum + buffer[bounds[k] + c - first[k] as usize]
                    });
                });
            }
        }
    }
}

/// Groups nodes into aggregates (Vaněk et al.'s three passes): a node whose neighbours
/// are all ungrouped starts an aggregate of its whole neighbourhood; the rest join the
/// aggregate of a grouped neighbour; what remains groups with its ungrouped neighbours.
/// Returns each node's aggregate and the number of aggregates.
fn aggregate(pattern: &BlockPattern) -> (Vec<u32>, usize) {
    const FREE: u32 = u32::MAX;
    let n = pattern.rows();
    let mut aggregate = vec![FREE; n];
    let mut count = 0u32;
    for i in 0..n {
        if pattern.row(i).iter().all(|&j| aggregate[j as usize] == FREE) {
            for &j in pattern.row(i) {
                aggregate[j as usize] = count;
            }
            count += 1;
        }
    }
    let roots = aggregate.clone();
    for i in 0..n {
        if aggregate[i] == FREE
            && let Some(&j) = pattern.row(i).iter().find(|&&j| roots[j as usize] != FREE)
        {
            aggregate[i] = roots[j as usize];
        }
    }
    for i in 0..n {
        if aggregate[i] == FREE {
            for &j in pattern.row(i) {
                if aggregate[j as usize] == FREE {
                    aggregate[j as usize] = count;
                }
            }
            count += 1;
        }
    }
    (aggregate, count as usize)
}

/// One level's numbers for the current system: its smoother and its prolongator from the
/// next coarser level.
#[derive(Debug, Clone, Default)]
struct Level {
    /// The smoothers' inverse diagonal.
    inverse: Jacobi,
    /// The estimated spectral radius ρ of `D⁻¹ A`.
    radius: f32,
    /// Weight of the prolongator's Jacobi step, `4 / (3 ρ)`.
    weight: f32,
    /// Per Chebyshev step, the weights `(keep, gain)` of its update
    /// `d = keep d + gain D⁻¹ (r − A z)`, `z += d`: a smoothing of degree `k` takes the
    /// first `k`.
    chebyshev: [(f32, f32); HEAP_SMOOTHING_DEGREE],
    /// Per aggregate of the coarsening below, the mean of its points.
    centres: Vec<Vec3>,
    /// Per aggregate, the axes its rotation node turns about, as columns: the principal
    /// axes of its points' spread, a column zeroed where turning about it hardly moves
    /// them (a line of points about itself, a single point).
    frames: Vec<Mat3>,
    /// The filtered, smoothed prolongator `S P` from the next coarser level.
    prolongation: Prolongation,
    /// Estimate of the dominant mode of `D⁻¹ A`, kept for the next system.
    dominant: Vec<Vec3>,
    /// The smoothing's products, then the residual after smoothing.
    scratch: Vec<Vec3>,
    /// The Chebyshev smoother's last update `d`.
    step: Vec<Vec3>,
    /// The coarser level's residual and correction in the V-cycle.
    coarse_residual: Vec<Vec3>,
    coarse_correction: Vec<Vec3>,
    /// The restriction's chunks' sums.
    restricted: Vec<Vec3>,
    /// The products with the level's springs' terms.
    coupled: Coupled,
}

/// Levels of at least this many rows keep their prolongator in bfloat16 ([`HalfBlock`]):
/// the finest prolongator of the 256² hang scene, the levels' largest array, which a
/// V-cycle reads twice. Rounded, a prolongator is another basis of the coarse space, and
/// since the Galerkin product, the restriction and the prolongation all read the rounded
/// one, the V-cycle stays symmetric and positive definite. Rounded, hang_256's finest
/// prolongator took its solves 467 iterations in the first 40 frames against 463, and
/// halved the bytes of the largest array of the levels: with every level's prolongator
/// rounded, its heap peaked at 84.1 MB against 89.1 and its solve took 57.4 and 61.3 ms
/// a frame against 61.4 and 66.4 (whole benches, alternating). A smaller prolongator
/// sits in the cache, where widening its blocks costs more than their bytes save: rounded
/// at every level, hang_64's solve took 2.32 to 2.38 ms a frame against 2.17 to 2.25, and
/// its frame, like hang_128's, 5 % longer.
const HALF_ROWS: usize = 32_768;

/// A prolongator's blocks over its pattern: in `f32`, or in bfloat16 on levels of at
/// least [`HALF_ROWS`] rows.
#[derive(Debug, Clone)]
enum Prolongation {
    Full(Vec<Mat3>),
    Half(Vec<HalfBlock>),
}

impl Default for Prolongation {
    fn default() -> Self {
        Self::Full(Vec::new())
    }
}

impl Prolongation {
    /// How many blocks it holds.
    fn len(&self) -> usize {
        match self {
            Self::Full(blocks) => blocks.len(),
            Self::Half(blocks) => blocks.len(),
        }
    }

    /// Block `s` as stored.
    fn block(&self, s: usize) -> Mat3 {
        match self {
            Self::Full(blocks) => blocks[s],
            Self::Half(blocks) => Mat3::from(blocks[s].get()),
        }
    }

    /// Row `i` of `S P` (over `p`) times the coarse `x`.
    #[inline]
    fn row_product(&self, p: &BlockPattern, i: usize, x: &[Vec3]) -> Vec3 {
        match self {
            Self::Full(blocks) => row_product(blocks, p, i, x),
            Self::Half(blocks) => row_product(blocks, p, i, x),
        }
    }

    /// `out = (S P)ᵀ t` by `restriction`.
    fn restrict(
        &self,
        restriction: &Restriction,
        p: &BlockPattern,
        t: &[Vec3],
        buffer: &mut Vec<Vec3>,
        out: &mut [Vec3],
    ) {
        match self {
            Self::Full(blocks) => restriction.apply(p, blocks, t, buffer, out),
            Self::Half(blocks) => restriction.apply(p, blocks, t, buffer, out),
        }
    }
}

/// The inverse `D⁻¹` of a level's diagonal blocks. On the finest level, per node, the
/// inverse of its filtered diagonal block times the filter, `(S A_ii S + I − S)⁻¹ S`: a
/// Jacobi step that stays within the filter. That is kept times the filter once more,
/// `(S A_ii S + I − S)⁻¹ S S`, the same where the filter is a projection, so that the
/// smoother's residual `S (r − A z)` can go unfiltered: filtered in a pass of its own,
/// or in the smoother's loop, it took hang_64's solve 6 % longer. On a paired level `D`
/// holds each pair's 6 × 6 block, so that an aggregate's translation and rotation, which
/// the stiffness couples, are smoothed together.
#[derive(Debug, Clone, Default)]
struct Jacobi {
    /// Per node, the block of `D⁻¹` that takes its own residual: a diagonal block of the
    /// inverse of a symmetric matrix, so symmetric, and kept by its six entries.
    own: Vec<SymmetricBlock>,
    /// Per node of a paired level, the block that takes its partner's (node `i ^ 1`);
    /// empty on the finest level.
    partner: Vec<Mat3>,
}

impl Jacobi {
    /// Makes the inverse for the matrix of `a`, paired or not.
    fn prepare(&mut self, a: Operator, paired: bool) {
        let n = a.pattern.rows();
        if !paired {
            self.partner.clear();
            (0..n)
                .into_par_iter()
                .with_min_len(PARALLEL_MIN_LEN)
                .map(|i| {
                    let inverse = a.inverse_diagonal(i);
                    SymmetricBlock::new(a.constraint(i).map_or(inverse, |filter| inverse * filter))
                })
                .collect_into_vec(&mut self.own);
            return;
        }
        // Per node, its row of its pair's inverse. A pair's 6 × 6 factor and six solves
        // take some 400 ns, so its loop splits at fewer items than a row's: at
        // PARALLEL_MIN_LEN pairs, hang_64's coarse levels of 169 and 25 pairs ran on one
        // thread, 73 µs a frame against 40.
        self.own.resize(n, SymmetricBlock::default());
        self.partner.resize(n, Mat3::ZERO);
        self.own
            .par_chunks_mut(2)
            .zip(self.partner.par_chunks_mut(2))
            .enumerate()
            .with_min_len(PAIRS_MIN_LEN)
            .for_each(|(p, (own, partner))| {
                let [[tt, tr], [rt, rr]] = pair_inverse(a, p);
                own.copy_from_slice(&[SymmetricBlock::new(tt), SymmetricBlock::new(rr)]);
                partner.copy_from_slice(&[tr, rt]);
            });
    }

    /// `(D⁻¹ v)_i`, `v` given entry by entry.
    #[inline]
    fn apply(&self, i: usize, v: impl Fn(usize) -> Vec3) -> Vec3 {
        let own = self.own[i].times(Vec3A::from(v(i)));
        Vec3::from(self.partner.get(i).map_or(own, |partner| own + times(partner, Vec3A::from(v(i ^ 1)))))
    }
}

/// The inverse of the 6 × 6 diagonal block of pair `p` (nodes `2p`, `2p + 1`) of the
/// matrix of `a`, as 3 × 3 blocks; zero on unknowns the block does not reach.
fn pair_inverse(a: Operator, p: usize) -> [[Mat3; 2]; 2] {
    dense_inverse(pair_block(a, p))
}

/// The 6 × 6 diagonal block of pair `p` of the matrix of `a`, row-major.
fn pair_block(a: Operator, p: usize) -> [f64; 36] {
    let mut block = [0.0; 36];
    for bi in 0..2 {
        for bj in 0..2 {
            set_dense(&mut block, 6, bi, bj, a.block((2 * p + bi) as u32, (2 * p + bj) as u32));
        }
    }
    block
}

/// The generalised inverse of a symmetric positive semi-definite 6 × 6 `block`
/// (row-major) as 3 × 3 blocks: the inverse on the unknowns it reaches, zero on those
/// [`cholesky`] drops.
fn dense_inverse(mut factor: [f64; 36]) -> [[Mat3; 2]; 2] {
    cholesky(&mut factor, 6);
    // The inverse's columns, solved one by one; it is symmetric, so they are its rows too.
    let mut columns = [[0.0; 6]; 6];
    for (k, column) in columns.iter_mut().enumerate() {
        column[k] = 1.0;
        cholesky_solve(&factor, column);
    }
    let block = |bi: usize, bj: usize| {
        let column = |c: usize| {
            let x = &columns[3 * bj + c][3 * bi..3 * bi + 3];
            Vec3::new(x[0] as f32, x[1] as f32, x[2] as f32)
        };
        Mat3::from_cols(column(0), column(1), column(2))
    };
    [[block(0, 0), block(0, 1)], [block(1, 0), block(1, 1)]]
}

/// Writes `block` as block `(i, j)` of the dense `m × m` row-major matrix `f`.
fn set_dense(f: &mut [f64], m: usize, i: usize, j: usize, block: Mat3) {
    for (c, column) in [block.x_axis, block.y_axis, block.z_axis].iter().enumerate() {
        for (r, value) in column.to_array().iter().enumerate() {
            f[(3 * i + r) * m + 3 * j + c] = f64::from(*value);
        }
    }
}

/// Adds `block` to block `(i, j)` of the dense `m × m` matrix `f` ([`set_dense`]).
fn add_dense(f: &mut [f64], m: usize, i: usize, j: usize, block: Mat3) {
    for (c, column) in [block.x_axis, block.y_axis, block.z_axis].iter().enumerate() {
        for (r, value) in column.to_array().iter().enumerate() {
            f[(3 * i + r) * m + 3 * j + c] += f64::from(*value);
        }
    }
}

/// Factors the symmetric `m × m` matrix `f` (row-major) in place into its lower Cholesky
/// factor. An unknown the matrix does not reach (a pinned aggregate, a rotation dropped
/// from a frame, a motion a contact's filter takes out) is dropped: its column is zeroed,
/// and [`cholesky_solve`] gives zero there. It shows as a pivot that falls to round-off of
/// its own diagonal ([`CANCELLED`]). Dropping is safe where keeping is not: the inverse
/// stays positive semi-definite, only weaker on that unknown, while a round-off pivot
/// kept makes it garbage.
fn cholesky(f: &mut [f64], m: usize) {
    for j in 0..m {
        let original = f[j * m + j];
        let pivot = original - (0..j).map(|k| f[j * m + k] * f[j * m + k]).sum::<f64>();
        if pivot <= CANCELLED * original.abs() || pivot <= 0.0 {
            for i in j..m {
                f[i * m + j] = 0.0;
            }
            continue;
        }
        let root = pivot.sqrt();
        f[j * m + j] = root;
        for i in j + 1..m {
            let sum = (0..j).map(|k| f[i * m + k] * f[j * m + k]).sum::<f64>();
            f[i * m + j] = (f[i * m + j] - sum) / root;
        }
    }
}

/// `y = L⁻ᵀ L⁻¹ y` for the factor `L` of [`cholesky`], zero in the dropped unknowns.
fn cholesky_solve(f: &[f64], y: &mut [f64]) {
    let m = y.len();
    for j in 0..m {
        let d = f[j * m + j];
        y[j] = if d > 0.0 { (y[j] - (0..j).map(|k| f[j * m + k] * y[k]).sum::<f64>()) / d } else { 0.0 };
    }
    for j in (0..m).rev() {
        let d = f[j * m + j];
        y[j] = if d > 0.0 { (y[j] - (j + 1..m).map(|k| f[k * m + j] * y[k]).sum::<f64>()) / d } else { 0.0 };
    }
}

/// A pivot below this part of its unknown's diagonal is round-off. The levels' matrices
/// are summed in single precision, and a contact's filter leaves the motions it takes out
/// at its round-off, not at zero: an aggregate held to a plane moves along the normal, and
/// turns out of the plane, by some 10⁻⁸ of its lever, coupled to its real motions by
/// round-off too. On a sheet held to a tilted plane those pivots fell to 2 · 10⁻⁸ to
/// 1.5 · 10⁻⁶ of their diagonals, while real ones (the hang bench scenes, the coarsest
/// levels included) stay above 10⁻²; on sphere_64's ground the turns' diagonals were
/// 10⁻¹⁵ of the translations'. At 10⁻⁹ they were kept, and a pair's inverse was no
/// inverse (`D D⁺ D` missed `D` by 7 times its norm), indefinite in single precision, and
/// the V-cycle with it: sphere_64 with multigrid at its 10 steps a frame ran 210 solves
/// to the iteration cap, 131 708 iterations in all against 23 064 with this bound, none
/// capped.
const CANCELLED: f64 = 1e-4;

/// The numbers of a [`Hierarchy`], made ready for each system by [`Multigrid::prepare`]
/// and applied by [`Multigrid::apply`]; kept from system to system.
#[derive(Debug, Clone, Default)]
pub struct Multigrid {
    /// The finest level's matrix: the system over the hierarchy's finest pattern
    /// ([`lump`]), stored on and above its diagonal as the system is.
    fine: SymmetricBlockMatrix,
    /// The diagonal shift of each block of the system that [`lump`] moves, by storage
    /// slot.
    shifts: Vec<f32>,
    /// Per level that has a coarser one, finest first.
    levels: Vec<Level>,
    /// Matrices of the levels below the finest (whose matrix is `fine`), stored on and
    /// above their diagonals.
    matrices: Vec<SymmetricBlockMatrix>,
    /// Per level below the finest, the contact springs' sum beside its matrix.
    couplings: Vec<CoarseSprings>,
    /// Per particle, the springs' diagonal blocks in the system, which the Galerkin
    /// product leaves out; empty where the cloth does not collide with itself.
    spring_diagonal: Vec<Mat3>,
    /// Scratch of the levels' setup, one level at a time: two chunks of [`PRODUCT_ROWS`]
    /// rows of `A S P` ([`Level::galerkin`]). It held the rotation blocks of the filtered
    /// tentative prolongator `S P₀` too, a block a particle, until they were formed where
    /// they are used ([`Rigid::rotation`]).
    blocks: Vec<Mat3>,
    /// The coarsest level's direct solver.
    coarsest: CoarsestSolver,
    /// Whether the next system rebuilds the coarse levels: none built yet, the last solve
    /// with them took too many iterations, or a run of rebuilds is on.
    rebuild: bool,
    /// Iterations of the first solve after the coarse levels were built; `None` until
    /// that solve reports.
    fresh_iterations: Option<u32>,
    /// Whether a solve after the first has used the current levels.
    tried_stale: bool,
    /// Systems still to rebuild in the run of [`REBUILD_RUN`].
    rebuilds_ahead: u32,
    /// Whether the prolongators were built for the last system: a rebuild for this one
    /// then keeps them (see [`Multigrid::prepare`]).
    prolongators_new: bool,
    /// The smoother's degree for the current system: [`SMOOTHING_DEGREE`], or
    /// [`HEAP_SMOOTHING_DEGREE`] for a heap.
    degree: usize,
}

/// The coarsest level's solver: dense Cholesky, or, where the coarsening stalled above
/// [`DENSE_LIMIT`] nodes (a cloth of many loose pieces), block Jacobi.
#[derive(Debug, Clone, Default)]
struct CoarsestSolver {
    /// Lower Cholesky factor, 3n × 3n, row-major; a zero pivot marks an unknown the coarse
    /// space does not reach, whose solution is zero.
    factor: Vec<f64>,
    /// Right-hand side, then solution.
    unknowns: Vec<f64>,
    /// The inverse diagonal blocks, when the level is too large to factor.
    jacobi: Vec<Mat3>,
}

/// Where a level's points are, for the rigid motions of the aggregates below it: the
/// particles' positions on the finest level; below it, the aggregates' centres and the
/// frames of their rotation nodes.
#[derive(Clone, Copy)]
struct Points<'a> {
    position: &'a [Vec3],
    frame: Option<&'a [Mat3]>,
}

/// The tentative prolongator `P₀` of a coarsening: each aggregate's translation and
/// rotation about its centre, as they move the points of this level.
struct Rigid<'a> {
    coarsening: &'a Coarsening,
    points: Points<'a>,
    centres: &'a [Vec3],
    frames: &'a [Mat3],
}

impl Rigid<'_> {
    /// The point of `node`: the particle itself, or a pair's point below the finest level.
    fn point(&self, node: usize) -> usize {
        if self.coarsening.paired { node / 2 } else { node }
    }

    /// The aggregate of `node`.
    fn aggregate(&self, node: usize) -> u32 {
        self.coarsening.aggregate[self.point(node)]
    }

    /// Block `(node, 2J)` of `S P₀` (`J` its aggregate), the filtered [`Rigid::block`] of
    /// the aggregate's translation: `S` on the finest level, and below it the identity on
    /// a pair's translation node and zero on its rotation node. `None` where it is the
    /// identity (a free particle, a pair's translation node), so that a product with it
    /// can be skipped.
    fn translation(&self, a: Operator, node: usize) -> Option<Mat3> {
        match self.coarsening.paired {
            true => (node % 2 == 1).then_some(Mat3::ZERO),
            false => a.constraint(node),
        }
    }

    /// Block `(node, 2J + 1)` of `P₀`, `J` the node's aggregate: how the aggregate's turn
    /// moves the node. A point `p` of aggregate `J` (centre `c`, frame `B`) moves by
    /// `B a × (p − c)` under `2J + 1`; a rotation
    /// node below the finest level turns by its own frame's share of `B a`.
    #[inline]
    fn turn(&self, node: usize) -> Mat3 {
        let (point, aggregate) = (self.point(node), self.aggregate(node) as usize);
        let frame = self.frames[aggregate];
        match self.coarsening.paired && node % 2 == 1 {
            false => skew(self.centres[aggregate] - self.points.position[point]) * frame,
            true => self.points.frame.map_or(Mat3::ZERO, |own| own[point].transpose() * frame),
        }
    }

    /// Block `(node, 2J + 1)` of `S P₀`: [`Rigid::turn`] filtered, formed wherever the
    /// prolongator's product uses it, some seven times a node. Kept per node instead,
    /// these blocks were 36 bytes a particle, for about 1 ms a frame less of hang_256's
    /// preparation.
    #[inline]
    fn rotation(&self, a: Operator, node: usize) -> Mat3 {
        let turn = self.turn(node);
        a.constraint(node).map_or(turn, |filter| filter * turn)
    }

    /// Block `(node, column)` of `P₀`, `None` where the node is not in the column's
    /// aggregate: under node `2J` a point moves by the aggregate's translation, a rotation
    /// node below the finest level not at all.
    #[cfg(test)]
    fn block(&self, node: usize, column: u32) -> Option<Mat3> {
        if column / 2 != self.aggregate(node) {
            return None;
        }
        Some(match (column % 2 == 1, self.coarsening.paired && node % 2 == 1) {
            (true, _) => self.turn(node),
            (false, false) => Mat3::IDENTITY,
            (false, true) => Mat3::ZERO,
        })
    }
}

/// The eigenvectors (as columns) and eigenvalues of a symmetric matrix, by cyclic Jacobi
/// rotations in double precision.
fn symmetric_eigen(m: Mat3) -> (Mat3, Vec3) {
    let mut a = m.to_cols_array_2d().map(|column| column.map(f64::from));
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..JACOBI_SWEEPS {
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q].abs() <= 1e-15 * (a[p][p].abs() + a[q][q].abs()) {
                continue;
            }
            let theta: f64 = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for row in a.iter_mut().chain(v.iter_mut()) {
                let (kp, kq) = (row[p], row[q]);
                row[p] = c * kp - s * kq;
                row[q] = s * kp + c * kq;
            }
            for k in 0..3 {
                let (pk, qk) = (a[p][k], a[q][k]);
                a[p][k] = c * pk - s * qk;
                a[q][k] = s * pk + c * qk;
            }
        }
    }
    let column = |p: usize| Vec3::new(v[0][p] as f32, v[1][p] as f32, v[2][p] as f32);
    (Mat3::from_cols(column(0), column(1), column(2)), Vec3::new(a[0][0] as f32, a[1][1] as f32, a[2][2] as f32))
}

/// The matrix of one level as the kernels see it: its pattern, its blocks and, on the
/// finest level, the constraint filters.
#[derive(Clone, Copy)]
struct Operator<'a> {
    pattern: &'a BlockPattern,
    /// The level's matrix, stored on and above its diagonal. The finest level's products
    /// are most of a V-cycle's time, and in full its matrix was the largest of the levels.
    /// The coarse levels' Galerkin products, once kept in full for products that gather
    /// over rows, are symmetric too: stored so, the Galerkin product adds only their
    /// upper blocks, and over whole benches alternating hang_64 took 3.88 and 3.91 ms a
    /// frame against 4.03 and 4.07, hang_128 15.2 and 15.7 against 15.9 and 16.1
    /// (hang_256 the same, 86.0 and 90.3 against 86.4 and 90.2), hang_256's heap peaking
    /// at 82.8 MB against 84.1.
    matrix: &'a SymmetricBlockMatrix,
    /// On the finest level of a system with constant couplings beside its pattern, what
    /// they lump onto each diagonal, which the operator adds to the system's own blocks
    /// instead of a lumped copy of them ([`Multigrid::prepare`]).
    lumps: Option<WeightedCouplings<'a>>,
    filter: Option<&'a Filters>,
    /// The contact springs' part beside the matrix, where any spring acts: in the level's
    /// products, and on a coarse level in its diagonal blocks and direct solve; never in
    /// [`Operator::for_row`].
    springs: Option<SpringPart<'a>>,
}

/// The contact springs' part of a level's operator beside its matrix.
#[derive(Clone, Copy)]
enum SpringPart<'a> {
    /// On the finest level, the springs and their weights in the system, whose diagonal
    /// blocks are in the matrix: their couplings. Without them the finest level's
    /// residual is not that of the system its coarse levels hold, and on fold_64 stepped
    /// as sphere_64_adaptive is the solves took 12 533 and 11 892 iterations from two
    /// starts against 9 364 and 8 998 (29 November 2026).
    Couplings(&'a SpringCouplings),
    /// On a coarse level, their terms ([`CoarseSprings`]).
    Terms(&'a CoarseSprings),
}

/// The finest level's operator, within the constraint filter: `fine`, the system lumped
/// over the hierarchy's finest pattern, where that pattern is narrower than the system's
/// and no constant couplings stand beside it; else the `system` itself, with the lumps of
/// its constant couplings, if it has them, on its diagonal.
fn finest_operator<'a>(
    hierarchy: &'a Hierarchy,
    fine: &'a SymmetricBlockMatrix,
    system: StepSystem<'a>,
    filter: &'a Filters,
    springs: Option<&'a SpringCouplings>,
) -> Operator<'a> {
    let springs = acting(springs).map(SpringPart::Couplings);
    match (system.far, &hierarchy.fine) {
        (None, Some(pattern)) => Operator { pattern, matrix: fine, lumps: None, filter: Some(filter), springs },
        (far, _) => {
            Operator { pattern: system.pattern, matrix: system.matrix, lumps: far, filter: Some(filter), springs }
        }
    }
}

/// A coarse level's operator: its Galerkin `matrix` over the `coarse` pattern, which no
/// filter restricts (the finest level's is in the prolongator), and the contact
/// `springs`' terms beside it, if there are any.
fn coarse_operator<'a>(
    coarse: &'a BlockPattern,
    matrix: &'a SymmetricBlockMatrix,
    springs: &'a CoarseSprings,
) -> Operator<'a> {
    let springs = (!springs.is_empty()).then_some(SpringPart::Terms(springs));
    Operator { pattern: coarse, matrix, lumps: None, filter: None, springs }
}

impl Operator<'_> {
    /// The springs' terms of a coarse level.
    fn terms(&self) -> Option<&CoarseSprings> {
        match self.springs {
            Some(SpringPart::Terms(terms)) => Some(terms),
            _ => None,
        }
    }

    /// What the lumps add to node `i`'s diagonal, as a multiple of `I`.
    #[inline]
    fn shift(&self, i: usize) -> f32 {
        self.lumps.map_or(0.0, |far| far.lump(i))
    }

    fn filter(&self, i: usize) -> Mat3 {
        self.filter.map_or(Mat3::IDENTITY, |f| f.block(i))
    }

    /// Node `i`'s filter where it constrains the node, `None` where it is the identity (a
    /// free particle, every node below the finest level), so that a product with it can
    /// be skipped.
    #[inline]
    fn constraint(&self, i: usize) -> Option<Mat3> {
        self.filter.filter(|f| !f.is_free(i)).map(|f| f.block(i))
    }

    /// `S_i v`.
    #[inline]
    fn filtered(&self, i: usize, v: Vec3) -> Vec3 {
        self.filter.map_or(v, |f| f.apply(i, v))
    }

    /// `(S A_ii S + I − S)⁻¹ S` for node `i` (with a one on any empty diagonal entry), zero
    /// where that is singular.
    fn inverse_diagonal(&self, i: usize) -> Mat3 {
        let diagonal = self.diagonal(i);
        self.filter.map_or_else(|| free_inverse(diagonal), |f| f.inverse(i, diagonal))
    }

    /// Node `i`'s diagonal block, the lumps' shift and the springs' terms on it, read
    /// where it is stored.
    fn diagonal(&self, i: usize) -> Mat3 {
        let springs = self.terms().map_or(Mat3::ZERO, |terms| terms.own(i));
        self.matrix.diagonal(self.pattern, i) + Mat3::from_diagonal(Vec3::splat(self.shift(i))) + springs
    }

    /// Block `(row, column)` of the operator, the springs' terms within a pair (rows
    /// `2p`, `2p + 1`) with it, zero where the pattern has none.
    fn block(&self, row: u32, column: u32) -> Mat3 {
        match row == column {
            true => self.diagonal(row as usize),
            false if column == row ^ 1 => {
                let springs = self.terms().map_or(Mat3::ZERO, |terms| terms.partner(row as usize));
                self.matrix.block(self.pattern, row, column) + springs
            }
            false => self.matrix.block(self.pattern, row, column),
        }
    }

    /// Calls `visit(column, block)` for every block of row `i`, columns ascending: the
    /// matrix with its lumps, without the springs' terms.
    #[inline]
    fn for_row(&self, i: usize, mut visit: impl FnMut(u32, Mat3)) {
        self.matrix.for_row(self.pattern, i, |j, block, _| match j as usize == i {
            true => visit(j, block + Mat3::from_diagonal(Vec3::splat(self.shift(i)))),
            false => visit(j, block),
        });
    }

    /// `out = A x`. The cycle's products take the lumps' part row by row in the pass
    /// that finishes them ([`SymmetricBlockMatrix::multiply_then`]).
    #[cfg(test)]
    fn multiply(&self, x: &[Vec3], out: &mut [Vec3]) {
        self.matrix.multiply(self.pattern, x, out);
        if self.lumps.is_some() {
            add_rows(out, |i| self.shift(i) * x[i]);
        }
        let mut coupled = Coupled::default();
        coupled.reset(x.len());
        if let Some(springs) = coupled.form(self, x) {
            add_rows(out, |i| springs[i]);
        }
    }

    /// `out = S (r − A z)`: the product, each stored block read once, and the difference
    /// formed as each run of its rows is whole; the springs' terms, if any, formed first
    /// into `coupled`.
    fn residual(&self, r: &[Vec3], z: &mut [Vec3], out: &mut [Vec3], coupled: &mut Coupled) {
        let springs = coupled.form(self, z);
        self.matrix.multiply_then(self.pattern, z, out, &mut vec![(); r.len()], |first, z, out, _| {
            for (k, (out, z)) in out.iter_mut().zip(z.iter()).enumerate() {
                let i = first + k;
                let springs = springs.map_or(Vec3::ZERO, |s| s[i]);
                *out = self.filtered(i, r[i] - *out - self.shift(i) * *z - springs);
            }
        });
    }
}

/// A level's product with its springs' part ([`SpringPart`]). The product is zero but at the
/// rows the springs reach, which each product sets: a heap's springs reach a few rows.
#[derive(Debug, Clone, Default)]
struct Coupled {
    product: Vec<Vec3>,
    pushes: Vec<Vec3>,
}

impl Coupled {
    /// Zeroes the product for a level of `rows` nodes and new springs.
    fn reset(&mut self, rows: usize) {
        self.product.clear();
        self.product.resize(rows, Vec3::ZERO);
    }

    /// The springs' part of `a` times `x`, if it has one.
    fn form(&mut self, a: &Operator, x: &[Vec3]) -> Option<&[Vec3]> {
        match a.springs? {
            SpringPart::Couplings(couplings) => couplings.set_product(x, &mut self.pushes, &mut self.product),
            SpringPart::Terms(terms) => terms.product(x, &mut self.product),
        }
        Some(&self.product)
    }
}

/// Sets `out` to `system` (over `pattern`) over `fine`, a pattern of fewer blocks: the
/// blocks `fine` has (zero where `pattern` has none), and each block `B` it leaves out
/// moved onto its row's diagonal ([`lumped`]), so that a rigid translation meets the same
/// force as in the system and the coarse levels keep the sheet's soft modes. On the hang
/// bench scenes the bending's couplings across an edge, so moved, cost no iterations
/// (6.9, 7.9 and 13.3 a frame at 64², 128² and 256² against 7.6, 10.3 and 13.7 with the
/// whole system, 30 frames); their Frobenius norms on the diagonal instead doubled them
/// at 256², where the bending outweighs the mass a thousandfold out of the sheet's plane.
///
/// A block and its mirror move the same shift onto their two diagonals, so each stored
/// block's shift is found once, into `shifts` (one per stored block), before the rows are
/// filled. Found for each side, they took `lump` 74 ms over the 120 frames of hang_64;
/// found once, 44 ms, for 4 bytes a stored block (a regular sheet stores 10 a particle).
fn lump(
    pattern: &BlockPattern,
    system: &SymmetricBlockMatrix,
    fine: &BlockPattern,
    shifts: &mut Vec<f32>,
    out: &mut SymmetricBlockMatrix,
) {
    shifts.resize(system.blocks.len(), 0.0);
    pattern.fill_upper_rows(shifts, &|i, row, shifts| {
        let (columns, mut at) = (fine.row(i), 0);
        for ((&column, block), shift) in row.above.iter().zip(&system.blocks[row.storage]).zip(shifts) {
            while at < columns.len() && columns[at] < column {
                at += 1;
            }
            if columns.get(at) != Some(&column) {
                *shift = lumping_shift(symmetric_part(*block), *block);
            }
        }
    });
    let shifts = &*shifts;
    out.reset(fine);
    fine.fill_upper_rows(&mut out.blocks, &|i, row, blocks| {
        // Row `i` of `fine` in full; its blocks from the diagonal on, those stored, begin
        // at `below`.
        let (columns, below, mut at, mut moved) = (fine.row(i), row.below.len(), 0, Mat3::ZERO);
        system.for_row(pattern, i, |column, block, slot| {
            while at < columns.len() && columns[at] < column {
                at += 1;
            }
            match columns.get(at) == Some(&column) {
                true if at >= below => blocks[at - below] = block,
                true => {}
                false => moved += symmetric_part(block) + Mat3::from_diagonal(Vec3::splat(shifts[slot])),
            }
        });
        // The diagonal block is the first stored.
        blocks[0] += moved;
    });
}

/// What [`lump`] moves onto the diagonal, as a multiple of `I` per unit stiffness weight
/// `w`, from a coupling `−w s I` of the system and its mirror: the lumps of
/// [`ConstantCouplings`](super::elements::ConstantCouplings) (a lump is positively
/// homogeneous in its block).
pub(crate) fn scalar_lump(s: f32) -> f32 {
    let block = Mat3::from_diagonal(Vec3::splat(-s));
    block.x_axis.x + lumping_shift(block, block)
}

/// `(B + Bᵀ) / 2`, the same for a block and its transpose.
fn symmetric_part(block: Mat3) -> Mat3 {
    (block + block.transpose()) * 0.5
}

/// What an off-diagonal block `B` (and `Bᵀ`, its mirror) adds to the diagonal of its row
/// when [`lump`] leaves it out: its symmetric part `S` (given), which keeps the row's
/// sum, widened by the returned `c = 2d + ‖W‖` times `I`, `W` its antisymmetric part and
/// `−d` a lower bound on `S`'s eigenvalues where they may be below zero ([`deficit`]).
/// The pair's change `[S + cI, −B; −Bᵀ, S + cI]` is then `[T, −T; −T, T]` with
/// `T = S + dI ⪰ 0`, plus `[(c − d)I, dI − W; dI + W, (c − d)I]`, positive semi-definite
/// for `c ≥ 2d + ‖W‖`: the lumped matrix is never below the system, so positive definite
/// with it, and a V-cycle over it a preconditioner still. `B` and `Bᵀ` give the same
/// shift, to the bit: `W` is formed as `(B − Bᵀ) / 2`, whose entries only change sign.
fn lumping_shift(symmetric: Mat3, block: Mat3) -> f32 {
    2.0 * deficit(symmetric) + frobenius((block - block.transpose()) * 0.5)
}

/// A `d ≥ 0` with `S + d I` positive semi-definite, for a symmetric `S`: the first of
/// [`DEFICIT_STEPS`] times `‖S‖` for which Sylvester's criterion (every principal minor
/// non-negative) holds, else Gershgorin's bound. The bending's blocks are near rank one,
/// `a bᵀ` with `a` and `b` nearly parallel, whose least eigenvalue
/// `(a·b − |a||b|) / 2` is a small part of `‖S‖`, while Gershgorin's bound on it can be
/// a third of `‖S‖`: with that bound alone hang_256 took 28.6 iterations a frame, not
/// 13.3. (Rounding in the minors may pass a shifted block whose least eigenvalue is a
/// rounding error below zero, far below the mass on the diagonal.)
///
/// The four shifts are tried at once, one to a lane of a `Vec4`, each lane with the
/// operations, in their order, of `Mat3::determinant` and of the minors on its own, so
/// the shift found is the one tried one by one would find (the off-diagonal entries are
/// taken as they are, not plus a zero shift, which can change only the sign of a zero,
/// and no comparison with zero sees that). Tried one by one, 1.9 of them
/// a block on average, the criterion was 60 % of [`lump`]'s time, and `lump` 8 % of a
/// hang_64 step: the unpredictable number of tries cost more than the arithmetic.
fn deficit(s: Mat3) -> f32 {
    let norm = frobenius(s);
    let (a, b, c) = (s.x_axis, s.y_axis, s.z_axis);
    let shifts = Vec4::from_array(DEFICIT_STEPS) * norm;
    // The shifted diagonal; the off-diagonal entries are the same in every lane.
    let (ax, by, cz) = (Vec4::splat(a.x) + shifts, Vec4::splat(b.y) + shifts, Vec4::splat(c.z) + shifts);
    // `(S + d I)`'s determinant as `Mat3::determinant` forms it: `a · (b × c)`.
    let cross = [by * cz - c.y * b.z, b.z * c.x - cz * b.x, b.x * c.y - c.x * by];
    let determinant = ax * cross[0] + a.y * cross[1] + a.z * cross[2];
    let zero = Vec4::ZERO;
    let semidefinite = ax.cmpge(zero)
        & by.cmpge(zero)
        & cz.cmpge(zero)
        & (ax * by - Vec4::splat(a.y * a.y)).cmpge(zero)
        & (ax * cz - Vec4::splat(a.z * a.z)).cmpge(zero)
        & (by * cz - Vec4::splat(b.z * b.z)).cmpge(zero)
        & determinant.cmpge(zero);
    match semidefinite.bitmask() {
        0 => {
            let rows = s.transpose();
            let gershgorin = [rows.x_axis, rows.y_axis, rows.z_axis]
                .iter()
                .enumerate()
                .map(|(r, row)| 2.0 * row[r] - row.abs().element_sum())
                .fold(f32::INFINITY, f32::min);
            (-gershgorin).max(0.0)
        }
        lanes => shifts[lanes.trailing_zeros() as usize],
    }
}

/// The shifts, as parts of a block's norm, that [`deficit`] tries, smallest first: on
/// hang_256, 0.01 and 0.1 alone gave 17.5 iterations a frame, these 13.3.
const DEFICIT_STEPS: [f32; 4] = [0.003, 0.01, 0.03, 0.1];

/// The Frobenius norm, which bounds the singular values.
fn frobenius(m: Mat3) -> f32 {
    (m.x_axis.length_squared() + m.y_axis.length_squared() + m.z_axis.length_squared()).sqrt()
}

/// Adds `block` to the block of `row` (sorted columns, with their `blocks`) in `column`,
/// searching forward from `*at`, where the last search of an ascending walk ended.
fn add_at(row: &[u32], blocks: &mut [Mat3], at: &mut usize, column: u32, block: Mat3) {
    while row[*at] != column {
        *at += 1;
    }
    blocks[*at] += block;
}

/// A fixed, irregular block for index `i`, each component in [−0.5, 0.5] (Knuth's
/// multiplicative hash): a vector of these has every direction in it.
fn irregular(i: u32) -> Vec3 {
    let h = i.wrapping_mul(2_654_435_761);
    Vec3::new((h >> 8 & 0xff) as f32, (h >> 16 & 0xff) as f32, (h >> 24) as f32) / 255.0 - 0.5
}

/// Euclidean length of a vector of blocks, summed in order.
fn length(v: &[Vec3]) -> f64 {
    v.iter().map(|x| f64::from(x.length_squared())).sum::<f64>().sqrt()
}

thread_local! {
    /// Per thread, the blocks of the group of a prolongator's rows being formed, in
    /// `f32`, before they are rounded to bfloat16: a group's rows, not the whole
    /// prolongator in `f32` beside its rounding (on the 256² hang scene 8.8 MB, 135 bytes
    /// a particle at the set-up's peak).
    static FORMING: std::cell::RefCell<Vec<Mat3>> = const { std::cell::RefCell::new(Vec::new()) };
}

impl Level {
    /// The smoothers: inverse diagonal blocks, and weights from the spectral radius of
    /// `D⁻¹ A`, estimated by power iterations that start from the last system's dominant
    /// mode (the system changes little from step to step). Gershgorin's bound is no use
    /// here: on a deformed sheet it overestimated the radius twentyfold (59 against about
    /// 3), and the smoothing all but stopped.
    ///
    /// The power iterations approach the radius from below, so the Chebyshev interval's
    /// top is the estimate with a margin ([`CHEBYSHEV_MARGIN`]), beyond which the smoother
    /// would amplify. The prolongator's weight `4 / (3 ρ)` takes the estimate as it is: a
    /// larger weight only makes `P` another basis, never the cycle unstable, and the
    /// margin of 1.1 it had took 4, 6 and 3 % more iterations on the hang bench scenes
    /// (hang_64 1 013 against 971 over 120 frames, hang_128 1 134 against 1 074, hang_256
    /// 745 against 721 over 60); margins of 0.9, 0.8 and 0.7 gave 965, 993 and 1 004 on
    /// hang_64 and 1 071, 1 072 and 1 227 on hang_128.
    fn smoother(&mut self, a: Operator, paired: bool) {
        let n = a.pattern.rows();
        self.inverse.prepare(a, paired);
        if self.dominant.len() != n {
            // A start with every direction in it.
            self.dominant.clear();
            self.dominant.extend((0..n as u32).map(irregular));
            self.radius = 0.0;
        }
        self.scratch.resize(n, Vec3::ZERO);
        // The length of the iterate, which after an iteration is that iteration's estimate.
        let mut norm = length(&self.dominant);
        // The first iteration's estimate settles against the last system's.
        let mut radius = f64::from(self.radius);
        for _ in 0..MAX_POWER_ITERATIONS {
            if norm == 0.0 {
                break;
            }
            // x ← D⁻¹ A x / |x|, each run of rows as soon as its product is whole.
            let inverse = &self.inverse;
            let springs = self.coupled.form(&a, &self.dominant);
            a.matrix.multiply_then(
                a.pattern,
                &mut self.dominant,
                &mut self.scratch,
                &mut vec![(); n],
                |first, x, ax, _| {
                    for (k, (ax, x)) in ax.iter_mut().zip(x.iter()).enumerate() {
                        *ax += a.shift(first + k) * *x + springs.map_or(Vec3::ZERO, |s| s[first + k]);
                    }
                    for (k, x) in x.iter_mut().enumerate() {
                        *x = inverse.apply(first + k, |m| ax[m - first]) / norm as f32;
                    }
                },
            );
            let estimate = length(&self.dominant);
            let settled = (estimate - radius).abs() <= POWER_TOLERANCE * estimate;
            (radius, norm) = (estimate, estimate);
            if settled {
                break;
            }
        }
        let radius = radius as f32;
        self.radius = radius;
        self.weight = if radius > 0.0 { 4.0 / (3.0 * radius) } else { 0.0 };
        self.chebyshev = chebyshev_weights(CHEBYSHEV_MARGIN * radius);
    }

    /// The centres and rotation frames of `coarsening`'s aggregates of `points`.
    fn rigid_motions(&mut self, coarsening: &Coarsening, points: Points) {
        let count = coarsening.members.len();
        self.centres.clear();
        self.centres.resize(count, Vec3::ZERO);
        for (p, &a) in coarsening.aggregate.iter().enumerate() {
            self.centres[a as usize] += points.position[p];
        }
        for (centre, &members) in self.centres.iter_mut().zip(&coarsening.members) {
            *centre /= members as f32;
        }
        // The spread Σ (|r|² I − r rᵀ) is the sum of the rotation columns' Gram matrices
        // (with the points' own rotations below the finest level).
        self.frames.clear();
        self.frames.resize(count, Mat3::ZERO);
        for (p, &a) in coarsening.aggregate.iter().enumerate() {
            let r = points.position[p] - self.centres[a as usize];
            let own = points.frame.map_or(Mat3::ZERO, |frame| frame[p] * frame[p].transpose());
            self.frames[a as usize] += Mat3::from_diagonal(Vec3::splat(r.length_squared())) - outer(r, r) + own;
        }
        for frame in &mut self.frames {
            let (axes, spread) = symmetric_eigen(*frame);
            let kept =
                Vec3::select(spread.cmpge(Vec3::splat(MIN_SPREAD * spread.max_element())), Vec3::ONE, Vec3::ZERO);
            *frame = axes * Mat3::from_diagonal(kept);
        }
    }

    /// The filtered smoothed prolongator `S (I − ω D⁻¹ A) P₀`, `P₀` the aggregates' rigid
    /// motions: block `(i, C)` is `S_i P₀_iC − ω D_i⁻¹ S_i Σ_k A_ik S_k P₀_kC`. The rows of
    /// a pair of nodes share their columns (both nodes of each neighbouring aggregate), and
    /// `D⁻¹` couples them, so a pair's rows are formed together. Row `i` of `A S P₀` is
    /// one walk of `A`'s row: a node `k` reaches the two columns of its own aggregate.
    ///
    /// The blocks of `S P₀` are formed where they are used: its translation blocks are `S`
    /// itself ([`Rigid::translation`]), its rotation blocks a cross-product matrix times the
    /// aggregate's frame ([`Rigid::rotation`]).
    /// On a level of [`HALF_ROWS`] rows or more, each group of rows is formed in `f32`
    /// ([`FORMING`]) and kept rounded to bfloat16.
    fn prolongator(&mut self, a: Operator, coarsening: &Coarsening, points: Points) {
        let Level { inverse, weight, centres, frames, prolongation, .. } = self;
        let (weight, rigid) = (*weight, Rigid { coarsening, points, centres, frames });
        let size = if coarsening.paired { 2 } else { 1 };
        // Node `i`'s blocks of `S P₀` in its aggregate's two columns, its only ones.
        let tentative = |i: usize| [rigid.translation(a, i).unwrap_or(Mat3::IDENTITY), rigid.rotation(a, i)];
        // Row `i` of `A S P₀` into `pushed`, the blocks of `columns`.
        let push = |i: usize, columns: &[u32], pushed: &mut [Mat3]| {
            pushed.fill(Mat3::ZERO);
            a.for_row(i, |node, a_ik| {
                let node = node as usize;
                let translation = 2 * rigid.aggregate(node);
                let Ok(at) = columns.binary_search(&translation) else { return };
                pushed[at] += rigid.translation(a, node).map_or(a_ik, |translation| block_product(&a_ik, &translation));
                pushed[at + 1] += block_product(&a_ik, &rigid.rotation(a, node));
            });
        };
        // The rows of `S P` in a group, given that group's rows of `A S P₀` (`pushed`
        // into them first).
        let form = |first: usize, columns: &[u32], blocks: &mut [Mat3]| {
            for (r, row) in blocks.chunks_mut(columns.len()).enumerate() {
                push(first + r, columns, row);
            }
            for (s, &coarse) in columns.iter().enumerate() {
                let pushed = [blocks[s], blocks.get(columns.len() + s).copied().unwrap_or(Mat3::ZERO)];
                for r in 0..size {
                    let i = first + r;
                    let mut smoothed = block_product(&inverse.own[i].matrix(), &pushed[r]);
                    if let Some(partner) = inverse.partner.get(i) {
                        smoothed += block_product(partner, &pushed[1 - r]);
                    }
                    let own = match coarse / 2 == rigid.aggregate(i) {
                        true => tentative(i)[coarse as usize % 2],
                        false => Mat3::ZERO,
                    };
                    blocks[r * columns.len() + s] = own - weight * smoothed;
                }
            }
        };
        let pattern = &coarsening.prolongation;
        let (rows, count) = (pattern.rows(), pattern.columns.len());
        match (rows >= HALF_ROWS, &mut *prolongation) {
            (true, Prolongation::Half(_)) | (false, Prolongation::Full(_)) => {}
            (true, kept) => *kept = Prolongation::Half(Vec::new()),
            (false, kept) => *kept = Prolongation::Full(Vec::new()),
        }
        match prolongation {
            Prolongation::Full(blocks) => {
                blocks.resize(count, Mat3::ZERO);
                pattern.fill_row_range(size, 0..rows, blocks, &form);
            }
            Prolongation::Half(halves) => {
                halves.resize(count, HalfBlock::default());
                pattern.fill_row_range(size, 0..rows, halves, &|first, columns, halves| {
                    FORMING.with_borrow_mut(|blocks| {
                        blocks.clear();
                        blocks.resize(halves.len(), Mat3::ZERO);
                        form(first, columns, blocks);
                        for (half, block) in halves.iter_mut().zip(blocks.iter()) {
                            *half = HalfBlock::rounded(*block);
                        }
                    });
                });
            }
        }
    }

    /// The coarser level's matrix `(S P)ᵀ A S P`. `A S P` is formed [`PRODUCT_ROWS`] fine
    /// rows at a time, in parallel, row `i` as `Σ_k A_ik (S P)_k` (the rows of `S P` at the
    /// columns of `A`'s row, each added by one forward walk of the result's row), while
    /// the chunk before is added into the coarse matrix: fine row `r` adds
    /// `(S P)_rRᵀ (A S P)_r` to each coarse row `R` of its row of `S P`, rows in order, so
    /// each coarse block sums its terms in fine-row order on any number of threads.
    /// The diagonal blocks `less` (one a node, or none) are left out of `A`.
    fn galerkin(
        &self,
        a: Operator,
        coarsening: &Coarsening,
        less: &[Mat3],
        out: &mut SymmetricBlockMatrix,
        buffer: &mut Vec<Mat3>,
    ) {
        match &self.prolongation {
            Prolongation::Full(blocks) => galerkin_over(a, coarsening, blocks, less, out, buffer),
            Prolongation::Half(blocks) => galerkin_over(a, coarsening, blocks, less, out, buffer),
        }
    }

    /// `degree` Chebyshev steps on `A z = r` with `D⁻¹` as preconditioner;
    /// with `first`, from `z = 0` (whose first step needs no product). Whatever the start,
    /// they multiply the error by the same polynomial in `D⁻¹ A`, so smoothing before and
    /// after the coarse correction keeps the V-cycle symmetric.
    ///
    /// The step takes the residual from the product itself, `r − A z` row by row,
    /// instead of a pass of its own that the step would read back, the filter being in
    /// `D⁻¹` ([`Jacobi`]): one parallel loop and one pass over three vectors fewer a
    /// sweep.
    fn smooth(&mut self, a: Operator, r: &[Vec3], z: &mut [Vec3], first: bool, degree: usize) {
        self.step.resize(z.len(), Vec3::ZERO);
        for (sweep, &(keep, gain)) in self.chebyshev[..degree].iter().enumerate() {
            let start = first && sweep == 0;
            let update = Update { inverse: &self.inverse, first: sweep == 0, start, keep, gain };
            if start {
                update.apply(z, &mut self.step, |i, _| r[i]);
                continue;
            }
            // Each run of rows updated as soon as its product is whole.
            let lumped = a.lumps.is_some();
            let springs = self.coupled.form(&a, z);
            a.matrix.multiply_then(a.pattern, z, &mut self.scratch, &mut self.step, |first, z, az, step| {
                match (lumped, springs) {
                    (true, None) => update.rows(first, z, step, |i, z| r[i] - az[i - first] - a.shift(i) * z),
                    (true, Some(s)) => update.rows(first, z, step, |i, z| r[i] - az[i - first] - a.shift(i) * z - s[i]),
                    (false, Some(s)) => update.rows(first, z, step, |i, _| r[i] - az[i - first] - s[i]),
                    (false, None) => update.rows(first, z, step, |i, _| r[i] - az[i - first]),
                }
            });
        }
    }
}

/// [`Level::galerkin`] over the prolongator's `blocks`.
fn galerkin_over<B: StoredBlock>(
    a: Operator,
    coarsening: &Coarsening,
    prolongation: &[B],
    less: &[Mat3],
    out: &mut SymmetricBlockMatrix,
    buffer: &mut Vec<Mat3>,
) {
    let Coarsening { prolongation: p, product: ap, coarse, .. } = coarsening;
    let rows = ap.rows();
    let chunk_rows = |chunk: usize| chunk * PRODUCT_ROWS..rows.min((chunk + 1) * PRODUCT_ROWS);
    let chunks = rows.div_ceil(PRODUCT_ROWS);
    let half = (0..chunks).map(|c| ap.slots_of(chunk_rows(c)).len()).max().unwrap_or(0);
    let compute = |chunk: usize, blocks: &mut [Mat3]| {
        let rows = chunk_rows(chunk);
        let blocks = &mut blocks[..ap.slots_of(rows.clone()).len()];
        blocks.fill(Mat3::ZERO);
        ap.fill_row_range(1, rows, blocks, &|i, columns, blocks| {
            a.for_row(i, |node, block| {
                let block = match less.get(i) {
                    Some(less) if node as usize == i => block - *less,
                    _ => block,
                };
                let mut at = 0;
                for s in p.slots(node as usize) {
                    add_at(
                        columns,
                        blocks,
                        &mut at,
                        p.columns[s],
                        Mat3::from(Mat3A::from(block) * prolongation[s].get()),
                    );
                }
            });
        });
    };
    out.reset(coarse);
    pipelined(chunks, buffer, half, compute, |chunk, blocks| {
        let rows = chunk_rows(chunk);
        let first = ap.slots_of(rows.clone()).start;
        // Split at the middle fine row's first coarse node: near fine rows restrict to
        // near coarse rows, so the halves share the additions.
        let middle = (rows.start + rows.end) / 2;
        let split = p.row(middle).first().map_or(0, |&node| (node as usize).min(coarse.rows()));
        out.add_by_parts(coarse, &[0, split, coarse.rows()], |_, coarse_rows, coarse_blocks, coarse_first| {
            for r in rows.clone() {
                let slots = ap.slots(r);
                let (products, product_columns) = (&blocks[slots.start - first..slots.end - first], ap.row(r));
                for s in p.slots(r).filter(|&s| coarse_rows.contains(&(p.columns[s] as usize))) {
                    let (row, transposed) = (p.columns[s], Mat3::from(prolongation[s].get().transpose()));
                    let stored = coarse.symmetric_row(row as usize);
                    let row_blocks =
                        &mut coarse_blocks[stored.storage.start - coarse_first..stored.storage.end - coarse_first];
                    // The row's blocks from its diagonal on: those below are mirrors.
                    let from = product_columns.partition_point(|&column| column < row);
                    let mut at = 0;
                    for (&column, product) in product_columns[from..].iter().zip(&products[from..]) {
                        add_at(stored.above, row_blocks, &mut at, column, block_product(&transposed, product));
                    }
                }
            }
        });
    });
}

/// One Chebyshev step's update of the correction `z` and the last update `d`, from the
/// residual.
struct Update<'a> {
    inverse: &'a Jacobi,
    /// Whether this is the first step (no last update to keep).
    first: bool,
    /// Whether `z` starts at zero.
    start: bool,
    keep: f32,
    gain: f32,
}

impl Update<'_> {
    /// `d = keep d + gain D⁻¹ residual`, `z += d`, `residual(i, z_i)` its entry `i`: a
    /// closure of its own for each way the residual is found, so that each loop is
    /// compiled for its own. Only unpaired levels' residuals may read `z_i`.
    fn apply(&self, z: &mut [Vec3], step: &mut [Vec3], residual: impl Fn(usize, Vec3) -> Vec3 + Sync) {
        const C: usize = 2 * PARALLEL_MIN_LEN;
        z.par_chunks_mut(C).zip(step.par_chunks_mut(C)).enumerate().for_each(|(c, (z, step))| {
            self.rows(c * C, z, step, &residual);
        });
    }

    /// [`Update::apply`] on the rows from `first` (even), `z` and `step` theirs.
    #[inline]
    fn rows(&self, first: usize, z: &mut [Vec3], step: &mut [Vec3], residual: impl Fn(usize, Vec3) -> Vec3) {
        let Self { inverse, first: first_step, start, keep, gain } = *self;
        for (k, (z, d)) in z.iter_mut().zip(step.iter_mut()).enumerate() {
            let current = *z;
            let push = gain * inverse.apply(first + k, |i| residual(i, current));
            *d = if first_step { push } else { keep * *d + push };
            *z = if start { *d } else { *z + *d };
        }
    }
}

/// The weights `(keep, gain)` of the Chebyshev steps that damp the eigenvalues of `D⁻¹ A`
/// in `[upper / CHEBYSHEV_RATIO, upper]` (Saad, Iterative Methods, Algorithm 12.1): the
/// first step is `d = D⁻¹ r / θ`, each next `d = ρₖ ρₖ₋₁ d + (2 ρₖ / δ) D⁻¹ r`, with θ
/// and δ the interval's centre and half-width and `ρₖ = 1 / (2 θ/δ − ρₖ₋₁)`, `ρ₀ = δ/θ`.
/// Each step's weights are those of the best polynomial of its degree, whatever the
/// degree the smoothing stops at. All zero (no smoothing) for a zero matrix.
fn chebyshev_weights(upper: f32) -> [(f32, f32); HEAP_SMOOTHING_DEGREE] {
    let mut weights = [(0.0, 0.0); HEAP_SMOOTHING_DEGREE];
    if upper <= 0.0 {
        return weights;
    }
    let lower = upper / CHEBYSHEV_RATIO;
    let (centre, half_width) = ((upper + lower) / 2.0, (upper - lower) / 2.0);
    let sigma = centre / half_width;
    let mut rho = 1.0 / sigma;
    weights[0] = (0.0, 1.0 / centre);
    for weight in &mut weights[1..] {
        let next = 1.0 / (2.0 * sigma - rho);
        *weight = (next * rho, 2.0 * next / half_width);
        rho = next;
    }
    weights
}

impl Multigrid {
    /// Makes the preconditioner ready for `system` (over `pattern`, the finest level of
    /// `hierarchy`) with its unknowns restricted by the per-particle `filter`, the
    /// particles at `positions` (about which the aggregates turn): the finest smoother
    /// always, the prolongators, coarse matrices and coarsest factor only when they are
    /// stale or were built for another hierarchy. Stale coarse levels still give
    /// a symmetric positive definite V-cycle (a Galerkin matrix of an older system is
    /// still positive definite, and the smoother is this system's), only a weaker one,
    /// which [`Multigrid::record`] notices.
    ///
    /// A rebuild right after one keeps the prolongators, one system old, and forms only
    /// the smoothers, Galerkin matrices and coarsest factor: what goes stale in a step is
    /// the Galerkin matrices. In hang_256's runs of rebuilds that saves 5.7 of the 17 ms
    /// every other system, for 1 556 iterations in 120 frames against 1 536.
    ///
    /// The finest level is not the system itself but the system over the hierarchy's
    /// pattern, the couplings of the bending across an edge lumped onto the diagonal
    /// ([`lump`]): a third of the blocks (7 of 19 a row on a regular sheet, 4 of 10
    /// stored), for each of the cycle's smoothing products and for the Galerkin product,
    /// at a frame-sized step where the bending is some 10⁻⁴ of the membrane's stiffness.
    /// Where those couplings are constant and kept beside the system
    /// ([`ConstantCouplings`](super::elements::ConstantCouplings)), its pattern is the
    /// finest level's, and the finest level is the system itself with their lumps, known
    /// ahead, on its diagonal: no copy (144 bytes a particle).
    ///
    /// The contact `springs`, with the weights of their blocks in the system, enter the
    /// coarse levels whole, summed beside their Galerkin matrices ([`CoarseSprings`]),
    /// formed for every system with the coarse smoothers and the coarsest factor. `None`
    /// where the system's cloth does not collide with itself, so that no spring will
    /// come: the levels then keep nothing for them, where otherwise they keep room for
    /// them from the first system on, so that contact starting in a warm frame allocates
    /// nothing.
    ///
    /// With `springs_changed`, the system is the last one prepared for but for its
    /// springs' diagonal blocks (the step's lagged solves, [`contact_springs::lag`]): a
    /// finest level formed by [`lump`] then takes their change on its diagonal instead of
    /// being formed again, which on sphere_64_adaptive took 0.44 ms of a prepare's 0.70.
    ///
    /// [`contact_springs::lag`]: super::contact_springs::lag
    pub fn prepare(
        &mut self,
        hierarchy: &Hierarchy,
        system: StepSystem<'_>,
        filter: &Filters,
        positions: &[Vec3],
        springs: Option<&SpringCouplings>,
        springs_changed: bool,
    ) {
        let had_springs = self.couplings.iter().any(|c| !c.is_empty());
        let couplings = acting(springs);
        let n = system.pattern.rows();
        let acting_springs = couplings.map_or(0, SpringCouplings::len);
        self.degree = if acting_springs * HEAP_SHARE >= n { HEAP_SMOOTHING_DEGREE } else { SMOOTHING_DEGREE };
        let lumped = match (system.far, &hierarchy.fine) {
            (None, Some(fine)) => Some(fine),
            _ => None,
        };
        // The finest level keeps the part of the system that is not the springs' diagonal.
        let kept = springs_changed && self.spring_diagonal.len() == n && !self.fine.blocks.is_empty();
        let fine = lumped.filter(|_| kept);
        if let Some(fine) = fine {
            for (i, block) in self.spring_diagonal.iter().enumerate() {
                *self.fine.diagonal_mut(fine, i) -= *block;
            }
        }
        self.spring_diagonal.clear();
        if let Some(springs) = springs {
            self.spring_diagonal.resize(n, Mat3::ZERO);
            for (i, block) in springs.diagonals() {
                self.spring_diagonal[i] = block;
            }
        }
        match (fine, lumped) {
            (Some(fine), _) => {
                for (i, block) in self.spring_diagonal.iter().enumerate() {
                    *self.fine.diagonal_mut(fine, i) += *block;
                }
            }
            (None, Some(fine)) => lump(system.pattern, system.matrix, fine, &mut self.shifts, &mut self.fine),
            (None, None) => self.fine = SymmetricBlockMatrix::default(),
        }
        let built_for = |levels: &[Level]| {
            levels.len() == hierarchy.coarsenings.len()
                && levels
                    .iter()
                    .zip(&hierarchy.coarsenings)
                    .all(|(level, coarsening)| level.prolongation.len() == coarsening.prolongation.columns.len())
                && levels.first().is_none_or(|level| level.inverse.own.len() == system.pattern.rows())
        };
        let built = built_for(&self.levels);
        match self.levels.first_mut() {
            Some(finest) if built && !self.rebuild => {
                if springs.is_some() {
                    finest.coupled.reset(system.pattern.rows());
                }
                finest.smoother(finest_operator(hierarchy, &self.fine, system, filter, couplings), false);
                self.prolongators_new = false;
                if had_springs || couplings.is_some() {
                    self.follow_springs(hierarchy, springs);
                }
            }
            Some(_) if built && self.prolongators_new => self.setup(hierarchy, system, filter, None, springs),
            // Stale, another hierarchy, or a single level (the system is the coarsest).
            _ => self.setup(hierarchy, system, filter, Some(positions), springs),
        }
        if let (Some(springs), Some(finest)) = (springs, self.levels.first_mut()) {
            springs.reserve(&mut finest.coupled.pushes);
        }
    }

    /// With the coarse levels kept, forms the springs' terms for this system, and with
    /// them the coarse smoothers and the coarsest factor.
    fn follow_springs(&mut self, hierarchy: &Hierarchy, springs: Option<&SpringCouplings>) {
        let depth = hierarchy.coarsenings.len();
        for l in 0..depth {
            let (finer, coarser) = self.couplings.split_at_mut(l);
            let coarsening = &hierarchy.coarsenings[l];
            restrict_springs(coarsening, &self.levels[l].prolongation, finer.last(), springs, &mut coarser[0]);
            let a = coarse_operator(&coarsening.coarse, &self.matrices[l], &self.couplings[l]);
            match self.levels.get_mut(l + 1) {
                Some(level) => {
                    level.coupled.reset(a.pattern.rows());
                    level.smoother(a, hierarchy.coarsenings[l + 1].paired);
                }
                None => self.coarsest.factorize(a),
            }
        }
    }

    /// Takes the iterations the solve preconditioned by the current levels needed, and
    /// marks the coarse levels stale once they need more than [`REBUILD_SLACK`] beyond
    /// what they needed new. If they needed that already in the system after they were
    /// built, levels one system old cost more than building new ones (on the 256² hang
    /// scene 13 iterations with new levels, 45 to 75 with the last step's), so the next
    /// [`REBUILD_RUN`] systems rebuild without trying. At a frame-sized step a swinging
    /// sheet's stiffness changes by more than its aggregates' turning: over hang_64's 120
    /// frames, levels rebuilt every other step took 1 255 iterations against 962 rebuilt
    /// every step, and 1 224 turned by each aggregate's rotation since they were built
    /// (prolongators and coarse matrices, a rotation fitted to each aggregate's points).
    pub fn record(&mut self, iterations: u32) {
        let Some(fresh) = self.fresh_iterations else {
            self.fresh_iterations = Some(iterations);
            self.rebuild = self.rebuilds_ahead > 0;
            self.rebuilds_ahead = self.rebuilds_ahead.saturating_sub(1);
            return;
        };
        self.rebuild = iterations > fresh + REBUILD_SLACK;
        if self.rebuild && !self.tried_stale {
            self.rebuilds_ahead = REBUILD_RUN;
        }
        self.tried_stale = true;
    }

    /// Builds the levels' smoothers and matrices, and the coarsest factor, from the finest
    /// level's matrix, and with the particles' `positions` the prolongators first (else
    /// the last ones are kept).
    fn setup(
        &mut self,
        hierarchy: &Hierarchy,
        system: StepSystem<'_>,
        filter: &Filters,
        positions: Option<&[Vec3]>,
        springs: Option<&SpringCouplings>,
    ) {
        self.rebuild = false;
        self.fresh_iterations = None;
        self.tried_stale = false;
        self.prolongators_new = positions.is_some();
        let depth = hierarchy.coarsenings.len();
        self.levels.resize_with(depth, Level::default);
        self.matrices.resize_with(depth, SymmetricBlockMatrix::default);
        self.couplings.resize_with(depth, CoarseSprings::default);
        let finest = finest_operator(hierarchy, &self.fine, system, filter, acting(springs));
        for (l, coarsening) in hierarchy.coarsenings.iter().enumerate() {
            let (above, below) = self.matrices.split_at_mut(l);
            let (finer_springs, springs_below) = self.couplings.split_at_mut(l);
            let a = match l {
                0 => finest,
                _ => coarse_operator(&hierarchy.coarsenings[l - 1].coarse, &above[l - 1], &finer_springs[l - 1]),
            };
            let (finer, level) = self.levels.split_at_mut(l);
            let level = &mut level[0];
            if springs.is_some() {
                level.coupled.reset(a.pattern.rows());
            }
            level.smoother(a, coarsening.paired);
            if let Some(positions) = positions {
                let points = match finer.last() {
                    None => Points { position: positions, frame: None },
                    Some(finer) => Points { position: &finer.centres, frame: Some(&finer.frames) },
                };
                level.rigid_motions(coarsening, points);
                level.prolongator(a, coarsening, points);
            }
            // The springs' diagonal blocks are in the finest level's matrix: left out of
            // the Galerkin product, as the springs are whole in their terms.
            let less = if l == 0 { &self.spring_diagonal[..] } else { &[] };
            level.galerkin(a, coarsening, less, &mut below[0], &mut self.blocks);
            restrict_springs(coarsening, &level.prolongation, finer_springs.last(), springs, &mut springs_below[0]);
            let coarse = coarsening.coarse.rows();
            level.coarse_residual.resize(coarse, Vec3::ZERO);
            level.coarse_correction.resize(coarse, Vec3::ZERO);
        }
        let coarsest = match depth {
            0 => finest,
            _ => coarse_operator(
                &hierarchy.coarsenings[depth - 1].coarse,
                &self.matrices[depth - 1],
                &self.couplings[depth - 1],
            ),
        };
        self.coarsest.factorize(coarsest);
    }

    /// One symmetric V-cycle on the finest level's residual `r` (filtered), giving the
    /// correction `z` (within the filter), for the `system` and contact `springs` it was
    /// prepared for.
    pub fn apply(
        &mut self,
        hierarchy: &Hierarchy,
        system: StepSystem<'_>,
        filter: &Filters,
        r: &[Vec3],
        z: &mut [Vec3],
        springs: Option<&SpringCouplings>,
    ) {
        let finest = finest_operator(hierarchy, &self.fine, system, filter, acting(springs));
        let coarse = Coarse { coarsenings: &hierarchy.coarsenings, matrices: &self.matrices, springs: &self.couplings };
        cycle(&mut self.levels, coarse, &mut self.coarsest, finest, self.degree, r, z);
    }
}

/// The `springs` where any of them acts: those whose couplings the finest level's
/// products take.
fn acting(springs: Option<&SpringCouplings>) -> Option<&SpringCouplings> {
    springs.filter(|springs| !springs.is_empty())
}

/// Sets `out` to the springs' sum on the coarse level of `coarsening`, through the
/// prolongator from it: the `finer` level's sum restricted, or below the finest level the
/// `springs`' terms with their weights, summed; none where the system has no springs to
/// come.
fn restrict_springs(
    coarsening: &Coarsening,
    prolongation: &Prolongation,
    finer: Option<&CoarseSprings>,
    springs: Option<&SpringCouplings>,
    out: &mut CoarseSprings,
) {
    let p = &coarsening.prolongation;
    let row = |i: usize, visit: &mut dyn FnMut(u32, Mat3)| {
        for s in p.slots(i) {
            visit(p.columns[s], prolongation.block(s));
        }
    };
    let nodes = coarsening.coarse.rows();
    match (springs, finer) {
        (None, _) => out.clear_terms(),
        (Some(springs), None) => out.restrict_springs(springs, nodes, row),
        (Some(_), Some(finer)) => out.restrict(finer, nodes, row),
    }
}

/// The V-cycle from the level of `a` down: smooth, restrict the residual, correct from
/// the coarser level, prolongate, smooth again.
fn cycle(
    levels: &mut [Level],
    coarse: Coarse,
    coarsest: &mut CoarsestSolver,
    a: Operator,
    degree: usize,
    r: &[Vec3],
    z: &mut [Vec3],
) {
    let Some((level, deeper)) = levels.split_first_mut() else {
        coarsest.solve(r, z);
        return;
    };
    let coarsening = &coarse.coarsenings[0];
    level.smooth(a, r, z, true, degree);
    a.residual(r, z, &mut level.scratch, &mut level.coupled);
    // r_c = (S P)ᵀ t, with t = S (r − A z).
    let Level { scratch, prolongation, coarse_residual, restricted, .. } = level;
    prolongation.restrict(&coarsening.restriction, &coarsening.prolongation, scratch, restricted, coarse_residual);
    let below = coarse_operator(&coarsening.coarse, &coarse.matrices[0], &coarse.springs[0]);
    cycle(deeper, coarse.deeper(), coarsest, below, degree, &level.coarse_residual, &mut level.coarse_correction);
    // z += S P c, each row of `P c` added as it is formed.
    let (p, prolongation, correction) = (&coarsening.prolongation, &level.prolongation, &level.coarse_correction);
    add_rows(z, |i| a.filtered(i, prolongation.row_product(p, i, correction)));
    level.smooth(a, r, z, false, degree);
}

/// The levels below one of the V-cycle's: their coarsenings, matrices and springs' terms,
/// the first of each the next level's.
#[derive(Clone, Copy)]
struct Coarse<'a> {
    coarsenings: &'a [Coarsening],
    matrices: &'a [SymmetricBlockMatrix],
    springs: &'a [CoarseSprings],
}

impl Coarse<'_> {
    /// Those below the next level.
    fn deeper(self) -> Self {
        Coarse { coarsenings: &self.coarsenings[1..], matrices: &self.matrices[1..], springs: &self.springs[1..] }
    }
}

impl CoarsestSolver {
    /// Factors the (filtered) matrix of `a`. A pivot that falls to round-off of its
    /// diagonal marks an unknown outside the coarse space (a pinned aggregate): its column
    /// is dropped, and its solution is zero.
    fn factorize(&mut self, a: Operator) {
        if a.pattern.rows() > DENSE_LIMIT {
            self.factor.clear();
            (0..a.pattern.rows())
                .into_par_iter()
                .with_min_len(PARALLEL_MIN_LEN)
                .map(|i| a.inverse_diagonal(i))
                .collect_into_vec(&mut self.jacobi);
            return;
        }
        self.jacobi.clear();
        let m = 3 * a.pattern.rows();
        self.factor.clear();
        self.factor.resize(m * m, 0.0);
        self.unknowns.resize(m, 0.0);
        for i in 0..a.pattern.rows() {
            let si = a.filter(i);
            a.for_row(i, |j, a_ij| {
                let j = j as usize;
                let mut block = si * a_ij * a.filter(j);
                if i == j {
                    block += Mat3::IDENTITY - si;
                }
                set_dense(&mut self.factor, m, i, j, block);
            });
        }
        if let Some(terms) = a.terms() {
            terms.for_blocks(|i, j, block| add_dense(&mut self.factor, m, i, j, block));
        }
        cholesky(&mut self.factor, m);
    }

    /// `z = L⁻ᵀ L⁻¹ r`, zero in the dropped unknowns.
    fn solve(&mut self, r: &[Vec3], z: &mut [Vec3]) {
        if !self.jacobi.is_empty() {
            z.par_iter_mut()
                .zip(r)
                .zip(&self.jacobi)
                .with_min_len(PARALLEL_MIN_LEN)
                .for_each(|((z, r), d)| *z = *d * *r);
            return;
        }
        let y = &mut self.unknowns;
        for (i, v) in r.iter().enumerate() {
            y[3 * i..3 * i + 3].copy_from_slice(&v.to_array().map(f64::from));
        }
        cholesky_solve(&self.factor, y);
        for (i, v) in z.iter_mut().enumerate() {
            *v = Vec3::new(y[3 * i] as f32, y[3 * i + 1] as f32, y[3 * i + 2] as f32);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::contact_springs::{ContactSpring, Outside, Stencil, Weights, add_diagonal};

    /// The `springs`' couplings over `n` vertices at `weights`, prepared.
    fn couplings(springs: &[ContactSpring], weights: Weights, n: usize) -> SpringCouplings {
        let mut couplings = SpringCouplings::default();
        couplings.prepare(Some(springs), weights, n);
        couplings
    }
    use crate::solver::elements::ConstantCouplings;

    /// An `n × n` grid of unit spacing, each quad split along one diagonal, as the system
    /// `m I + Σ k d dᵀ` of an implicit step with springs of stiffness `k` along its edges
    /// (`d` the unit edge): stiff along the edges, soft across the sheet, like cloth.
    fn sheet(n: u32, m: f32, k: f32) -> (BlockPattern, SymmetricBlockMatrix) {
        sheet_at(n, m, k, |p| grid_position(n, p))
    }

    /// Particle `p` of an `n × n` grid of unit spacing in the xy plane.
    fn grid_position(n: u32, p: u32) -> Vec3 {
        Vec3::new((p % n) as f32, (p / n) as f32, 0.0)
    }

    /// [`sheet`] with its particles at `position(p)` instead of the grid's.
    fn sheet_at(n: u32, m: f32, k: f32, position: impl Fn(u32) -> Vec3) -> (BlockPattern, SymmetricBlockMatrix) {
        layers_at(1, n, m, k, position)
    }

    /// `layers` unconnected [`sheet`]s, layer `l`'s particles numbered from `l n²`, particle
    /// `p` at `position(p)`.
    fn layers_at(
        layers: u32,
        n: u32,
        m: f32,
        k: f32,
        position: impl Fn(u32) -> Vec3,
    ) -> (BlockPattern, SymmetricBlockMatrix) {
        let mut edges = Vec::new();
        for layer in 0..layers {
            let index = |i: u32, j: u32| layer * n * n + i * n + j;
            for i in 0..n {
                for j in 0..n {
                    if j + 1 < n {
                        edges.push([index(i, j), index(i, j + 1)]);
                    }
                    if i + 1 < n {
                        edges.push([index(i, j), index(i + 1, j)]);
                    }
                    if i + 1 < n && j + 1 < n {
                        edges.push([index(i, j), index(i + 1, j + 1)]);
                    }
                }
            }
        }
        let particles = (layers * n * n) as usize;
        let pattern = BlockPattern::from_stencils(particles, edges.iter().map(|e| &e[..])).with_upper();
        let mut system = SymmetricBlockMatrix::default();
        system.reset(&pattern);
        system.add_diagonal(&pattern, |_| m);
        for e in &edges {
            let d = (position(e[1]) - position(e[0])).normalize();
            let block = k * outer(d, d);
            system.add_local(*e, &pattern.upper_slots::<2, 3>(*e), &[[block, -block], [-block, block]]);
        }
        (pattern, system)
    }

    /// A fixed, irregular vector within `filter`.
    fn probe(filter: &Filters, seed: u32) -> Vec<Vec3> {
        (0..filter.len()).map(|i| filter.apply(i, irregular(i as u32 ^ seed))).collect()
    }

    fn dot(a: &[Vec3], b: &[Vec3]) -> f64 {
        a.iter().zip(b).map(|(a, b)| f64::from(a.dot(*b))).sum()
    }

    #[test]
    fn symmetric_eigen_diagonalises_with_orthonormal_axes() {
        let m = Mat3::from_cols(Vec3::new(4.0, 1.0, -2.0), Vec3::new(1.0, 3.0, 0.5), Vec3::new(-2.0, 0.5, 1.0));
        let (axes, values) = symmetric_eigen(m);
        let back = axes * Mat3::from_diagonal(values) * axes.transpose();
        assert!((back - m).to_cols_array().iter().all(|d| d.abs() < 1e-5), "{back} against {m}");
        let gram = axes.transpose() * axes - Mat3::IDENTITY;
        assert!(gram.to_cols_array().iter().all(|d| d.abs() < 1e-6), "axes not orthonormal: {axes}");
        // Trace and determinant are the sum and product of the eigenvalues.
        assert!((values.element_sum() - 8.0).abs() < 1e-5);
        assert!((values.element_product() - m.determinant()).abs() < 1e-4);
    }

    /// Every level's tentative prolongator carries a rigid motion of the whole sheet,
    /// a translation `t` and a turn `ω` about a point `o`, as the coarser level's
    /// translations `t + ω × (c − o)` and rotations `Bᵀ ω` of each aggregate.
    #[test]
    fn the_coarse_levels_move_the_sheet_rigidly() {
        let n = 32;
        let (pattern, _) = sheet(n, 1.0, 1.0);
        let hierarchy = Hierarchy::build(&pattern, &pattern, &pattern);
        // A sheet bent about one axis, so that no aggregate's points lie on a line.
        let positions: Vec<Vec3> = (0..n * n)
            .map(|p| {
                let (x, y) = ((p % n) as f32, (p / n) as f32);
                Vec3::new(x, y, 0.05 * (x - 16.0).powi(2))
            })
            .collect();
        let (t, omega, o) = (Vec3::new(0.1, -0.2, 0.3), Vec3::new(0.02, -0.01, 0.03), Vec3::new(3.0, 5.0, 1.0));
        let mut points = Points { position: &positions, frame: None };
        let mut levels = vec![Level::default(); hierarchy.coarsenings.len()];
        for (level, coarsening) in levels.iter_mut().zip(&hierarchy.coarsenings) {
            level.rigid_motions(coarsening, points);
            let rigid = Rigid { coarsening, points, centres: &level.centres, frames: &level.frames };
            // The motion at this level's nodes, and from the coarser one's through P₀.
            let exact = |node: usize| match (coarsening.paired, node % 2) {
                (false, _) => t + omega.cross(points.position[node] - o),
                (true, 0) => t + omega.cross(points.position[node / 2] - o),
                (true, _) => points.frame.expect("paired")[node / 2].transpose() * omega,
            };
            let coarse = |column: u32| {
                let aggregate = (column / 2) as usize;
                match column % 2 {
                    0 => t + omega.cross(level.centres[aggregate] - o),
                    _ => level.frames[aggregate].transpose() * omega,
                }
            };
            for node in 0..coarsening.prolongation.rows() {
                let moved = (0..coarsening.coarse.rows() as u32)
                    .filter_map(|c| rigid.block(node, c).map(|block| block * coarse(c)))
                    .fold(Vec3::ZERO, |sum, v| sum + v);
                assert!((moved - exact(node)).length() < 1e-5, "node {node}: {moved} against {}", exact(node));
            }
            points = Points { position: &level.centres, frame: Some(&level.frames) };
        }
    }

    /// A block left out of the finest level, with its mirror, leaves the lumped matrix
    /// above the system: `[L, −B; −Bᵀ, L]` is positive semi-definite, `L` what it adds to
    /// each diagonal; a near-rank-one block (the bending's) adds little beyond its
    /// symmetric part, and a symmetric positive one (nearly) keeps its row's sum, widened
    /// by twice the smallest shift, 2 × 0.003 of its norm on each diagonal entry.
    /// What [`lump`] moves onto the diagonal for block `b`.
    fn lumped(b: Mat3) -> Mat3 {
        let symmetric = symmetric_part(b);
        symmetric + Mat3::from_diagonal(Vec3::splat(lumping_shift(symmetric, b)))
    }

    /// Constant couplings `s I` beside a system over the finest pattern (the quadratic
    /// bending's) lump onto the finest level's diagonal, from their lumps per unit weight,
    /// as the same blocks in a system over the wider pattern do, and the system's product
    /// with their rows is that system's: here a sheet's diagonal edges, of either sign,
    /// beside its horizontal and vertical ones.
    #[test]
    fn constant_couplings_lump_as_their_blocks_do() {
        let (n, weight) = (9u32, 0.37);
        let (pattern, mut whole) = sheet(n, 1.0, 100.0);
        let index = |i: u32, j: u32| i * n + j;
        let mut straight = Vec::new();
        for i in 0..n {
            for j in 0..n {
                straight.extend((j + 1 < n).then_some([index(i, j), index(i, j + 1)]));
                straight.extend((i + 1 < n).then_some([index(i, j), index(i + 1, j)]));
            }
        }
        let fine = BlockPattern::from_stencils((n * n) as usize, straight.iter().map(|e| &e[..])).with_upper();
        // The diagonal edges' blocks become `−weight s I`, `s` irregular and of either
        // sign, kept apart as couplings beside the system over `fine`.
        let mut entries = Vec::new();
        for i in 0..pattern.rows() {
            let row = pattern.symmetric_row(i);
            for (&column, slot) in row.above.iter().zip(row.storage) {
                if column != i as u32 && fine.row(i).binary_search(&column).is_err() {
                    let s = irregular(column + 31 * i as u32).x;
                    whole.blocks[slot] = Mat3::from_diagonal(Vec3::splat(-weight * s));
                    entries.push((i as u32, column, s));
                }
            }
        }
        let mut system = SymmetricBlockMatrix::default();
        system.reset(&fine);
        for i in 0..fine.rows() {
            let row = fine.symmetric_row(i);
            for (&column, slot) in row.above.iter().zip(row.storage) {
                system.blocks[slot] = whole.block(&pattern, i as u32, column);
            }
        }
        let couplings = ConstantCouplings::new(fine.rows(), || entries.iter().copied());
        let split = StepSystem { pattern: &fine, matrix: &system, far: Some(couplings.weighted(-weight)) };
        let hierarchy = Hierarchy::build(&pattern, &fine, &fine);
        let (mut shifts, mut expected, filter) =
            (Vec::new(), SymmetricBlockMatrix::default(), Filters::free(fine.rows()));
        lump(&pattern, &whole, &fine, &mut shifts, &mut expected);
        let unused = SymmetricBlockMatrix::default();
        let finest = finest_operator(&hierarchy, &unused, split, &filter, None);
        let moved = (0..fine.rows()).map(|i| couplings.weighted(-1.0).lump(i).abs()).fold(0.0, f32::max);
        assert!(moved > 0.1, "the diagonal edges move {moved} onto a diagonal");
        for i in 0..fine.rows() {
            finest.for_row(i, |j, block| {
                let lumped = expected.block(&fine, i as u32, j);
                assert!(
                    frobenius(block - lumped) <= 1e-5 * frobenius(lumped),
                    "block ({i}, {j}): {block} against {lumped}"
                );
            });
        }
        let x: Vec<Vec3> = (0..pattern.rows() as u32).map(irregular).collect();
        let (mut exact, mut product, mut lumped) =
            (vec![Vec3::ZERO; x.len()], vec![Vec3::ZERO; x.len()], vec![Vec3::ZERO; x.len()]);
        whole.multiply(&pattern, &x, &mut exact);
        split.multiply(&x, &mut product);
        finest.multiply(&x, &mut lumped);
        let mut expected_lumped = vec![Vec3::ZERO; x.len()];
        expected.multiply(&fine, &x, &mut expected_lumped);
        for i in 0..x.len() {
            assert!((product[i] - exact[i]).length() <= 1e-4, "row {i}: {} against {}", product[i], exact[i]);
            assert!((split.row_product(i, &x) - exact[i]).length() <= 1e-4, "row {i} alone");
            assert!(
                (lumped[i] - expected_lumped[i]).length() <= 1e-4,
                "lumped row {i}: {} against {}",
                lumped[i],
                expected_lumped[i]
            );
        }
    }

    /// The restriction summed by chunks of rows gives the gathered one's sums: over a
    /// 40 × 40 sheet's first coarsening (two chunks of rows), with irregular blocks.
    #[test]
    fn the_restriction_by_rows_sums_as_the_one_by_columns() {
        let (pattern, _) = sheet(40, 1.0, 100.0);
        let hierarchy = Hierarchy::build(&pattern, &pattern, &pattern);
        let coarsening = &hierarchy.coarsenings[0];
        let (p, count) = (&coarsening.prolongation, coarsening.coarse.rows());
        assert!(matches!(coarsening.restriction, Restriction::ByColumns { .. }), "a small level gathers");
        let blocks: Vec<HalfBlock> = (0..p.columns.len() as u32)
            .map(|k| HalfBlock::rounded(Mat3::from_cols(irregular(3 * k), irregular(3 * k + 1), irregular(3 * k + 2))))
            .collect();
        let t: Vec<Vec3> = (0..p.rows() as u32).map(|i| irregular(i ^ 77)).collect();
        let by_rows = Restriction::by_rows(p, count);
        let Restriction::ByRows { bounds, .. } = &by_rows else { panic!("by rows") };
        assert!(bounds.len() > 2, "more than one chunk");
        let (mut buffer, mut gathered, mut summed) = (Vec::new(), vec![Vec3::ZERO; count], vec![Vec3::ZERO; count]);
        coarsening.restriction.apply(p, &blocks, &t, &mut buffer, &mut gathered);
        by_rows.apply(p, &blocks, &t, &mut buffer, &mut summed);
        for (c, (a, b)) in gathered.iter().zip(&summed).enumerate() {
            assert!((*a - *b).length() <= 1e-5 * a.length().max(1.0), "coarse node {c}: {a} against {b}");
        }
        assert!(gathered.iter().any(|r| r.length() > 0.1), "the restriction is not all zero");
    }

    #[test]
    fn a_lumped_block_never_lowers_the_matrix() {
        let block = |seed: u32| Mat3::from_cols(irregular(seed), irregular(seed + 1), irregular(seed + 2));
        let mut worst: f32 = 0.0;
        for seed in 0..2000u32 {
            let b = match seed % 3 {
                0 => block(7 * seed),
                // a bᵀ, a and b within a few degrees, as the bending's couplings.
                1 => {
                    let a = irregular(seed);
                    outer(a, a + 0.05 * a.length() * irregular(seed + 9000).normalize())
                }
                _ => -outer(irregular(seed), irregular(seed)),
            };
            let l = lumped(b);
            assert_eq!(l, l.transpose(), "the diagonal's change is symmetric");
            assert_eq!(l, lumped(b.transpose()), "a block and its mirror move the same");
            for probe in 0..20 {
                let (x, y) = (irregular(3 * probe + seed), irregular(3 * probe + seed + 1));
                let energy = x.dot(l * x) + y.dot(l * y) - 2.0 * x.dot(b * y);
                worst = worst.min(energy / (x.length_squared() + y.length_squared()) / frobenius(b));
            }
            if seed % 3 == 1 {
                let extra = frobenius(l - (b + b.transpose()) * 0.5) / frobenius(b);
                assert!(extra < 0.2, "a near-rank-one block widened by {extra} of its norm");
            }
        }
        assert!(worst > -1e-5, "energy {worst} of a block's norm below zero");
        let a = Vec3::new(0.3, -0.2, 0.9);
        let kept = lumped(outer(a, a));
        assert!(frobenius(kept - outer(a, a)) <= 0.011 * frobenius(outer(a, a)), "{kept}");
    }

    #[test]
    fn a_sheet_coarsens_level_by_level_to_a_few_dozen_nodes() {
        let (pattern, _) = sheet(64, 1.0, 1.0);
        let sizes = Hierarchy::build(&pattern, &pattern, &pattern).sizes();
        assert!(sizes.len() >= 3, "levels {sizes:?}");
        assert!(sizes.windows(2).all(|w| 4 * w[1] <= w[0]), "each level at least 4× coarser: {sizes:?}");
        assert!(sizes.last().is_some_and(|&n| n <= COARSEST_NODES), "coarsest {sizes:?}");
    }

    #[test]
    fn the_v_cycle_is_symmetric_positive_within_the_filter_and_converges_alone() {
        // h²k/m = 10⁴, as cloth at frame-sized steps; two levels below the particles.
        // Measured: 10 cycles take the residual down by 4.5e-5 (0.37 a cycle); with damped
        // Jacobi smoothing by 3.0e-4 (0.44), and with the aggregates' translations alone
        // by 0.0085 (0.62).
        assert_v_cycle_symmetric_positive_and_convergent(48, |hierarchy, _| {
            assert!(hierarchy.sizes().len() >= 3, "levels {:?}", hierarchy.sizes());
        });
    }

    /// A sheet large enough that its finest prolongator is kept in bfloat16
    /// ([`HALF_ROWS`]), the next one in `f32`: the V-cycle that reads the rounded one stays
    /// symmetric, positive and within the filter, and converges alone. Measured: 10 cycles
    /// take the residual down by 4.2e-5 (0.37 a cycle, as on the 48² sheet).
    #[test]
    fn a_rounded_finest_prolongator_keeps_the_v_cycle_symmetric_positive_and_convergent() {
        assert_v_cycle_symmetric_positive_and_convergent(182, |hierarchy, multigrid| {
            let sizes = hierarchy.sizes();
            assert!(sizes[0] >= HALF_ROWS && sizes[1] < HALF_ROWS, "levels {sizes:?}");
            assert!(matches!(multigrid.levels[0].prolongation, Prolongation::Half(_)));
            assert!(matches!(multigrid.levels[1].prolongation, Prolongation::Full(_)));
        });
    }

    /// Prepares the V-cycle of a `side`² sheet at h²k/m = 10⁴, two corners pinned and
    /// particle 1000 held to a plane, lets `check` look at its levels, and asserts that the
    /// cycle is symmetric, positive and within the filter, and that as a stationary
    /// iteration `x += V (b − S A x)` it converges alone: its error propagation has norm
    /// below one, 10 cycles taking the residual down by 2e-4 or more.
    fn assert_v_cycle_symmetric_positive_and_convergent(side: u32, check: impl FnOnce(&Hierarchy, &Multigrid)) {
        let (pattern, system) = sheet(side, 1.0, 1.0e4);
        let hierarchy = Hierarchy::build(&pattern, &pattern, &pattern);
        let n = pattern.rows();
        let mut filter = Filters::free(n);
        filter.pin(0);
        filter.pin(side as usize - 1);
        filter.constrain(1000, Mat3::IDENTITY - outer(Vec3::Y, Vec3::Y));
        let mut multigrid = Multigrid::default();
        let positions: Vec<Vec3> = (0..n as u32).map(|p| grid_position(side, p)).collect();
        multigrid.prepare(&hierarchy, StepSystem::new(&pattern, &system), &filter, &positions, None, false);
        check(&hierarchy, &multigrid);
        let apply = |multigrid: &mut Multigrid, r: &[Vec3]| {
            let mut z = vec![Vec3::ZERO; n];
            multigrid.apply(&hierarchy, StepSystem::new(&pattern, &system), &filter, r, &mut z, None);
            z
        };
        let (r1, r2) = (probe(&filter, 1), probe(&filter, 2));
        let (z1, z2) = (apply(&mut multigrid, &r1), apply(&mut multigrid, &r2));
        let (a, b) = (dot(&z1, &r2), dot(&r1, &z2));
        let scale = (dot(&z1, &r1) * dot(&z2, &r2)).sqrt();
        assert!(dot(&z1, &r1) > 0.0 && dot(&z2, &r2) > 0.0, "not positive");
        assert!((a - b).abs() < 1e-4 * scale, "not symmetric: {a} against {b}");
        assert_eq!(z1[0], Vec3::ZERO, "a pinned particle moved");
        assert!(z1[1000].y.abs() < 1e-6 * z1[1000].length(), "crossed the normal: {}", z1[1000]);
        let b = probe(&filter, 3);
        let mut x = vec![Vec3::ZERO; n];
        let mut residual = b.clone();
        let mut product = vec![Vec3::ZERO; n];
        let start = dot(&b, &b).sqrt();
        for _ in 0..10 {
            let z = apply(&mut multigrid, &residual);
            x.iter_mut().zip(&z).for_each(|(x, z)| *x += *z);
            system.multiply(&pattern, &x, &mut product);
            for i in 0..n {
                residual[i] = filter.apply(i, b[i] - product[i]);
            }
        }
        let end = dot(&residual, &residual).sqrt();
        assert!(end < 2e-4 * start, "10 cycles took the residual from {start} to {end}");
    }

    /// Between a step's lagged solves only the contact springs' diagonal blocks change in
    /// the system. A finest level formed by [`lump`] that takes their change must be the
    /// one formed again for the new system: here a sheet whose diagonal edges are lumped,
    /// its springs first half as many, then others, stiffer.
    #[test]
    fn a_lumped_finest_level_takes_the_change_of_its_springs_as_if_formed_again() {
        let n = 12u32;
        let (pattern, whole) = sheet(n, 1.0, 100.0);
        let straight: Vec<[u32; 2]> = (0..n * n)
            .flat_map(|p| [(p % n + 1 < n).then_some([p, p + 1]), (p / n + 1 < n).then_some([p, p + n])])
            .flatten()
            .collect();
        let fine = BlockPattern::from_stencils((n * n) as usize, straight.iter().map(|e| &e[..])).with_upper();
        let hierarchy = Hierarchy::build(&pattern, &fine, &pattern);
        let rows = pattern.rows();
        let positions: Vec<Vec3> = (0..rows as u32).map(|p| grid_position(n, p)).collect();
        let filter = Filters::free(rows);
        let weights = Weights { stiffness: 0.5, drag: 0.1 };
        let springs = |count: u32, stiffness: f32| -> Vec<ContactSpring> {
            (0..count)
                .map(|k| ContactSpring {
                    stencil: Stencil::point_triangle(
                        k * 3,
                        [rows as u32 - 2 - k * 4, rows as u32 - 1 - k * 4, k + 40],
                        [0.2, 0.5, 0.3],
                    ),
                    normal: Vec3::new(0.2 * k as f32, 1.0, -0.1).normalize(),
                    gap: 0.002,
                    stiffness,
                    friction: 0.3,
                    drag: 20.0,
                    armed: 0.0,
                    outside: Outside::default(),
                })
                .collect()
        };
        let (before, after) = (springs(5, 300.0), springs(10, 800.0));
        let with = |springs: &[ContactSpring]| {
            let mut system = whole.clone();
            add_diagonal(springs, weights, &pattern, &mut system);
            system
        };
        let (system_before, system_after) = (with(&before), with(&after));
        let prepared =
            |multigrid: &mut Multigrid, system: &SymmetricBlockMatrix, springs: &[ContactSpring], changed| {
                let step = StepSystem::new(&pattern, system);
                let springs = couplings(springs, weights, rows);
                multigrid.prepare(&hierarchy, step, &filter, &positions, Some(&springs), changed);
            };
        let (mut followed, mut formed) = (Multigrid::default(), Multigrid::default());
        prepared(&mut followed, &system_before, &before, false);
        let old = followed.fine.clone();
        prepared(&mut followed, &system_after, &after, true);
        prepared(&mut formed, &system_after, &after, false);
        let (mut changed, mut largest) = (0, 0.0f32);
        for i in 0..rows {
            let (got, wanted) = (followed.fine.diagonal(&fine, i), formed.fine.diagonal(&fine, i));
            changed += usize::from(old.diagonal(&fine, i) != wanted);
            largest = largest.max(frobenius(got - wanted) / frobenius(wanted));
        }
        assert!(changed >= 20, "only {changed} diagonal blocks changed with the springs");
        assert!(largest < 1e-6, "a diagonal block {largest} off the one formed again");
        let off_diagonal = |m: &Multigrid| {
            (0..rows)
                .flat_map(|i| fine.symmetric_row(i).storage.skip(1))
                .map(|slot| m.fine.blocks[slot])
                .collect::<Vec<_>>()
        };
        assert_eq!(off_diagonal(&followed), off_diagonal(&formed), "the off-diagonal blocks are the system's");
    }

    #[test]
    fn every_coarse_level_is_the_galerkin_product_of_the_system_with_its_contact_springs() {
        // A 24² sheet folded in thought: springs join vertices of its two halves, far apart
        // in the pattern, as a heap's layers are joined. The first coarse level, its
        // Galerkin matrix with the springs' sum beside it, must be `(S P)ᵀ A (S P)` of the
        // whole system, the springs' couplings in it, not their diagonal blocks alone, and
        // of this system's springs, not those its matrix was formed for; and each level
        // below it the same product of the level above.
        let n_side = 24;
        let (pattern, mut system) = sheet(n_side, 1.0, 1.0e3);
        let hierarchy = Hierarchy::build(&pattern, &pattern, &pattern);
        let n = pattern.rows();
        let springs: Vec<ContactSpring> = (0..40u32)
            .map(|k| {
                let (row, column) = (k % 10, 2 + k / 10 * 4);
                let (p, q) = (row * n_side + column, (n_side - 2 - row) * n_side + column);
                let stencil = match k % 2 {
                    0 => Stencil::point_triangle(p, [q, q + 1, q + n_side], [0.2, 0.5, 0.3]),
                    _ => Stencil::edge_edge([p, p + 1], [q, q + n_side], 0.3, 0.6),
                };
                let normal = Vec3::new(0.1 * k as f32, 1.0, -0.2).normalize();
                ContactSpring {
                    stencil,
                    normal,
                    gap: 0.002,
                    stiffness: 500.0,
                    friction: 0.3,
                    drag: 20.0,
                    armed: 0.0,
                    outside: Outside::default(),
                }
            })
            .collect();
        let weights = Weights { stiffness: 0.5, drag: 0.1 };
        let positions: Vec<Vec3> = (0..n as u32).map(|p| grid_position(n_side, p)).collect();
        let filter = Filters::free(n);
        let mut multigrid = Multigrid::default();
        // Levels built for the last step's springs (half of them) and kept for this one's,
        // as between steps: the coarse levels must follow the springs all the same.
        let (last, mut last_system) = (&springs[..20], system.clone());
        add_diagonal(last, weights, &pattern, &mut last_system);
        let prepare = |multigrid: &mut Multigrid, system, springs, changed| {
            let springs = couplings(springs, weights, n);
            multigrid.prepare(
                &hierarchy,
                StepSystem::new(&pattern, system),
                &filter,
                &positions,
                Some(&springs),
                changed,
            );
        };
        prepare(&mut multigrid, &last_system, last, false);
        add_diagonal(&springs, weights, &pattern, &mut system);
        prepare(&mut multigrid, &system, &springs, true);
        assert!(!multigrid.rebuild, "the levels are kept");
        let (coarsening, level) = (&hierarchy.coarsenings[0], &multigrid.levels[0]);
        let coarse = coarse_operator(&coarsening.coarse, &multigrid.matrices[0], &multigrid.couplings[0]);
        assert!(coarse.springs.is_some());
        let m = coarse.pattern.rows();
        for seed in 0..4 {
            let x: Vec<Vec3> = (0..m as u32).map(|c| irregular(c ^ seed)).collect();
            let fine = prolongated(&level.prolongation, coarsening, n, &x);
            let mut product = vec![Vec3::ZERO; n];
            system.multiply(&pattern, &fine, &mut product);
            // The springs' diagonal blocks alone, before their couplings are added.
            let diagonal_only = product.clone();
            couplings(&springs, weights, n).add_product(&fine, &mut Vec::new(), &mut product);
            let (error, scale) = galerkin_error(coarse, &x, coarsening, &level.prolongation, &product);
            assert!(error < 1e-4 * scale, "coarse product off by {error} of {scale}");
            // Against the springs' diagonal blocks alone, it differs.
            let apart = diagonal_only.iter().zip(&product).map(|(d, p)| (*d - *p).length()).fold(0.0, f32::max);
            assert!(apart > 1e-2 * scale, "the springs' couplings moved the product by only {apart}");
        }
        // The smoother's pair blocks hold the springs' terms, and their inverses are right.
        for p in 0..m / 2 {
            assert_generalised_inverse(&pair_block(coarse, p), &pair_inverse(coarse, p));
        }
        // Each coarser level is the Galerkin product of the one above it, the springs'
        // sum restricted with it.
        let depth = hierarchy.coarsenings.len();
        assert!(depth >= 2, "a second coarse level to restrict the springs' sum to");
        for l in 1..depth {
            let operator = |l: usize| {
                coarse_operator(&hierarchy.coarsenings[l].coarse, &multigrid.matrices[l], &multigrid.couplings[l])
            };
            let (finer, coarse, coarsening) = (operator(l - 1), operator(l), &hierarchy.coarsenings[l]);
            assert!(coarse.springs.is_some(), "level {l} holds the springs");
            let (n, m) = (finer.pattern.rows(), coarse.pattern.rows());
            let x: Vec<Vec3> = (0..m as u32).map(irregular).collect();
            let prolongation = &multigrid.levels[l].prolongation;
            let mut product = vec![Vec3::ZERO; n];
            finer.multiply(&prolongated(prolongation, coarsening, n, &x), &mut product);
            let (error, scale) = galerkin_error(coarse, &x, coarsening, prolongation, &product);
            assert!(error < 1e-4 * scale, "level {l}'s product off by {error} of {scale}");
        }
    }

    /// `S P x` on the `n` nodes of the level above `coarsening`.
    fn prolongated(prolongation: &Prolongation, coarsening: &Coarsening, n: usize, x: &[Vec3]) -> Vec<Vec3> {
        (0..n).map(|i| prolongation.row_product(&coarsening.prolongation, i, x)).collect()
    }

    /// How far `coarse x` is from `(S P)ᵀ product`, the level above's product restricted,
    /// and the largest entry of the latter.
    fn galerkin_error(
        coarse: Operator,
        x: &[Vec3],
        coarsening: &Coarsening,
        prolongation: &Prolongation,
        product: &[Vec3],
    ) -> (f32, f32) {
        let mut expected = vec![Vec3::ZERO; x.len()];
        prolongation.restrict(
            &coarsening.restriction,
            &coarsening.prolongation,
            product,
            &mut Vec::new(),
            &mut expected,
        );
        let mut got = vec![Vec3::ZERO; x.len()];
        coarse.multiply(x, &mut got);
        let error = got.iter().zip(&expected).map(|(g, e)| (*g - *e).length()).fold(0.0, f32::max);
        (error, expected.iter().map(|e| e.length()).fold(0.0, f32::max))
    }

    /// Two 24² sheets 2 mm apart, h²k/m = 10⁴ in their planes, the upper one held off the
    /// lower by a contact spring at each of its vertices (`k h²/m` = 10³ along the normal,
    /// as stiff as at one step a frame) and pressed onto it: the layers must move together
    /// along their normal, which only their mass resists. Conjugate gradients preconditioned
    /// by the V-cycle with the springs whole on its levels solve that in fewer iterations
    /// than with only the springs' diagonal blocks (in the finest
    /// level's matrix), to whose coarse levels moving the layers together is as stiff as
    /// the springs. Measured, smoothing to degree 3 as a heap: 57 against 90 (to degree
    /// 2, 72 against 87), and at degree 2 174 with the springs whole on the coarse levels
    /// alone, where the finest level's residual is not that of the system they
    /// hold. The rest of the work is the finest smoother's: a vertex moving with the
    /// triangle it rests on is as stiff as the spring to its diagonal blocks.
    #[test]
    fn two_layers_pressed_together_converge_with_the_springs_whole_on_the_coarse_levels() {
        let side = 24u32;
        let n = 2 * (side * side) as usize;
        let position = |p: u32| grid_position(side, p % (side * side)) + Vec3::Z * (0.002 * (p / (side * side)) as f32);
        let (pattern, mut system) = layers_at(2, side, 1.0, 1.0e4, position);
        // Each upper vertex against the lower triangle below and beside it.
        let springs: Vec<ContactSpring> = (0..side * side)
            .filter(|p| p % side + 1 < side && p / side + 1 < side)
            .map(|p| ContactSpring {
                stencil: Stencil::point_triangle(side * side + p, [p, p + 1, p + side], [0.6, 0.2, 0.2]),
                normal: Vec3::Z,
                gap: 0.002,
                stiffness: 1.0e3,
                friction: 0.0,
                drag: 0.0,
                armed: 0.0,
                outside: Outside::default(),
            })
            .collect();
        let weights = Weights { stiffness: 1.0, drag: 0.0 };
        add_diagonal(&springs, weights, &pattern, &mut system);
        let hierarchy = Hierarchy::build(&pattern, &pattern, &pattern);
        let positions: Vec<Vec3> = (0..n as u32).map(position).collect();
        let filter = Filters::free(n);
        // The upper layer pressed down.
        let b: Vec<Vec3> = (0..n).map(|i| if i >= n / 2 { -Vec3::Z } else { Vec3::ZERO }).collect();
        let prepared = couplings(&springs, weights, n);
        let multiply = |x: &[Vec3]| {
            let mut product = vec![Vec3::ZERO; n];
            system.multiply(&pattern, x, &mut product);
            prepared.add_product(x, &mut Vec::new(), &mut product);
            product
        };
        // Conjugate gradients preconditioned by the V-cycle, to a relative residual of 10⁻⁶.
        let iterations = |with_springs: Option<&SpringCouplings>, degree: usize| {
            let mut multigrid = Multigrid::default();
            let step = StepSystem::new(&pattern, &system);
            multigrid.prepare(&hierarchy, step, &filter, &positions, with_springs, false);
            multigrid.degree = degree;
            let mut precondition = |r: &[Vec3]| {
                let mut z = vec![Vec3::ZERO; n];
                multigrid.apply(&hierarchy, step, &filter, r, &mut z, with_springs);
                z
            };
            let (mut x, mut r) = (vec![Vec3::ZERO; n], b.clone());
            let mut z = precondition(&r);
            let (mut d, mut rz) = (z.clone(), dot(&r, &z));
            for iteration in 0..500 {
                if dot(&r, &r) <= 1e-12 * dot(&b, &b) {
                    return iteration;
                }
                let q = multiply(&d);
                let step = (rz / dot(&d, &q)) as f32;
                x.iter_mut().zip(&d).for_each(|(x, d)| *x += step * *d);
                r.iter_mut().zip(&q).for_each(|(r, q)| *r -= step * *q);
                z = precondition(&r);
                let next = dot(&r, &z);
                let ratio = (next / rz) as f32;
                rz = next;
                d.iter_mut().zip(&z).for_each(|(d, z)| *d = *z + ratio * *d);
            }
            500
        };
        // Both smoothed as a heap (the layers touch), and the springs whole as their
        // smoothing would be on a free sheet.
        let whole = iterations(Some(&prepared), HEAP_SMOOTHING_DEGREE);
        let diagonal = iterations(None, HEAP_SMOOTHING_DEGREE);
        let free = iterations(Some(&prepared), SMOOTHING_DEGREE);
        assert!(
            10 * whole < 9 * diagonal,
            "{whole} iterations with the springs whole, {diagonal} with their diagonal alone"
        );
        // The third Chebyshev step damps more of the spectrum the coarse levels leave:
        // 57 iterations against 72 (a fourth would take 49).
        assert!(
            10 * whole < 9 * free,
            "{whole} iterations smoothed to degree {HEAP_SMOOTHING_DEGREE}, {free} to {SMOOTHING_DEGREE}"
        );
    }

    #[test]
    fn a_sheet_held_to_a_tilted_plane_keeps_every_smoother_inverse_and_the_v_cycle_positive() {
        // A drape settled on a body: every particle held by a contact's filter to a plane
        // whose normal is no axis, so the aggregates' translations along the normal and
        // their turns out of the plane are filtered to the filter's round-off, not to zero.
        let turned = Mat3::from_euler(glam::EulerRot::XYZ, 0.4, 0.3, 0.2);
        let (normal, position) = (turned * Vec3::Z, |p| turned * grid_position(48, p));
        let (pattern, system) = sheet_at(48, 1.0, 1.0e4, position);
        let hierarchy = Hierarchy::build(&pattern, &pattern, &pattern);
        let n = pattern.rows();
        let mut filter = Filters::free(n);
        for i in 0..n {
            filter.constrain(i, Mat3::IDENTITY - outer(normal, normal));
        }
        let positions: Vec<Vec3> = (0..n as u32).map(position).collect();
        let mut multigrid = Multigrid::default();
        multigrid.prepare(&hierarchy, StepSystem::new(&pattern, &system), &filter, &positions, None, false);
        // Each pair's inverse in the first paired level's smoother.
        let coarse = coarse_operator(&hierarchy.coarsenings[0].coarse, &multigrid.matrices[0], &multigrid.couplings[0]);
        for p in 0..coarse.pattern.rows() / 2 {
            assert_generalised_inverse(&pair_block(coarse, p), &pair_inverse(coarse, p));
        }
        for seed in 0..16 {
            let r = probe(&filter, seed);
            let mut z = vec![Vec3::ZERO; n];
            multigrid.apply(&hierarchy, StepSystem::new(&pattern, &system), &filter, &r, &mut z, None);
            let (rz, rr, zz) = (dot(&r, &z), dot(&r, &r), dot(&z, &z));
            assert!(rz > 0.0, "r·M⁻¹r = {rz} for probe {seed}");
            // Nothing amplified: the cycle is near A⁻¹ ≤ I / m (m = 1).
            assert!(zz.sqrt() <= 2.0 * rr.sqrt(), "|M⁻¹r| = {} for |r| = {}", zz.sqrt(), rr.sqrt());
        }
    }

    #[test]
    fn a_pair_block_with_unreached_turns_gets_a_generalised_inverse() {
        // A pair block of sphere_64's first paired level, its sheet on the ground
        // (normal +y, so the translation's y row is zero): the turns about x and z moved
        // the points by round-off, their diagonal 10⁻¹⁵ of the translations'. Inverted,
        // they gave an inverse 10²³ times the block's norm.
        let rows = [
            [1.615e-2, 0.0, -4.151e-3, 2.250e-10, -4.024e-4, -4.431e-10],
            [0.0; 6],
            [-4.151e-3, 0.0, 1.950e-2, 3.546e-10, 2.793e-4, 4.767e-10],
            [2.250e-10, 0.0, 3.546e-10, 1.236e-17, -1.670e-12, 1.945e-18],
            [-4.024e-4, 0.0, 2.793e-4, -1.670e-12, 2.888e-5, 1.450e-11],
            [-4.431e-10, 0.0, 4.767e-10, 1.945e-18, 1.450e-11, 1.930e-17],
        ];
        let block: [f64; 36] = std::array::from_fn(|k| rows[k / 6][k % 6]);
        assert_generalised_inverse(&block, &dense_inverse(block));
    }

    /// Asserts that `D⁺` is a generalised inverse of `D` (`D D⁺ D = D`) that keeps no
    /// round-off pivot (`D⁺ D D⁺ = D⁺`), to single precision, both 6 × 6 row-major.
    fn assert_generalised_inverse(block: &[f64; 36], pseudo: &[[Mat3; 2]; 2]) {
        let mut inverse = [0.0; 36];
        for bi in 0..2 {
            for bj in 0..2 {
                set_dense(&mut inverse, 6, bi, bj, pseudo[bi][bj]);
            }
        }
        let product = |a: &[f64; 36], b: &[f64; 36]| {
            std::array::from_fn::<f64, 36, _>(|k| (0..6).map(|l| a[k / 6 * 6 + l] * b[l * 6 + k % 6]).sum())
        };
        let norm = |m: &[f64; 36]| m.iter().map(|v| v * v).sum::<f64>().sqrt();
        let error = |a: &[f64; 36], b: &[f64; 36]| norm(&std::array::from_fn(|k| a[k] - b[k])) / norm(b);
        let block_again = error(&product(&product(block, &inverse), block), block);
        let inverse_again = error(&product(&product(&inverse, block), &inverse), &inverse);
        assert!(block_again <= 1e-4, "|D D⁺ D − D| = {block_again:e} |D|");
        assert!(inverse_again <= 1e-4, "|D⁺ D D⁺ − D⁺| = {inverse_again:e} |D⁺|");
    }
}
