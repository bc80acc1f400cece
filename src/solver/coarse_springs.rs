//! The contact springs' couplings on the multigrid's coarse levels.
//!
//! A contact spring couples its pair's four vertices, `(w wᵀ) ⊗ B` for the stencil's
//! weights `w` and the spring's 3 × 3 block `B` (its stiffness along the normal, its
//! friction across it). The finest level's matrix holds the diagonal blocks `w_k² B`, for
//! its smoother, and its products add the couplings; a coarse level needs the couplings
//! too. Where two layers of a heap lie on each other, moving both together along the
//! normal strains no spring, while the diagonal blocks alone make that motion as stiff as
//! the springs, a thousand times the mass at a frame-sized step: coarse levels built from
//! them alone could not correct it.
//!
//! Springs join vertices far apart in the cloth, whose aggregates no coarse pattern
//! joins, so their sum stays beside each coarse level's Galerkin matrix as a sparse
//! matrix of its own over the nodes they reach. On the first coarse level it is the sum
//! of terms `Qᵀ B Q`, one a spring, `Q = Σ_k w_k (S P)_k` the prolongated stencil, a few
//! blocks wide (the rows of the prolongator at the four vertices, weighted); on each
//! coarser one it is the finer level's sum restricted, `Pᵀ M P`, which is the same sum of
//! the springs' terms carried down, in far fewer products where springs crowd. The
//! Galerkin matrices are then formed without the springs' diagonal blocks, so that each
//! level holds `(S P)ᵀ A (S P)` of the whole system. The sums follow the springs: they
//! are formed for every system, while the Galerkin matrices are kept for as long as they
//! serve.

use super::contact_springs::Stencil;
use super::elements::block::{by_parts, by_parts_keeping, cut_parts, times};
use super::gather::{FLOOR, reserve_floored};
use super::spring_couplings::SpringCouplings;
use glam::{Mat3, Vec3, Vec3A};
use rayon::prelude::*;

/// Entries a term is given room for: its nodes on a coarse level, where its four
/// vertices' rows of the prolongator reach a few aggregates each (two nodes an aggregate).
const ENTRIES: usize = 16;

/// The most parts a sum's rows are cut into, each summed on a task of its own.
const MAX_PARTS: usize = 8;

/// The block products a part of a sum takes at least, so that a task outweighs its
/// scheduling: untangle_layers' first coarse level, some 60 000, is summed in eight parts.
const PART_WORK: usize = 4096;

/// The blocks a sum holds from which its product runs its parts in parallel.
const PARALLEL_BLOCKS: usize = 16_384;

/// Springs whose terms one task forms ([`CoarseSprings::restrict_springs`]): each takes
/// four rows of the prolongator and a block product per node it reaches, a microsecond or
/// so, so that a run outweighs its task.
const RUN_SPRINGS: usize = 256;

/// The contact springs' couplings on a coarse level, `Σ Lᵀ R` over terms each a few
/// nodes wide, summed into a sparse matrix over the nodes they reach, with what a
/// smoother and a direct solver need of it.
#[derive(Debug, Clone, Default)]
pub struct CoarseSprings {
    /// Term `t`'s left entries are `offsets[t]..offsets[t + 1]` of `nodes` and `blocks`:
    /// a spring's `Q`, which takes the nodes' unknowns to the pair's relative motion, or a
    /// finer node's row of the prolongator.
    offsets: Vec<u32>,
    /// Per left entry its node, ascending within a term.
    nodes: Vec<u32>,
    blocks: Vec<Mat3>,
    /// Term `t`'s right entries are `right_offsets[t]..right_offsets[t + 1]` of
    /// `right_nodes` and `right_blocks`: a spring's `B Q`, or the finer node's row of the
    /// finer sum times the prolongator, `(M P)_c`.
    right_offsets: Vec<u32>,
    right_nodes: Vec<u32>,
    right_blocks: Vec<Mat3>,
    /// Node `c`'s left entries are `at[at_offsets[c]..at_offsets[c + 1]]` (in term
    /// order), their terms in `term_of`: the rows of the sum, each summed on its own.
    at_offsets: Vec<u32>,
    at: Vec<u32>,
    term_of: Vec<u32>,
    /// The nodes some term reaches, ascending.
    reached: Vec<u32>,
    /// The terms summed, in parts of the reached rows summed in parallel: part `p` holds
    /// the rows `reached[part_rows[p]..part_rows[p + 1]]`, the nodes from `bounds[p]` to
    /// `bounds[p + 1]`. Where springs crowd (two cloths lying on each other, a spring at
    /// every vertex of one), many terms reach the same few coarse nodes: untangle_layers'
    /// first coarse level held 3 941 springs' terms of 15 594 entries over 50 nodes, whose
    /// sum has 548 blocks, and a product term by term cost twice the entries. Single
    /// precision serves: moving two layers together strains no spring, and the product
    /// with the summed blocks rounds that cancellation to the same order, `ε |Q|² |B|`,
    /// as a product term by term, which formed the relative motion `Q x` before the
    /// stiffness took it (double-precision sums were tried: 15 to 20 % slower to form, and
    /// over five starts of sphere_64_adaptive's chaotic settling their iterations spread
    /// as widely).
    parts: Vec<SumPart>,
    part_rows: Vec<usize>,
    bounds: Vec<usize>,
    /// Per node, its diagonal block of the sum and the block with its partner in a pair
    /// (node `c ^ 1`).
    near: Vec<[Mat3; 2]>,
    /// The terms formed in runs, each on a task of its own, then appended in order to the
    /// lists above: the same lists on any number of threads. Formed one after another,
    /// they were most of the multigrid's preparation on a crowded heap.
    runs: Vec<TermRun>,
    /// Scratch, kept so that a step allocates nothing: each node's next place in `at`.
    next: Vec<u32>,
}

