//! Block-sparse matrices of 3×3 blocks, the shape of every derivative ∂f/∂x and ∂f/∂v of
//! a cloth: one block row per particle, one block per pair of particles that share an
//! element.

use glam::{Mat3, Vec3};
use rayon::prelude::*;

use crate::solver::PARALLEL_MIN_LEN;

/// Which blocks exist: for each particle (block row) the sorted particles (block columns)
/// it shares an element with, itself included.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BlockPattern {
    /// Row `i` is `columns[offsets[i]..offsets[i + 1]]`.
    pub offsets: Vec<u32>,
    /// Block column indices, sorted within each row.
    pub columns: Vec<u32>,
}

impl BlockPattern {
    /// The pattern of `row_count` particles coupled by `stencils` (the particle lists of
    /// elements: every pair within a stencil gets a block).
    pub fn from_stencils<'a>(row_count: usize, stencils: impl IntoIterator<Item = &'a [u32]>) -> Self {
        let mut rows: Vec<Vec<u32>> = (0..row_count as u32).map(|i| vec![i]).collect();
        for stencil in stencils {
            for &i in stencil {
                rows[i as usize].extend_from_slice(stencil);
            }
        }
        let mut offsets = Vec::with_capacity(row_count + 1);
        let mut columns = Vec::new();
        offsets.push(0);
        for mut row in rows {
            row.sort_unstable();
            row.dedup();
            columns.extend_from_slice(&row);
            offsets.push(columns.len() as u32);
        }
        Self { offsets, columns }
    }

    /// Number of block rows.
    pub fn rows(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// The slots of row `i` in the block storage (and in `columns`).
    pub fn slots(&self, i: usize) -> std::ops::Range<usize> {
        self.offsets[i] as usize..self.offsets[i + 1] as usize
    }

    /// The slots of rows `rows`, which are contiguous.
    pub fn slots_of(&self, rows: std::ops::Range<usize>) -> std::ops::Range<usize> {
        self.offsets[rows.start] as usize..self.offsets[rows.end] as usize
    }

    /// The columns of row `i`.
    pub fn row(&self, i: usize) -> &[u32] {
        &self.columns[self.slots(i)]
    }

    /// The row a slot belongs to.
    pub fn row_of(&self, slot: usize) -> usize {
        self.offsets.partition_point(|&o| o as usize <= slot) - 1
    }

    /// Index of block `(row, column)` in the block storage, if it exists.
    pub fn slot(&self, row: u32, column: u32) -> Option<u32> {
        let (start, end) = (self.offsets[row as usize] as usize, self.offsets[row as usize + 1] as usize);
        self.columns[start..end].binary_search(&column).ok().map(|k| (start + k) as u32)
    }

    /// Index of row `i`'s diagonal block, which every row has.
    pub fn diagonal_slot(&self, i: usize) -> usize {
        self.slot(i as u32, i as u32).expect("every row has its diagonal") as usize
    }

    /// Slots of all `N × N` blocks of a stencil, row-major: where an element's local
    /// blocks go. Panics if the stencil is not in the pattern.
    pub fn stencil_slots<const N: usize>(&self, stencil: [u32; N]) -> [[u32; N]; N] {
        stencil.map(|i| stencil.map(|j| self.slot(i, j).expect("the stencil is part of the pattern")))
    }

    /// [`BlockPattern::stencil_slots`] relative to each block's row: the position of
    /// column `stencil[b]` within row `stencil[a]`. Kept per element instead of the
    /// slots, they take half the memory (a row holds a few dozen blocks, not 65 536).
    pub fn stencil_positions<const N: usize>(&self, stencil: [u32; N]) -> [[u16; N]; N] {
        let slots = self.stencil_slots(stencil);
        std::array::from_fn(|a| {
            let start = self.offsets[stencil[a] as usize];
            slots[a].map(|slot| u16::try_from(slot - start).expect("a particle shares elements with fewer than 65 536"))
        })
    }

    /// Lets `group(i, columns, blocks)` work on each group of `size` rows from row `i`
    /// within `rows` (whole groups), given their `blocks` (row after row, `blocks` being
    /// those of `rows`) and the columns of row `i`: halves of the rows in parallel, down
    /// to [`PARALLEL_MIN_LEN`] blocks. Each block is worked on by one call, so the result
    /// does not depend on the number of threads.
    pub(crate) fn fill_row_range(
        &self,
        size: usize,
        rows: std::ops::Range<usize>,
        blocks: &mut [Mat3],
        group: &(impl Fn(usize, &[u32], &mut [Mat3]) + Sync),
    ) {
        let first = self.offsets[rows.start] as usize;
        if blocks.len() <= PARALLEL_MIN_LEN || rows.len() <= size {
            for i in rows.step_by(size) {
                let slots = self.slots_of(i..i + size);
                group(i, self.row(i), &mut blocks[slots.start - first..slots.end - first]);
            }
            return;
        }
        let middle = rows.start + rows.len() / (2 * size) * size;
        let (left, right) = blocks.split_at_mut(self.offsets[middle] as usize - first);
        rayon::join(
            || self.fill_row_range(size, rows.start..middle, left, group),
            || self.fill_row_range(size, middle..rows.end, right, group),
        );
    }

    /// The slots of a stencil from its [`BlockPattern::stencil_positions`].
    pub fn slots_at<const N: usize>(&self, stencil: [u32; N], positions: &[[u16; N]; N]) -> [[u32; N]; N] {
        std::array::from_fn(|a| {
            let start = self.offsets[stencil[a] as usize];
            positions[a].map(|position| start + u32::from(position))
        })
    }
}

