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
//! joins, so they stay beside each coarse level's Galerkin matrix as a sum of terms
//! `Qᵀ B Q`, one a spring, `Q = Σ_k w_k (S P)_k` the prolongated stencil, a few blocks
//! wide: on the first coarse level the rows of the prolongator at the four vertices
//! weighted, on each coarser one the last level's `Q` times that level's prolongator.
//! The Galerkin matrices are then formed without the springs' diagonal blocks, so that
//! each level holds `(S P)ᵀ A (S P)` of the whole system. The terms follow the springs:
//! they are formed for every system, while the Galerkin matrices are kept for as long as
//! they serve.

use super::contact_springs::{ContactSpring, Weights};
use super::elements::block::{times, transposed_times};
use super::gather::{FLOOR, reserve_floored};
use glam::{Mat3, Vec3, Vec3A};

/// Entries a term is given room for: its nodes on a coarse level, where its four
/// vertices' rows of the prolongator reach a few aggregates each (two nodes an aggregate).
const ENTRIES: usize = 16;

/// Per spring of a coarse level, `Qᵀ B Q` over a few nodes, with what a smoother and a
/// direct solver need of them.
#[derive(Debug, Clone, Default)]
pub struct CoarseSprings {
    /// Term `t`'s entries are `offsets[t]..offsets[t + 1]` of `nodes` and `blocks`.
    offsets: Vec<u32>,
    /// Per entry its node, ascending within a term.
    nodes: Vec<u32>,
    /// Per entry its block of `Q`, which takes the node's unknowns to the pair's relative
    /// motion.
    blocks: Vec<Mat3>,
    /// Per term, the spring's block `B`.
    springs: Vec<Mat3>,
    /// Node `c`'s entries are `at[at_offsets[c]..at_offsets[c + 1]]` (in term order),
    /// their terms in `term_of`: the rows of the product, each summed on its own.
    at_offsets: Vec<u32>,
    at: Vec<u32>,
    term_of: Vec<u32>,
    /// The nodes some term reaches, ascending.
    reached: Vec<u32>,
    /// Per node, its diagonal block `Σ Q_cᵀ B Q_c`, and the block with its partner in a
    /// pair (node `c ^ 1`).
    own: Vec<Mat3>,
    partner: Vec<Mat3>,
    /// Scratch, kept so that a step allocates nothing: a term's entries as they are
    /// gathered, and each node's next place in `at`.
    gathered: Vec<(u32, Mat3)>,
    next: Vec<u32>,
}

impl CoarseSprings {
    /// Whether there are no terms.
    pub fn is_empty(&self) -> bool {
        self.springs.is_empty()
    }

    /// Sets the terms of the first coarse level (`nodes` of them) from the acting
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
            self.push(s.block(weights), &mut entries);
        }
        self.gathered = entries;
        self.index(nodes);
    }

    /// Sets the terms to `finer`'s on the next coarser level (`nodes` of them), given the
    /// rows of the prolongator between them, as [`CoarseSprings::restrict_springs`].
    pub fn restrict(&mut self, finer: &CoarseSprings, nodes: usize, row: impl Fn(usize, &mut dyn FnMut(u32, Mat3))) {
        self.clear();
        let mut entries = std::mem::take(&mut self.gathered);
        for (t, &spring) in finer.springs.iter().enumerate() {
            entries.clear();
            for e in finer.entries(t) {
                let q = finer.blocks[e];
                row(finer.nodes[e] as usize, &mut |column, block| entries.push((column, q * block)));
            }
            self.push(spring, &mut entries);
        }
        self.gathered = entries;
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
        self.offsets.clear();
        self.offsets.push(0);
        self.nodes.clear();
        self.blocks.clear();
        self.springs.clear();
        self.gathered.clear();
        reserve_floored(&mut self.offsets, FLOOR);
        reserve_floored(&mut self.springs, FLOOR);
        reserve_floored(&mut self.nodes, FLOOR * ENTRIES);
        reserve_floored(&mut self.blocks, FLOOR * ENTRIES);
        reserve_floored(&mut self.gathered, 4 * ENTRIES);
    }

    fn entries(&self, t: usize) -> std::ops::Range<usize> {
        self.offsets[t] as usize..self.offsets[t + 1] as usize
    }

    /// Appends a term of block `spring` over `entries`, whose blocks at the same node are
    /// added (in the order given).
    fn push(&mut self, spring: Mat3, entries: &mut [(u32, Mat3)]) {
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
        self.springs.push(spring);
    }

    /// Indexes the entries by node, and sums each node's diagonal blocks.
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
        for t in 0..self.springs.len() {
            for e in self.entries(t) {
                let slot = &mut self.next[self.nodes[e] as usize];
                self.at[*slot as usize] = e as u32;
                self.term_of[*slot as usize] = t as u32;
                *slot += 1;
            }
        }
        let (mut own, mut partner) = (std::mem::take(&mut self.own), std::mem::take(&mut self.partner));
        own.clear();
        own.resize(nodes, Mat3::ZERO);
        partner.clear();
        partner.resize(nodes, Mat3::ZERO);
        self.for_blocks(|row, column, block| {
            if row == column {
                own[row] += block;
            } else if column == row ^ 1 {
                partner[row] += block;
            }
        });
        (self.own, self.partner) = (own, partner);
    }

    /// Node `c`'s diagonal block.
    pub fn own(&self, c: usize) -> Mat3 {
        self.own.get(c).copied().unwrap_or(Mat3::ZERO)
    }

    /// The block of row `c` in the column of its partner `c ^ 1`.
    pub fn partner(&self, c: usize) -> Mat3 {
        self.partner.get(c).copied().unwrap_or(Mat3::ZERO)
    }

    /// Calls `visit(row, column, block)` for every block the terms add, several times
    /// at the same place where several terms reach it: for a dense matrix.
    pub fn for_blocks(&self, mut visit: impl FnMut(usize, usize, Mat3)) {
        for (t, &spring) in self.springs.iter().enumerate() {
            for e in self.entries(t) {
                let pushed = spring * self.blocks[e];
                for f in self.entries(t) {
                    visit(self.nodes[f] as usize, self.nodes[e] as usize, self.blocks[f].transpose() * pushed);
                }
            }
        }
    }

    /// Sets the rows the terms reach of `out` to those of `Σ Qᵀ B Q x`, with `pushes`
    /// (one a term) to keep `B Q x` in: each term's push, then each row's sum of its
    /// entries, in term order. The rows no term reaches are left as they are (zero, kept
    /// so by the caller): a heap's springs reach a few coarse nodes, and on
    /// sphere_64_adaptive at rest (some 16 springs) products over every node made its
    /// median frame 5 to 14 % longer.
    pub fn product(&self, x: &[Vec3], pushes: &mut Vec<Vec3>, out: &mut [Vec3]) {
        pushes.clear();
        pushes.extend((0..self.springs.len()).map(|t| {
            let q: Vec3A =
                self.entries(t).map(|e| times(&self.blocks[e], Vec3A::from(x[self.nodes[e] as usize]))).sum();
            Vec3::from(times(&self.springs[t], q))
        }));
        for &c in &self.reached {
            let c = c as usize;
            let entries = self.at_offsets[c] as usize..self.at_offsets[c + 1] as usize;
            let sum: Vec3A = entries
                .map(|k| {
                    let (e, t) = (self.at[k] as usize, self.term_of[k] as usize);
                    transposed_times(&self.blocks[e], Vec3A::from(pushes[t]))
                })
                .sum();
            out[c] = Vec3::from(sum);
        }
    }
}