impl CoarseSprings {
    /// Whether there are no terms.
    pub fn is_empty(&self) -> bool {
        self.terms() == 0
    }

    fn terms(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Sets the sum of the first coarse level (`nodes` of them) from the acting `springs`
    /// as weighted in the system, given the rows of the finest level's filtered
    /// prolongator `S P`: `row(i, visit)` calls `visit(column, block)` for each block of
    /// row `i`. Runs of [`RUN_SPRINGS`] springs form their terms in parallel.
    pub fn restrict_springs(
        &mut self,
        springs: &SpringCouplings,
        nodes: usize,
        row: impl Fn(usize, &mut dyn FnMut(u32, Mat3)) + Sync,
    ) {
        let count = springs.len();
        let runs = count.div_ceil(RUN_SPRINGS).clamp(1, MAX_PARTS);
        self.form_runs(runs, nodes, |r, run| {
            for (stencil, spring) in springs.springs_in(r * count / runs..(r + 1) * count / runs) {
                run.push_spring(stencil, spring, &row);
            }
        });
        self.index(nodes);
    }

    /// Sets the sum to `finer`'s restricted to the next coarser level (`nodes` of them),
    /// `Pᵀ M P`, given the rows of the prolongator `P` between them, as
    /// [`CoarseSprings::restrict_springs`]: a term for each row `c` the finer sum has, its
    /// row of `P` on the left and `(M P)_c` on the right, the rows of each of the finer
    /// sum's parts in a run of their own.
    pub fn restrict(
        &mut self,
        finer: &CoarseSprings,
        nodes: usize,
        row: impl Fn(usize, &mut dyn FnMut(u32, Mat3)) + Sync,
    ) {
        let runs = finer.bounds.len().saturating_sub(1);
        self.form_runs(runs, nodes, |r, run| {
            for (c, blocks) in finer.part(r) {
                run.push_row(c, blocks, &row);
            }
        });
        self.index(nodes);
    }

    /// Clears the terms, lets `form(r, run)` form the terms of each of `runs` runs over
    /// `nodes` nodes in parallel, and appends them in order of run.
    fn form_runs(&mut self, runs: usize, nodes: usize, form: impl Fn(usize, &mut TermRun) + Sync) {
        self.clear();
        if self.runs.len() < runs {
            self.runs.resize_with(runs, TermRun::default);
        }
        self.runs[..runs].par_iter_mut().enumerate().for_each(|(r, run)| {
            run.clear(nodes);
            form(r, run);
        });
        for run in &self.runs[..runs] {
            let (left, right) = (self.nodes.len() as u32, self.right_nodes.len() as u32);
            self.offsets.extend(run.ends.iter().map(|&(l, _)| left + l));
            self.right_offsets.extend(run.ends.iter().map(|&(_, r)| right + r));
            self.nodes.extend_from_slice(&run.nodes);
            self.blocks.extend_from_slice(&run.blocks);
            self.right_nodes.extend_from_slice(&run.right_nodes);
            self.right_blocks.extend_from_slice(&run.right_blocks);
        }
    }

    /// Leaves no terms (no spring acts).
    pub fn clear_terms(&mut self) {
        self.clear();
        self.index(0);
    }

    /// Removes the terms, keeping their storage, with room for at least [`FLOOR`] terms
    /// of [`ENTRIES`] entries each: contact that starts or grows in a warm frame then
    /// allocates nothing ([`reserve_floored`]).
    fn clear(&mut self) {
        for offsets in [&mut self.offsets, &mut self.right_offsets] {
            offsets.clear();
            offsets.push(0);
            reserve_floored(offsets, FLOOR);
        }
        for nodes in [&mut self.nodes, &mut self.right_nodes] {
            nodes.clear();
            reserve_floored(nodes, FLOOR * ENTRIES);
        }
        self.blocks.clear();
        reserve_floored(&mut self.blocks, FLOOR * ENTRIES);
        self.right_blocks.clear();
        reserve_floored(&mut self.right_blocks, FLOOR * ENTRIES);
    }

    fn entries(&self, t: usize) -> std::ops::Range<usize> {
        self.offsets[t] as usize..self.offsets[t + 1] as usize
    }

    fn right_entries(&self, t: usize) -> std::ops::Range<usize> {
        self.right_offsets[t] as usize..self.right_offsets[t + 1] as usize
    }

    /// Indexes the left entries by node, and sums the terms.
    fn index(&mut self, nodes: usize) {
        self.at_offsets.clear();
        self.at_offsets.resize(nodes + 1, 0);
        for &node in &self.nodes {
            self.at_offsets[node as usize + 1] += 1;
        }
        self.reached.clear();
        reserve_floored(&mut self.reached, self.nodes.capacity());
        for c in 0..nodes {
            if self.at_offsets[c + 1] > 0 {
                self.reached.push(c as u32);
            }
            self.at_offsets[c + 1] += self.at_offsets[c];
        }
        self.next.clear();
        self.next.extend_from_slice(&self.at_offsets[..nodes]);
        self.at.clear();
        reserve_floored(&mut self.at, self.nodes.capacity());
        self.at.resize(self.nodes.len(), 0);
        self.term_of.clear();
        reserve_floored(&mut self.term_of, self.nodes.capacity());
        self.term_of.resize(self.nodes.len(), 0);
        for t in 0..self.terms() {
            for e in self.entries(t) {
                let slot = &mut self.next[self.nodes[e] as usize];
                self.at[*slot as usize] = e as u32;
                self.term_of[*slot as usize] = t as u32;
                *slot += 1;
            }
        }
        self.sum(nodes);
    }

    /// Cuts the reached rows into parts of about equal work (the block products their
    /// rows take), at most [`MAX_PARTS`] and none under [`PART_WORK`] but the only one.
    fn cut(&mut self, nodes: usize) {
        let (mut part_rows, mut bounds) = (std::mem::take(&mut self.part_rows), std::mem::take(&mut self.bounds));
        let work = |k: usize| -> usize {
            let c = self.reached[k] as usize;
            let terms = &self.term_of[self.at_offsets[c] as usize..self.at_offsets[c + 1] as usize];
            terms.iter().map(|&t| self.right_entries(t as usize).len()).sum()
        };
        // Each left entry is at one node: the total is the terms' own, without the index.
        let total: usize = (0..self.terms()).map(|t| self.entries(t).len() * self.right_entries(t).len()).sum();
        cut_parts(&self.reached, nodes, total, PART_WORK, MAX_PARTS, work, &mut part_rows, &mut bounds);
        (self.part_rows, self.bounds) = (part_rows, bounds);
        if self.parts.len() < MAX_PARTS {
            self.parts.resize_with(MAX_PARTS, SumPart::default);
        }
    }

    /// Sums the terms row by row over the nodes they reach, each row's blocks in term
    /// order, and keeps each node's diagonal and partner blocks: the parts in parallel,
    /// the same sums on any number of threads.
    fn sum(&mut self, nodes: usize) {
        self.cut(nodes);
        let parts = self.bounds.len() - 1;
        self.near.clear();
        self.near.resize(nodes, [Mat3::ZERO; 2]);
        let share = self.right_nodes.capacity().div_ceil(parts);
        let (mut near, mut sums) = (std::mem::take(&mut self.near), std::mem::take(&mut self.parts));
        let (terms, reached, part_rows) = (&*self, &self.reached, &self.part_rows);
        by_parts_keeping(&mut near, &mut sums[..parts], &self.bounds, |p, rows, near, part| {
            part.row_offsets.clear();
            part.row_offsets.push(0);
            reserve_floored(&mut part.row_offsets, part_rows[p + 1] - part_rows[p]);
            part.sums.clear();
            reserve_floored(&mut part.sums, share);
            part.slot.clear();
            part.slot.resize(nodes, u32::MAX);
            for &c in &reached[part_rows[p]..part_rows[p + 1]] {
                let c = c as usize;
                let start = part.sums.len();
                for k in terms.at_offsets[c] as usize..terms.at_offsets[c + 1] as usize {
                    let (e, t) = (terms.at[k] as usize, terms.term_of[k] as usize);
                    let left = terms.blocks[e].transpose();
                    for f in terms.right_entries(t) {
                        let block = left * terms.right_blocks[f];
                        accumulate(&mut part.slot, &mut part.sums, terms.right_nodes[f], block);
                    }
                }
                for &(column, block) in &part.sums[start..] {
                    let column = column as usize;
                    part.slot[column] = u32::MAX;
                    if column == c {
                        near[c - rows.start][0] = block;
                    } else if column == c ^ 1 {
                        near[c - rows.start][1] = block;
                    }
                }
                part.row_offsets.push(part.sums.len() as u32);
            }
        });
        (self.near, self.parts) = (near, sums);
    }

    /// Part `p`'s rows, each with its summed blocks: `(row, [(column, block)])`.
    fn part(&self, p: usize) -> impl Iterator<Item = (usize, &[(u32, Mat3)])> {
        let part = &self.parts[p];
        self.reached[self.part_rows[p]..self.part_rows[p + 1]]
            .iter()
            .zip(part.row_offsets.windows(2))
            .map(|(&c, span)| (c as usize, &part.sums[span[0] as usize..span[1] as usize]))
    }

    /// The reached rows, each with its summed blocks: `(row, [(column, block)])`.
    fn rows(&self) -> impl Iterator<Item = (usize, &[(u32, Mat3)])> {
        (0..self.bounds.len().saturating_sub(1)).flat_map(|p| self.part(p))
    }

    /// Node `c`'s diagonal block.
    pub fn own(&self, c: usize) -> Mat3 {
        self.near.get(c).map_or(Mat3::ZERO, |near| near[0])
    }

    /// The block of row `c` in the column of its partner `c ^ 1`.
    pub fn partner(&self, c: usize) -> Mat3 {
        self.near.get(c).map_or(Mat3::ZERO, |near| near[1])
    }

    /// Calls `visit(row, column, block)` for every block of the sum: for a dense matrix.
    pub fn for_blocks(&self, mut visit: impl FnMut(usize, usize, Mat3)) {
        for (row, blocks) in self.rows() {
            for &(column, block) in blocks {
                visit(row, column as usize, block);
            }
        }
    }

    /// Sets the rows the terms reach of `out` to those of the sum times `x`, the parts in
    /// parallel where the sum holds [`PARALLEL_BLOCKS`]. The rows no term reaches are left
    /// as they are (zero, kept so by the caller): a heap's springs reach a few coarse
    /// nodes, and on sphere_64_adaptive at rest (some 16 springs) products over every
    /// node made its median frame 5 to 14 % longer.
    pub fn product(&self, x: &[Vec3], out: &mut [Vec3]) {
        let row = |blocks: &[(u32, Mat3)]| -> Vec3 {
            let sum: Vec3A = blocks.iter().map(|(column, block)| times(block, Vec3A::from(x[*column as usize]))).sum();
            Vec3::from(sum)
        };
        let parts = self.bounds.len().saturating_sub(1);
        let blocks: usize = self.parts[..parts].iter().map(|part| part.sums.len()).sum();
        if blocks < PARALLEL_BLOCKS {
            for (c, blocks) in self.rows() {
                out[c] = row(blocks);
            }
            return;
        }
        by_parts(out, &self.bounds, |p, nodes, out| {
            for (c, blocks) in self.part(p) {
                out[c - nodes.start] = row(blocks);
            }
        });
    }
}

/// Terms formed on a task of their own: their entries as [`CoarseSprings`] keeps them,
/// with ends counted from the run's start, and the scratch that forms them.
#[derive(Debug, Clone, Default)]
struct TermRun {
    /// Per term, the ends of its left and right entries in the run's lists.
    ends: Vec<(u32, u32)>,
    nodes: Vec<u32>,
    blocks: Vec<Mat3>,
    right_nodes: Vec<u32>,
    right_blocks: Vec<Mat3>,
    /// A term's left entries as they are gathered, the row of `P` times the finer sum
    /// being formed, and each node's place in whichever is being gathered (`u32::MAX`
    /// where it has none).
    gathered: Vec<(u32, Mat3)>,
    accumulated: Vec<(u32, Mat3)>,
    slot: Vec<u32>,
}

impl TermRun {
    /// Removes the terms, keeping their storage, with the room [`CoarseSprings::clear`]
    /// makes, for terms over `nodes` nodes.
    fn clear(&mut self, nodes: usize) {
        self.ends.clear();
        reserve_floored(&mut self.ends, FLOOR);
        for nodes in [&mut self.nodes, &mut self.right_nodes] {
            nodes.clear();
            reserve_floored(nodes, FLOOR * ENTRIES);
        }
        for blocks in [&mut self.blocks, &mut self.right_blocks] {
            blocks.clear();
            reserve_floored(blocks, FLOOR * ENTRIES);
        }
        for scratch in [&mut self.gathered, &mut self.accumulated] {
            scratch.clear();
            reserve_floored(scratch, 4 * ENTRIES);
        }
        self.slot.clear();
        self.slot.resize(nodes, u32::MAX);
    }