/// A matrix of 3×3 blocks over a [`BlockPattern`], stored in full (both triangles), so a
/// product is a parallel gather over rows in a fixed order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BlockMatrix {
    /// One block per pattern slot.
    pub blocks: Vec<Mat3>,
}

impl BlockMatrix {
    /// Zeroes the matrix and sizes it for `pattern`, in parallel: on the 256² hang scene
    /// the matrix is 45 MB, and zeroing it on one thread idled the other.
    pub fn reset(&mut self, pattern: &BlockPattern) {
        self.blocks.resize(pattern.columns.len(), Mat3::ZERO);
        self.blocks.par_iter_mut().with_min_len(PARALLEL_MIN_LEN).for_each(|block| *block = Mat3::ZERO);
    }

    /// Adds an element's local blocks at their `slots`.
    #[inline]
    pub fn add_local<const N: usize>(&mut self, slots: &[[u32; N]; N], local: &[[Mat3; N]; N]) {
        for a in 0..N {
            for b in 0..N {
                self.blocks[slots[a][b] as usize] += local[a][b];
            }
        }
    }

    /// Adds `diagonal[i] · I` to each diagonal block.
    pub fn add_diagonal(&mut self, pattern: &BlockPattern, diagonal: impl Fn(usize) -> f32) {
        for i in 0..pattern.rows() {
            self.blocks[pattern.diagonal_slot(i)] += Mat3::from_diagonal(Vec3::splat(diagonal(i)));
        }
    }

    /// Adds to the rows below `split` and to the rest in two parallel tasks:
    /// `add(rows, blocks, first)` gets the blocks of `rows` (over `pattern`), the first of
    /// them at slot `first`, and must add only into those. Terms that each task adds in a
    /// fixed order keep that order, and so their sums, on any number of threads; the
    /// serial additions of an assembly become two.
    pub fn add_by_halves(
        &mut self,
        pattern: &BlockPattern,
        split: usize,
        add: impl Fn(std::ops::Range<usize>, &mut [Mat3], usize) + Sync,
    ) {
        let split = split.min(pattern.rows());
        let first = pattern.offsets[split] as usize;
        let (low, high) = self.blocks.split_at_mut(first);
        rayon::join(|| add(0..split, low, 0), || add(split..pattern.rows(), high, first));
    }

    /// `out = self · x`.
    pub fn multiply(&self, pattern: &BlockPattern, x: &[Vec3], out: &mut [Vec3]) {
        out.par_iter_mut().with_min_len(PARALLEL_MIN_LEN).enumerate().for_each(|(i, out)| {
            let mut sum = Vec3::ZERO;
            for k in pattern.slots(i) {
                sum += self.blocks[k] * x[pattern.columns[k] as usize];
            }
            *out = sum;
        });
    }

    /// The block `(row, column)`, zero where the pattern has none.
    pub fn block(&self, pattern: &BlockPattern, row: u32, column: u32) -> Mat3 {
        pattern.slot(row, column).map_or(Mat3::ZERO, |s| self.blocks[s as usize])
    }
}

