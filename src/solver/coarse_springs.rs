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

use super::contact_springs::{ContactSpring, Weights};
use super::elements::block::times;
use super::gather::{FLOOR, reserve_floored};
use glam::{Mat3, Vec3, Vec3A};

/// Entries a term is given room for: its nodes on a coarse level, where its four
/// vertices' rows of the prolongator reach a few aggregates each (two nodes an aggregate).
const ENTRIES: usize = 16;

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
    /// The terms summed: the row of `reached[k]` is `row_offsets[k]..row_offsets[k + 1]`
    /// of `sums`, (column, block), each column once. Where springs crowd (two cloths lying
    /// on each other, a spring at every vertex of one), many terms reach the same few
    /// coarse nodes: untangle_layers' first coarse level held 3 941 springs' terms of
    /// 15 594 entries over 50 nodes, whose sum has 548 blocks, and a product term by term
    /// cost twice the entries. Single precision serves: moving two layers together
    /// strains no spring, and the product with the summed blocks rounds that
    /// cancellation to the same order, `ε |Q|² |B|`, as a product term by term, which
    /// formed the relative motion `Q x` before the stiffness took it (double-precision
    /// sums were tried: 15 to 20 % slower to form, and over five starts of
    /// sphere_64_adaptive's chaotic settling their iterations spread as widely).
    row_offsets: Vec<u32>,
    sums: Vec<(u32, Mat3)>,
    /// Per node, its diagonal block of the sum, and the block with its partner in a pair
    /// (node `c ^ 1`).
    own: Vec<Mat3>,
    partner: Vec<Mat3>,
    /// Scratch, kept so that a step allocates nothing: a term's left and right entries as
    /// they are gathered, each node's next place in `at`, and each node's place in the row
    /// being summed (`u32::MAX` where the row has none).
    gathered: Vec<(u32, Mat3)>,
    accumulated: Vec<(u32, Mat3)>,
    next: Vec<u32>,
    slot: Vec<u32>,
}

impl CoarseSprings {
    /// Whether there are no terms.
    pub fn is_empty(&self) -> bool {
        self.terms() == 0
    }