    /// Appends a spring's term: `Q`, its stencil's rows of the prolongator weighted, on
    /// the left, and `B Q` on the right.
    fn push_spring(&mut self, stencil: &Stencil, spring: Mat3, row: &impl Fn(usize, &mut dyn FnMut(u32, Mat3))) {
        let Self { gathered, slot, .. } = self;
        gathered.clear();
        for (&vertex, &weight) in stencil.vertices.iter().zip(&stencil.weights) {
            row(vertex as usize, &mut |column, block| accumulate(slot, gathered, column, weight * block));
        }
        for e in self.push_left() {
            self.right_nodes.push(self.nodes[e]);
            self.right_blocks.push(spring * self.blocks[e]);
        }
        self.end_term();
    }

    /// Appends the term of the finer sum's row `c`, its `blocks`: the row of `P` on the
    /// left, `(M P)_c` on the right.
    fn push_row(&mut self, c: usize, blocks: &[(u32, Mat3)], row: &impl Fn(usize, &mut dyn FnMut(u32, Mat3))) {
        let Self { gathered, slot, .. } = self;
        gathered.clear();
        row(c, &mut |column, block| accumulate(slot, gathered, column, block));
        self.push_left();
        let Self { accumulated, slot, .. } = self;
        accumulated.clear();
        for &(f, m) in blocks {
            row(f as usize, &mut |column, block| accumulate(slot, accumulated, column, m * block));
        }
        for &(column, block) in &*accumulated {
            slot[column as usize] = u32::MAX;
            self.right_nodes.push(column);
            self.right_blocks.push(block);
        }
        self.end_term();
    }