/// ∂f/∂v: a [`BlockMatrix`] over the pattern where springs damp, else its diagonal alone.
/// Only damped springs fill it off the diagonal (drag is per particle), and a second full
/// matrix beside ∂f/∂x costs a cloth of triangles some 700 bytes a particle for zeros.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct VelocityJacobian {
    /// Over the pattern when `full`; else one block per row, the diagonal's.
    matrix: BlockMatrix,
    full: bool,
}

impl VelocityJacobian {
    /// Zeroes the matrix, sized for the whole `pattern` if `full`, else for its diagonal.
    pub fn reset(&mut self, pattern: &BlockPattern, full: bool) {
        self.full = full;
        if full {
            self.matrix.reset(pattern);
        } else {
            self.matrix.blocks.clear();
            self.matrix.blocks.resize(pattern.rows(), Mat3::ZERO);
        }
    }

    /// Adds an element's local blocks at their `slots`. Panics unless reset `full`.
    pub fn add_local<const N: usize>(&mut self, slots: &[[u32; N]; N], local: &[[Mat3; N]; N]) {
        assert!(self.full, "off-diagonal blocks need a full velocity Jacobian");
        self.matrix.add_local(slots, local);
    }

    /// Adds `diagonal[i] · I` to each diagonal block.
    pub fn add_diagonal(&mut self, pattern: &BlockPattern, diagonal: impl Fn(usize) -> f32) {
        if self.full {
            return self.matrix.add_diagonal(pattern, diagonal);
        }
        for (i, block) in self.matrix.blocks.iter_mut().enumerate() {
            *block += Mat3::from_diagonal(Vec3::splat(diagonal(i)));
        }
    }

    /// `out = self · x`.
    pub fn multiply(&self, pattern: &BlockPattern, x: &[Vec3], out: &mut [Vec3]) {
        if self.full {
            return self.matrix.multiply(pattern, x, out);
        }
        out.par_iter_mut()
            .zip(x.par_iter())
            .zip(self.matrix.blocks.par_iter())
            .with_min_len(PARALLEL_MIN_LEN)
            .for_each(|((out, x), block)| {
                *out = *block * *x;
            });
    }

    /// The block `(row, column)`, zero where there is none.
    pub fn block(&self, pattern: &BlockPattern, row: u32, column: u32) -> Mat3 {
        match self.full {
            true => self.matrix.block(pattern, row, column),
            false if row == column => self.matrix.blocks[row as usize],
            false => Mat3::ZERO,
        }
    }