    fn terms(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Sets the sum of the first coarse level (`nodes` of them) from the acting
    /// `springs` as weighted in the system, given the rows of the finest level's filtered
    /// prolongator `S P`: `row(i, visit)` calls `visit(column, block)` for each block of
    /// row `i`.
    pub fn restrict_springs(
        &mut self,
        springs: &[ContactSpring],
        weights: Weights,
        nodes: usize,
        row: impl Fn(usize, &mut dyn FnMut(u32, Mat3)),
    ) {
        self.clear();
        let mut entries = std::mem::take(&mut self.gathered);
        for s in springs.iter().filter(|s| s.acts()) {
            entries.clear();
            for (&vertex, &weight) in s.stencil.vertices.iter().zip(&s.stencil.weights) {
                row(vertex as usize, &mut |column, block| entries.push((column, weight * block)));
            }
            let spring = s.block(weights);
            for e in self.push_left(&mut entries) {
                self.right_nodes.push(self.nodes[e]);
                self.right_blocks.push(spring * self.blocks[e]);
            }
            self.right_offsets.push(self.right_nodes.len() as u32);
        }
        self.gathered = entries;
        self.index(nodes);
    }

    /// Sets the sum to `finer`'s restricted to the next coarser level (`nodes` of them),
    /// `Pᵀ M P`, given the rows of the prolongator `P` between them, as
    /// [`CoarseSprings::restrict_springs`]: a term for each row `c` the finer sum has, its
    /// row of `P` on the left and `(M P)_c` on the right.
    pub fn restrict(&mut self, finer: &CoarseSprings, nodes: usize, row: impl Fn(usize, &mut dyn FnMut(u32, Mat3))) {
        self.clear();
        let (mut entries, mut product) = (std::mem::take(&mut self.gathered), std::mem::take(&mut self.accumulated));
        let mut slot = std::mem::take(&mut self.slot);
        slot.clear();
        slot.resize(nodes, u32::MAX);
        for (c, blocks) in finer.rows() {
            entries.clear();
            row(c, &mut |column, block| entries.push((column, block)));
            self.push_left(&mut entries);
            product.clear();
            for &(f, m) in blocks {
                row(f as usize, &mut |column, block| accumulate(&mut slot, &mut product, column, m * block));
            }
            for &(column, block) in &product {
                slot[column as usize] = u32::MAX;
                self.right_nodes.push(column);
                self.right_blocks.push(block);
            }
            self.right_offsets.push(self.right_nodes.len() as u32);
        }
        (self.gathered, self.accumulated, self.slot) = (entries, product, slot);
        self.index(nodes);
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
        self.gathered.clear();
        reserve_floored(&mut self.gathered, 4 * ENTRIES);
        self.accumulated.clear();
        reserve_floored(&mut self.accumulated, 4 * ENTRIES);
    }

    fn entries(&self, t: usize) -> std::ops::Range<usize> {
        self.offsets[t] as usize..self.offsets[t + 1] as usize
    }

    fn right_entries(&self, t: usize) -> std::ops::Range<usize> {
        self.right_offsets[t] as usize..self.right_offsets[t + 1] as usize
    }

    /// Appends the left entries of a new term, `entries`, whose blocks at the same node
    /// are added (in the order given), and returns where they lie.
    fn push_left(&mut self, entries: &mut [(u32, Mat3)]) -> std::ops::Range<usize> {
        entries.sort_by_key(|&(node, _)| node);
        let start = self.nodes.len();
        for &(node, block) in entries.iter() {
            match self.nodes[start..].last() {
                Some(&last) if last == node => {
                    let at = self.blocks.len() - 1;
                    self.blocks[at] += block;
                }
                _ => {
                    self.nodes.push(node);
                    self.blocks.push(block);
                }
            }
        }
        self.offsets.push(self.nodes.len() as u32);
        start..self.nodes.len()
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

    /// Sums the terms row by row over the nodes they reach, each row's blocks in term
    /// order, and keeps each node's diagonal and partner blocks.
    fn sum(&mut self, nodes: usize) {
        self.row_offsets.clear();
        self.row_offsets.push(0);
        self.sums.clear();
        reserve_floored(&mut self.row_offsets, self.reached.capacity() + 1);
        reserve_floored(&mut self.sums, self.right_nodes.capacity());
        self.slot.clear();
        self.slot.resize(nodes, u32::MAX);
        self.own.clear();
        self.own.resize(nodes, Mat3::ZERO);
        self.partner.clear();
        self.partner.resize(nodes, Mat3::ZERO);
        for &c in &self.reached {
            let c = c as usize;
            let start = self.sums.len();
            for k in self.at_offsets[c] as usize..self.at_offsets[c + 1] as usize {
                let (e, t) = (self.at[k] as usize, self.term_of[k] as usize);
                let left = self.blocks[e].transpose();
                for f in self.right_entries(t) {
                    accumulate(&mut self.slot, &mut self.sums, self.right_nodes[f], left * self.right_blocks[f]);
                }
            }
            for &(column, block) in &self.sums[start..] {
                let column = column as usize;
                self.slot[column] = u32::MAX;
                if column == c {
                    self.own[c] = block;
                } else if column == c ^ 1 {
                    self.partner[c] = block;
                }
            }
            self.row_offsets.push(self.sums.len() as u32);
        }
    }

    /// The reached rows, each with its summed blocks: `(row, [(column, block)])`.
    fn rows(&self) -> impl Iterator<Item = (usize, &[(u32, Mat3)])> {
        self.reached
            .iter()
            .zip(self.row_offsets.windows(2))
            .map(|(&c, span)| (c as usize, &self.sums[span[0] as usize..span[1] as usize]))
    }

    /// Node `c`'s diagonal block.
    pub fn own(&self, c: usize) -> Mat3 {
        self.own.get(c).copied().unwrap_or(Mat3::ZERO)
    }

    /// The block of row `c` in the column of its partner `c ^ 1`.
    pub fn partner(&self, c: usize) -> Mat3 {
        self.partner.get(c).copied().unwrap_or(Mat3::ZERO)
    }

    /// Calls `visit(row, column, block)` for every block of the sum: for a dense matrix.
    pub fn for_blocks(&self, mut visit: impl FnMut(usize, usize, Mat3)) {
        for (row, blocks) in self.rows() {
            for &(column, block) in blocks {
                visit(row, column as usize, block);
            }
        }
    }

    /// Sets the rows the terms reach of `out` to those of the sum times `x`. The rows no
    /// term reaches are left as they are (zero, kept so by the caller): a heap's springs
    /// reach a few coarse nodes, and on sphere_64_adaptive at rest (some 16 springs)
    /// products over every node made its median frame 5 to 14 % longer.
    pub fn product(&self, x: &[Vec3], out: &mut [Vec3]) {
        for (row, blocks) in self.rows() {
            let sum: Vec3A = blocks.iter().map(|(column, block)| times(block, Vec3A::from(x[*column as usize]))).sum();
            out[row] = Vec3::from(sum);
        }
    }
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