    /// Appends the gathered left entries of a new term, each node once (their blocks added
    /// by [`accumulate`] in the order given, which left their places in `slot`, here set
    /// back), in ascending order of node, and returns where they lie. Gathered by node
    /// before they are sorted, the entries of a spring's four rows of the prolongator
    /// (some 30) are sorted once each, not moved about as they merge.
    fn push_left(&mut self) -> std::ops::Range<usize> {
        for &(node, _) in &self.gathered {
            self.slot[node as usize] = u32::MAX;
        }
        // Each node once, so no order among equals is left to the sort.
        self.gathered.sort_unstable_by_key(|&(node, _)| node);
        let start = self.nodes.len();
        self.nodes.extend(self.gathered.iter().map(|&(node, _)| node));
        self.blocks.extend(self.gathered.iter().map(|&(_, block)| block));
        start..self.nodes.len()
    }

    /// Ends the term whose entries were appended last.
    fn end_term(&mut self) {
        self.ends.push((self.nodes.len() as u32, self.right_nodes.len() as u32));
    }
}

/// A part of a sum's rows: the rows' blocks, and its scratch.
#[derive(Debug, Clone, Default)]
struct SumPart {
    /// Its `k`th row is `row_offsets[k]..row_offsets[k + 1]` of `sums`, (column, block),
    /// each column once.
    row_offsets: Vec<u32>,
    sums: Vec<(u32, Mat3)>,
    /// Each node's place in the row being summed (`u32::MAX` where the row has none).
    slot: Vec<u32>,
}

/// Adds `block` at `column` to the row being summed into `row`, where `slot` holds each
/// column's place in `row` so far (`u32::MAX` for none): each column once, its blocks
/// added in the order given. The caller sets the slots of the row's columns back to
/// `u32::MAX` when the row is whole.
fn accumulate(slot: &mut [u32], row: &mut Vec<(u32, Mat3)>, column: u32, block: Mat3) {
    match slot[column as usize] {
        u32::MAX => {
            slot[column as usize] = row.len() as u32;
            row.push((column, block));
        }
        at => row[at as usize].1 += block,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::contact_springs::{ContactSpring, Outside, Stencil, Weights};

    /// A block of no structure, from `seed`.
    fn block(seed: u32) -> Mat3 {
        let entry = |k: u32| ((seed.wrapping_mul(2_654_435_761).wrapping_add(k * 40_503) % 1000) as f32) / 500.0 - 1.0;
        Mat3::from_cols_array(&std::array::from_fn(|k| entry(k as u32)))
    }

    #[test]
    fn a_crowded_sum_cut_into_parts_is_the_sum_of_its_terms() {
        // Vertex `i` reaches coarse nodes `2 (i / 3)` and the next, as a vertex reaches its
        // aggregate's translation and rotation; springs join vertices far apart, so that
        // the sum holds many blocks over the nodes and is cut into parts.
        let (vertices, count) = (3_000u32, 2_000u32);
        let nodes = 2 * vertices.div_ceil(3) as usize;
        let row = |i: usize, visit: &mut dyn FnMut(u32, Mat3)| {
            let node = 2 * (i / 3) as u32;
            visit(node, block(i as u32));
            visit(node + 1, block(i as u32 + vertices));
        };
        let springs: Vec<ContactSpring> = (0..count)
            .map(|k| {
                let (p, q) = ((k * 7) % vertices, (k * 1_543 + 1_000) % (vertices - 2));
                let stencil = Stencil::point_triangle(p, [q, q + 1, q + 2], [0.2, 0.5, 0.3]);
                ContactSpring {
                    stencil,
                    normal: Vec3::new(0.3, 1.0, -0.1 * (k % 5) as f32).normalize(),
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
        let mut sum = CoarseSprings::default();
        let mut couplings = SpringCouplings::default();
        couplings.prepare(Some(&springs), weights, vertices as usize);
        sum.restrict_springs(&couplings, nodes, row);
        let parts = sum.bounds.len() - 1;
        let blocks: usize = sum.parts[..parts].iter().map(|part| part.sums.len()).sum();
        assert_eq!(parts, MAX_PARTS, "a crowded sum is cut into every part");
        assert!(blocks >= PARALLEL_BLOCKS, "its product runs in parallel ({blocks} blocks)");
        assert_eq!(sum.rows().count(), sum.reached.len(), "every reached row is in a part");

        // Against the terms `Qᵀ B Q x`, spring by spring, in double precision.
        let x: Vec<Vec3> = (0..nodes as u32).map(|c| block(c).x_axis).collect();
        let mut expected = vec![glam::DVec3::ZERO; nodes];
        for s in &springs {
            let mut q = Vec::new();
            for (&vertex, &weight) in s.stencil.vertices.iter().zip(&s.stencil.weights) {
                row(vertex as usize, &mut |node, block| q.push((node as usize, weight * block)));
            }
            let relative: Vec3 = q.iter().map(|(node, block)| *block * x[*node]).sum();
            let force = s.block(weights) * relative;
            for (node, block) in q {
                expected[node] += block.transpose().mul_vec3(force).as_dvec3();
            }
        }
        let mut out = vec![Vec3::ZERO; nodes];
        sum.product(&x, &mut out);
        let scale = expected.iter().map(|e| e.length()).fold(0.0, f64::max);
        let error = expected.iter().zip(&out).map(|(e, o)| (*e - o.as_dvec3()).length()).fold(0.0, f64::max);
        assert!(error < 1e-5 * scale, "the sum's product off by {error} of {scale}");
        // Each node's diagonal and partner blocks are those of its row.
        for (c, blocks) in sum.rows() {
            let at = |column: usize| blocks.iter().find(|(j, _)| *j as usize == column).map_or(Mat3::ZERO, |b| b.1);
            assert_eq!((sum.own(c), sum.partner(c)), (at(c), at(c ^ 1)), "node {c}");
        }
    }
}