    /// `matrix ← a · self − b · matrix + diagonal(i) I` over `matrix`'s pattern, in place
    /// and rows in parallel: the implicit system takes over the storage of ∂f/∂x, which
    /// nothing reads once the system is built, instead of a third matrix of the pattern,
    /// and is made in one pass over it (two passes on one thread took 1.3 % of the 256²
    /// hang scene's samples while the other thread waited).
    pub fn combine_into(
        &self,
        a: f32,
        b: f32,
        pattern: &BlockPattern,
        matrix: &mut BlockMatrix,
        diagonal: impl Fn(usize) -> f32 + Sync,
    ) {
        pattern.fill_row_range(1, 0..pattern.rows(), &mut matrix.blocks, &|i, columns, blocks| {
            let first = pattern.offsets[i] as usize;
            for (k, (&column, block)) in columns.iter().zip(blocks).enumerate() {
                let on_diagonal = column as usize == i;
                *block = match (self.full, on_diagonal) {
                    (true, _) => a * self.matrix.blocks[first + k] - b * *block,
                    (false, true) => a * self.matrix.blocks[i] - b * *block,
                    (false, false) => -(b * *block),
                };
                if on_diagonal {
                    *block += Mat3::from_diagonal(Vec3::splat(diagonal(i)));
                }
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_chain_of_two_springs_couples_neighbours_only() {
        let pattern = BlockPattern::from_stencils(3, [&[0u32, 1][..], &[1, 2][..]]);
        assert_eq!(pattern.offsets, vec![0, 2, 5, 7]);
        assert_eq!(pattern.columns, vec![0, 1, 0, 1, 2, 1, 2]);
        assert_eq!(pattern.slot(0, 2), None);
        // Row 2 is [1, 2]: column 1 is its first block, and slot 5.
        assert_eq!(pattern.stencil_positions([2, 1]), [[1, 0], [2, 1]]);
        assert_eq!(pattern.slots_at([2, 1], &pattern.stencil_positions([2, 1])), pattern.stencil_slots([2, 1]));
        let mut m = BlockMatrix::default();
        m.reset(&pattern);
        m.add_diagonal(&pattern, |i| i as f32 + 1.0);
        m.add_local(&pattern.stencil_slots([1, 2]), &[[Mat3::ZERO, Mat3::IDENTITY], [Mat3::IDENTITY, Mat3::ZERO]]);
        let mut out = vec![Vec3::ZERO; 3];
        m.multiply(&pattern, &[Vec3::X, Vec3::Y, Vec3::Z], &mut out);
        assert_eq!(out, vec![Vec3::X, 2.0 * Vec3::Y + Vec3::Z, 3.0 * Vec3::Z + Vec3::Y]);
    }

    /// Either half sees its own rows' blocks at their slots, wherever the split falls.
    #[test]
    fn halves_add_into_their_own_rows_only() {
        let pattern = BlockPattern::from_stencils(3, [&[0u32, 1][..], &[1, 2][..]]);
        for split in 0..5 {
            let mut m = BlockMatrix::default();
            m.reset(&pattern);
            m.add_by_halves(&pattern, split, |rows, blocks, first| {
                for row in rows {
                    for slot in pattern.slots(row) {
                        blocks[slot - first] += Mat3::from_diagonal(Vec3::splat((10 * row + slot) as f32));
                    }
                }
            });
            for slot in 0..pattern.columns.len() {
                let expected = (10 * pattern.row_of(slot) + slot) as f32;
                assert_eq!(m.blocks[slot], Mat3::from_diagonal(Vec3::splat(expected)), "split {split}, slot {slot}");
            }
        }
    }

    /// The diagonal-only velocity Jacobian multiplies, reads and combines as the full one
    /// holding the same diagonal does.
    #[test]
    fn a_diagonal_velocity_jacobian_acts_as_the_full_one() {
        let pattern = BlockPattern::from_stencils(3, [&[0u32, 1][..], &[1, 2][..]]);
        let mut stiffness = BlockMatrix::default();
        stiffness.reset(&pattern);
        stiffness.add_local(
            &pattern.stencil_slots([0, 1]),
            &[[Mat3::IDENTITY, -Mat3::IDENTITY], [-Mat3::IDENTITY, Mat3::IDENTITY]],
        );
        let [mut diagonal, mut full] = [false, true].map(|full| {
            let mut d = VelocityJacobian::default();
            d.reset(&pattern, full);
            d
        });
        for d in [&mut diagonal, &mut full] {
            d.add_diagonal(&pattern, |i| -(i as f32) - 0.5);
        }
        assert_eq!(diagonal.matrix.blocks.len(), 3);
        let x = [Vec3::X, Vec3::Y, Vec3::new(1.0, 2.0, 3.0)];
        let (mut a, mut b) = (vec![Vec3::ZERO; 3], vec![Vec3::ZERO; 3]);
        diagonal.multiply(&pattern, &x, &mut a);
        full.multiply(&pattern, &x, &mut b);
        assert_eq!(a, b);
        assert_eq!(diagonal.block(&pattern, 1, 0), Mat3::ZERO);
        assert_eq!(diagonal.block(&pattern, 2, 2), full.block(&pattern, 2, 2));
        let (mut a, mut b) = (stiffness.clone(), stiffness.clone());
        diagonal.combine_into(-0.1, 0.3, &pattern, &mut a, |i| i as f32);
        full.combine_into(-0.1, 0.3, &pattern, &mut b, |i| i as f32);
        assert_eq!(a, b);
        assert_eq!(a.block(&pattern, 0, 0), Mat3::from_diagonal(Vec3::splat(0.05 - 0.3)));
        // −0.1 · (−1.5) − 0.3 · 1 + 1 on the diagonal; off it, −0.3 · (−1).
        assert!(a.block(&pattern, 1, 1).abs_diff_eq(Mat3::from_diagonal(Vec3::splat(0.85)), 1e-6));
        assert_eq!(a.block(&pattern, 1, 0), Mat3::from_diagonal(Vec3::splat(0.3)));
    }
}
