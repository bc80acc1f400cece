//! Block-sparse matrices of 3×3 blocks, the shape of every derivative ∂f/∂x and ∂f/∂v of
//! a cloth: one block row per particle, one block per pair of particles that share an
//! element. The cloth's derivatives and its implicit system are symmetric and keep only
//! the blocks on and above the diagonal ([`SymmetricBlockMatrix`]), as do the
//! multigrid's levels; its prolongators keep every block, on large levels in bfloat16
//! ([`super::half`]).

use glam::{Mat3, Mat3A, Vec3, Vec3A};
use rayon::prelude::*;

use crate::memory::release;
use crate::solver::PARALLEL_MIN_LEN;

/// `b v` with the block's columns in SIMD registers. glam's `Mat3 * Vec3` works on
/// three scalar lanes; widened to four, the symmetric product over the 65 536-particle
/// sheet took 0.87 ms against 1.14 (`cargo bench --bench step -- matrix_product`), with
/// the same sums in the same order, so the same bits.
#[inline]
pub fn times(b: &Mat3, v: Vec3A) -> Vec3A {
    Vec3A::from(b.x_axis) * v.x + Vec3A::from(b.y_axis) * v.y + Vec3A::from(b.z_axis) * v.z
}

/// `bᵀ v` as [`times`] does `b v`: the block transposed in registers, then its columns
/// scaled and added, faster than three dot products and the same sums.
#[inline]
pub fn transposed_times(b: &Mat3, v: Vec3A) -> Vec3A {
    let t = Mat3A::from(*b).transpose();
    t.x_axis * v.x + t.y_axis * v.y + t.z_axis * v.z
}

/// `a b` as [`times`] does `b v`, column by column: the Galerkin and prolongator
/// products' blocks.
#[inline]
pub fn block_product(a: &Mat3, b: &Mat3) -> Mat3 {
    Mat3::from(Mat3A::from(*a) * Mat3A::from(*b))
}

/// A symmetric 3×3 block kept by its six distinct entries (`xx, yy, zz, xy, xz, yz`):
/// 24 bytes where a [`Mat3`] takes 36. The multigrid's smoothers keep the inverse of
/// each node's diagonal block, symmetric as the matrix is, for every node of every level:
/// on the 256² hang scene 0.8 MB, 12 bytes a particle, less.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SymmetricBlock([f32; 6]);

impl SymmetricBlock {
    /// The symmetric part of `m`, `(m + mᵀ) / 2`: `m` itself, bit for bit, where it is
    /// symmetric.
    pub fn new(m: Mat3) -> Self {
        let mean = |a: f32, b: f32| 0.5 * (a + b);
        Self([
            m.x_axis.x,
            m.y_axis.y,
            m.z_axis.z,
            mean(m.y_axis.x, m.x_axis.y),
            mean(m.z_axis.x, m.x_axis.z),
            mean(m.z_axis.y, m.y_axis.z),
        ])
    }

    /// The block whole.
    pub fn matrix(self) -> Mat3 {
        let [xx, yy, zz, xy, xz, yz] = self.0;
        Mat3::from_cols(Vec3::new(xx, xy, xz), Vec3::new(xy, yy, yz), Vec3::new(xz, yz, zz))
    }

    /// `b v` as [`times`] forms it from the block whole: the same sums, the same bits.
    #[inline]
    pub fn times(&self, v: Vec3A) -> Vec3A {
        let [xx, yy, zz, xy, xz, yz] = self.0;
        Vec3A::new(xx, xy, xz) * v.x + Vec3A::new(xy, yy, yz) * v.y + Vec3A::new(xz, yz, zz) * v.z
    }
}

/// Which blocks exist: for each particle (block row) the sorted particles (block columns)
/// it shares an element with, itself included.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BlockPattern {
    /// Row `i` is `columns[offsets[i]..offsets[i + 1]]`.
    pub offsets: Vec<u32>,
    /// Block column indices, sorted within each row.
    pub columns: Vec<u32>,
    /// Where each row's blocks on and above the diagonal begin in the storage of a
    /// [`SymmetricBlockMatrix`], one more than there are rows; empty unless laid out for
    /// one ([`BlockPattern::with_upper`]).
    pub upper: Vec<u32>,
    /// Per block below the diagonal, in slot order, the index of its mirror above in that
    /// storage.
    pub mirrors: Vec<u32>,
    /// How far right of the diagonal any row reaches (`column − row`, at most): the
    /// bandwidth that the cloth's ordering keeps small.
    pub reach: usize,
}

/// The `(a, b)` pairs, `a ≤ b`, of an `N`-particle element's local blocks on and above
/// its diagonal, row by row: those a [`SymmetricBlockMatrix`] takes (each one below is
/// its mirror transposed).
pub fn upper_pairs<const N: usize>() -> impl Iterator<Item = (usize, usize)> + Clone {
    (0..N).flat_map(|a| (a..N).map(move |b| (a, b)))
}

/// `[f(a, b)]` over the [`upper_pairs`] of an `N`-particle element, in their order: the
/// `M = N (N + 1) / 2` values a symmetric matrix takes of an element's blocks.
pub fn upper_map<const N: usize, const M: usize, T>(mut f: impl FnMut(usize, usize) -> T) -> [T; M] {
    const { assert!(M == N * (N + 1) / 2) };
    let mut pairs = upper_pairs::<N>();
    std::array::from_fn(|_| {
        let (a, b) = pairs.next().expect("M pairs");
        f(a, b)
    })
}

/// The index of pair `(a, b)` or `(b, a)` among [`upper_pairs`].
pub const fn upper_pair<const N: usize>(a: usize, b: usize) -> usize {
    let (a, b) = if a <= b { (a, b) } else { (b, a) };
    a * (2 * N + 1 - a) / 2 + (b - a)
}

/// Row `i` of a symmetric pattern in its two parts, columns ascending in each.
pub struct SymmetricRow<'a> {
    /// The columns below the diagonal.
    pub below: &'a [u32],
    /// Where each of those blocks' mirror above the diagonal is stored.
    pub mirrors: &'a [u32],
    /// The columns from the diagonal on.
    pub above: &'a [u32],
    /// Where their blocks are stored, in order.
    pub storage: std::ops::Range<usize>,
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
        // Each row is taken as its turn comes, so the lists are freed as they go.
        let pattern = Self::from_rows(row_count, |i, row| *row = std::mem::take(&mut rows[i]));
        release(rows);
        pattern
    }

    /// Frees a pattern that was made for a while, its lists as [`release`] frees them.
    pub fn release(self) {
        let Self { offsets, columns, upper, mirrors, .. } = self;
        release(offsets);
        release(columns);
        release(upper);
        release(mirrors);
    }

    /// A pattern of `rows` rows, row `i` the sorted distinct columns that `fill(i, row)`
    /// leaves in `row`, which it is given empty.
    /// The storage is given back what growing it row by row reserved beyond the rows, up
    /// to half the columns': with every pattern so shrunk, the 256² hang scene's peak
    /// heap fell by 2.4 MB (36 bytes a particle, of 2 493).
    pub(crate) fn from_rows(rows: usize, mut fill: impl FnMut(usize, &mut Vec<u32>)) -> Self {
        let mut pattern = Self { offsets: Vec::with_capacity(rows + 1), ..Self::default() };
        pattern.offsets.push(0);
        let mut row = Vec::new();
        for i in 0..rows {
            row.clear();
            fill(i, &mut row);
            row.sort_unstable();
            row.dedup();
            pattern.columns.extend_from_slice(&row);
            pattern.offsets.push(pattern.columns.len() as u32);
        }
        pattern.offsets.shrink_to_fit();
        pattern.columns.shrink_to_fit();
        pattern
    }

    /// This (symmetric) pattern laid out for a [`SymmetricBlockMatrix`]: each row's
    /// blocks from the diagonal on, row after row, and the mirror of every block below.
    /// Only the patterns of such matrices need it (on the 256² hang scene the mirrors
    /// are 2.3 MB).
    pub fn with_upper(mut self) -> Self {
        let rows = self.rows();
        self.upper = Vec::with_capacity(rows + 1);
        self.upper.push(0);
        for i in 0..rows {
            let above = self.row(i).len() - self.below(i);
            self.upper.push(self.upper[i] + above as u32);
        }
        let mut mirrors = Vec::with_capacity(self.columns.len() - self.upper[rows] as usize);
        for i in 0..rows {
            let below = &self.row(i)[..self.below(i)];
            mirrors.extend(below.iter().map(|&j| self.upper_index(j, i as u32).expect("the pattern is symmetric")));
        }
        self.mirrors = mirrors;
        self.reach =
            (0..rows).map(|i| self.row(i).last().map_or(0, |&j| (j as usize).saturating_sub(i))).max().unwrap_or(0);
        self
    }

    /// How many of row `i`'s columns are below the diagonal.
    fn below(&self, i: usize) -> usize {
        self.row(i).partition_point(|&c| (c as usize) < i)
    }

    /// Row `i` split at its diagonal, with where a [`SymmetricBlockMatrix`] stores each
    /// part.
    #[inline]
    pub fn symmetric_row(&self, i: usize) -> SymmetricRow<'_> {
        let (slots, storage) = (self.slots(i), self.upper[i] as usize..self.upper[i + 1] as usize);
        let diagonal = slots.end - storage.len();
        let first_mirror = slots.start - storage.start;
        SymmetricRow {
            below: &self.columns[slots.start..diagonal],
            mirrors: &self.mirrors[first_mirror..first_mirror + diagonal - slots.start],
            above: &self.columns[diagonal..slots.end],
            storage,
        }
    }

    /// Row `i`'s columns from the diagonal on, and where a [`SymmetricBlockMatrix`] stores
    /// their blocks: the part of [`BlockPattern::symmetric_row`] a product over the stored
    /// blocks reads, without the slices of the part below the diagonal it does not.
    #[inline(always)]
    fn upper_row(&self, i: usize) -> (&[u32], std::ops::Range<usize>) {
        let storage = self.upper[i] as usize..self.upper[i + 1] as usize;
        let end = self.offsets[i + 1] as usize;
        (&self.columns[end - storage.len()..end], storage)
    }

    /// Index in a [`SymmetricBlockMatrix`]'s storage of block `(row, column)` or, below
    /// the diagonal, of its mirror, if the pattern has it.
    pub fn upper_index(&self, row: u32, column: u32) -> Option<u32> {
        let (row, column) = (row.min(column) as usize, row.max(column));
        let above = (self.upper[row + 1] - self.upper[row]) as usize;
        let end = self.offsets[row + 1] as usize;
        self.columns[end - above..end].binary_search(&column).ok().map(|k| self.upper[row] + k as u32)
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

    /// Storage indices in a [`SymmetricBlockMatrix`] of a stencil's blocks on and above
    /// its diagonal, in [`upper_pairs`] order (`M = N (N + 1) / 2` of them): where an
    /// element's local blocks go. Panics if the stencil is not in the pattern.
    pub fn upper_slots<const N: usize, const M: usize>(&self, stencil: [u32; N]) -> [u32; M] {
        upper_map::<N, M, _>(|a, b| {
            self.upper_index(stencil[a], stencil[b]).expect("the stencil is part of the pattern")
        })
    }

    /// [`BlockPattern::upper_slots`] relative to the start of the upper row each block is
    /// in: for `(a, b)`, the position of the later of the two particles among the earlier
    /// one's columns from its diagonal on. Kept per element instead of the storage
    /// indices, they take half the memory (a row holds a few dozen blocks, not 65 536),
    /// and the pairs on and above the diagonal alone a bending face's 42 bytes, not 72.
    pub fn upper_positions<const N: usize, const M: usize>(&self, stencil: [u32; N]) -> [u16; M] {
        upper_map::<N, M, _>(|a, b| {
            let slot = self.upper_index(stencil[a], stencil[b]).expect("the stencil is part of the pattern");
            let row_start = self.upper[stencil[a].min(stencil[b]) as usize];
            u16::try_from(slot - row_start).expect("a particle shares elements with fewer than 65 536")
        })
    }

    /// The storage indices of a stencil's blocks from its
    /// [`BlockPattern::upper_positions`].
    pub fn upper_slots_at<const N: usize, const M: usize>(&self, stencil: [u32; N], positions: &[u16; M]) -> [u32; M] {
        let mut pairs = upper_pairs::<N>();
        positions.map(|position| {
            let (a, b) = pairs.next().expect("M pairs");
            self.upper[stencil[a].min(stencil[b]) as usize] + u32::from(position)
        })
    }

    /// Lets `group(i, columns, blocks)` work on each group of `size` rows from row `i`
    /// within `rows` (whole groups), given their `blocks` (or whatever is kept per block;
    /// row after row, `blocks` being those of `rows`) and the columns of row `i`: halves
    /// of the rows in parallel, down to [`PARALLEL_MIN_LEN`] blocks. Each block is worked
    /// on by one call, so the result does not depend on the number of threads.
    pub(crate) fn fill_row_range<T: Send>(
        &self,
        size: usize,
        rows: std::ops::Range<usize>,
        blocks: &mut [T],
        group: &(impl Fn(usize, &[u32], &mut [T]) + Sync),
    ) {
        split_rows(&self.offsets, size, rows, blocks, &|i, blocks| group(i, self.row(i), blocks));
    }

    /// Lets `group(i, row, values)` work on what is kept per block of a
    /// [`SymmetricBlockMatrix`]'s storage (`values`, one per stored block) row by row,
    /// given row `i`'s part from its diagonal on: halves of the rows in parallel, as
    /// [`BlockPattern::fill_row_range`].
    pub(crate) fn fill_upper_rows<T: Send>(
        &self,
        values: &mut [T],
        group: &(impl Fn(usize, SymmetricRow<'_>, &mut [T]) + Sync),
    ) {
        split_rows(&self.upper, 1, 0..self.rows(), values, &|i, values| group(i, self.symmetric_row(i), values));
    }
}

/// Lets `add(part, rows, blocks, first)` work on each part of the rows, between
/// consecutive `bounds` (ascending, from 0 to the number of rows), in parallel tasks,
/// given their `blocks` in a storage whose rows begin at `offsets`. Halves of the parts
/// are split off by `rayon::join`, which allocates nothing.
fn add_by_parts(
    offsets: &[u32],
    blocks: &mut [Mat3],
    bounds: &[usize],
    add: &(impl Fn(usize, std::ops::Range<usize>, &mut [Mat3], usize) + Sync),
) {
    let offset = |row: usize| offsets[row] as usize;
    split_parts(RowStorage { offset: &offset, items: blocks }, bounds, 0, &|part, rows, blocks| {
        let first = offset(rows.start);
        add(part, rows, blocks.items, first);
    });
}

/// Lets `work(part, rows, values)` work on each part of the rows, between consecutive
/// `bounds`, given the part's `values` (one per row), in parallel tasks as
/// [`add_by_parts`] does.
pub(crate) fn by_parts<T: Send>(
    values: &mut [T],
    bounds: &[usize],
    work: impl Fn(usize, std::ops::Range<usize>, &mut [T]) + Sync,
) {
    split_parts(RowStorage { offset: &|row| row, items: values }, bounds, 0, &|part, rows, values| {
        work(part, rows, values.items);
    });
}

/// Cuts the ascending `rows` (of `nodes`) into parts of about equal work, row `k` taking
/// `work(k)` of `total`: at most `max_parts`, and none under `part_work` but the only
/// one. Part `p` holds `rows[part_rows[p]..part_rows[p + 1]]`, the nodes from `bounds[p]`
/// to `bounds[p + 1]`, for [`by_parts`].
#[allow(clippy::too_many_arguments)]
pub(crate) fn cut_parts(
    rows: &[u32],
    nodes: usize,
    total: usize,
    part_work: usize,
    max_parts: usize,
    work: impl Fn(usize) -> usize,
    part_rows: &mut Vec<usize>,
    bounds: &mut Vec<usize>,
) {
    let parts = total.div_ceil(part_work).clamp(1, max_parts);
    part_rows.clear();
    part_rows.push(0);
    bounds.clear();
    bounds.push(0);
    let mut done = 0;
    for (k, &row) in rows.iter().enumerate() {
        let cuts = part_rows.len();
        if cuts < parts && k > 0 && done * parts >= cuts * total {
            part_rows.push(k);
            bounds.push(row as usize);
        }
        done += work(k);
    }
    part_rows.push(rows.len());
    bounds.push(nodes);
}

/// [`by_parts`] with one item of `kept` for each part (as many as the parts, which must
/// not be empty): `work(part, rows, values, kept)` gets its own beside its values, such as
/// a part's scratch and the lists it fills.
pub(crate) fn by_parts_keeping<T: Send, K: Send>(
    values: &mut [T],
    kept: &mut [K],
    bounds: &[usize],
    work: impl Fn(usize, std::ops::Range<usize>, &mut [T], &mut K) + Sync,
) {
    // The storages are cut at the bounds alone, where a bound's index is its part's.
    let part = |row: usize| bounds.partition_point(|&bound| bound < row);
    let storages = (RowStorage { offset: &|row| row, items: values }, RowStorage { offset: &part, items: kept });
    split_parts(storages, bounds, 0, &|p, rows, (values, kept)| work(p, rows, values.items, &mut kept.items[0]));
}

/// What is kept for a range of rows, cut where a part of the rows begins.
trait PartStorage: Send + Sized {
    /// The storage of the rows before `at` and of those from it, this storage's rows
    /// beginning at `start`.
    fn cut(self, start: usize, at: usize) -> (Self, Self);
}

/// Items kept row by row, row `r`'s from `offset(r)` of the whole storage.
struct RowStorage<'a, T, F> {
    offset: &'a F,
    items: &'a mut [T],
}

impl<T: Send, F: Fn(usize) -> usize + Sync> PartStorage for RowStorage<'_, T, F> {
    fn cut(self, start: usize, at: usize) -> (Self, Self) {
        let (low, high) = self.items.split_at_mut((self.offset)(at) - (self.offset)(start));
        (Self { offset: self.offset, items: low }, Self { offset: self.offset, items: high })
    }
}

/// Two storages of the same rows, cut together.
impl<A: PartStorage, B: PartStorage> PartStorage for (A, B) {
    fn cut(self, start: usize, at: usize) -> (Self, Self) {
        let ((a_low, a_high), (b_low, b_high)) = (self.0.cut(start, at), self.1.cut(start, at));
        ((a_low, b_low), (a_high, b_high))
    }
}

/// [`add_by_parts`] for the parts from `first_part` on, at `bounds`, whose `items` begin
/// at the first bound's row.
fn split_parts<S: PartStorage>(
    items: S,
    bounds: &[usize],
    first_part: usize,
    work: &(impl Fn(usize, std::ops::Range<usize>, S) + Sync),
) {
    match *bounds {
        [] | [_] => {}
        [start, end] => work(first_part, start..end, items),
        [start, ..] => {
            let middle = (bounds.len() - 1) / 2;
            let (low, high) = items.cut(start, bounds[middle]);
            rayon::join(
                || split_parts(low, &bounds[..=middle], first_part, work),
                || split_parts(high, &bounds[middle..], first_part + middle, work),
            );
        }
    }
}

/// Lets `group(i, blocks)` work on each group of `size` rows from row `i` within `rows`
/// (whole groups), given their `blocks` (or whatever is kept per block) in a storage whose
/// rows begin at `offsets` (`blocks` being those of `rows`): halves of the rows in
/// parallel, down to [`PARALLEL_MIN_LEN`] blocks.
fn split_rows<T: Send>(
    offsets: &[u32],
    size: usize,
    rows: std::ops::Range<usize>,
    blocks: &mut [T],
    group: &(impl Fn(usize, &mut [T]) + Sync),
) {
    let first = offsets[rows.start] as usize;
    if blocks.len() <= PARALLEL_MIN_LEN || rows.len() <= size {
        for i in rows.step_by(size) {
            let (start, end) = (offsets[i] as usize, offsets[i + size] as usize);
            group(i, &mut blocks[start - first..end - first]);
        }
        return;
    }
    let middle = rows.start + rows.len() / (2 * size) * size;
    let (left, right) = blocks.split_at_mut(offsets[middle] as usize - first);
    rayon::join(
        || split_rows(offsets, size, rows.start..middle, left, group),
        || split_rows(offsets, size, middle..rows.end, right, group),
    );
}

/// Where each element's local blocks go in a [`SymmetricBlockMatrix`]: per element, its
/// [`BlockPattern::upper_positions`], one byte each where no row holds more than 256
/// blocks from its diagonal on (a cloth's rows hold a few dozen), else two. The positions
/// of a 256² sheet's bending faces and membranes took 108 bytes a particle in two bytes
/// each, 54 in one. Collected from an exact-size iterator, the arrays are allocated at
/// their size.
#[derive(Debug, Clone, PartialEq)]
pub enum ElementPositions<const M: usize> {
    /// One byte a position: every row holds at most 256 blocks from its diagonal on.
    Narrow(Vec<[u8; M]>),
    /// Two bytes a position.
    Wide(Vec<[u16; M]>),
}

impl<const M: usize> Default for ElementPositions<M> {
    fn default() -> Self {
        Self::Narrow(Vec::new())
    }
}

impl<const M: usize> ElementPositions<M> {
    /// The positions of the `stencils`' blocks in `pattern`.
    pub fn new<const N: usize>(pattern: &BlockPattern, stencils: impl ExactSizeIterator<Item = [u32; N]>) -> Self {
        let widest = pattern.upper.windows(2).map(|w| w[1] - w[0]).max().unwrap_or(0);
        let positions = stencils.map(|stencil| pattern.upper_positions::<N, M>(stencil));
        match widest <= 1 << u8::BITS {
            true => Self::Narrow(positions.map(|p| p.map(|p| p as u8)).collect()),
            false => Self::Wide(positions.collect()),
        }
    }

    /// Element `e`'s positions.
    #[inline]
    pub fn get(&self, e: usize) -> [u16; M] {
        match self {
            Self::Narrow(positions) => positions[e].map(u16::from),
            Self::Wide(positions) => positions[e],
        }
    }
}

/// Rows a chunk of [`SymmetricBlockMatrix::multiply`] at least.
const PRODUCT_CHUNK: usize = 64;

/// The rows of a chunk of [`SymmetricBlockMatrix::multiply`] over `pattern`: at least its
/// reach, so that a chunk adds only to its own rows and the next chunk's, and even.
fn product_chunk(pattern: &BlockPattern) -> usize {
    pattern.reach.max(PRODUCT_CHUNK).next_multiple_of(2)
}

/// A symmetric matrix of 3×3 blocks over a symmetric [`BlockPattern`] laid out for it
/// ([`BlockPattern::with_upper`]), of which it stores the blocks on and above the
/// diagonal, row after row ([`BlockPattern::upper`]); a block below is its mirror
/// transposed. The cloth's
/// ∂f/∂x, ∂f/∂v and implicit system are symmetric (conjugate gradients need it), and
/// stored in full the mirrors cost the largest scenes half their matrix traffic in every
/// product and some 300 bytes a particle (on the 256² hang scene the process peaked at
/// 181 MB instead of 197, and the product of 65 536 particles took 1.16 ms instead of
/// 1.34).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SymmetricBlockMatrix {
    /// One block per upper slot of the pattern.
    pub blocks: Vec<Mat3>,
}

/// Block `(p, q)` of an element as stored at `(min, max)`: itself on or above the
/// diagonal, transposed below it.
#[inline]
pub(crate) fn oriented(block: Mat3, p: u32, q: u32) -> Mat3 {
    if p <= q { block } else { block.transpose() }
}

impl SymmetricBlockMatrix {
    /// Zeroes the matrix and sizes it for `pattern`, in parallel: on the 256² hang scene
    /// the matrix is 24 MB, and zeroing it on one thread idled the other.
    pub fn reset(&mut self, pattern: &BlockPattern) {
        self.reset_to_identities(pattern, &[]);
    }

    /// Sizes the matrix for `pattern` and sets each stored block to `scales[slot] I`
    /// (zero past the end of `scales`), in parallel: a constant part of the matrix set in
    /// the pass that would have zeroed it.
    pub fn reset_to_identities(&mut self, pattern: &BlockPattern, scales: &[f32]) {
        let size = pattern.upper.last().expect("the pattern is laid out for a symmetric matrix (`with_upper`)");
        self.blocks.resize(*size as usize, Mat3::ZERO);
        self.blocks.par_iter_mut().with_min_len(PARALLEL_MIN_LEN).enumerate().for_each(|(slot, block)| {
            *block = scales.get(slot).map_or(Mat3::ZERO, |&s| Mat3::from_diagonal(Vec3::splat(s)));
        });
    }

    /// Adds the local blocks of an element over the particles `stencil`, those on and
    /// above its diagonal (`a ≤ b`; the rest are their transposes), at their storage
    /// `slots` ([`BlockPattern::upper_slots_at`]).
    #[inline]
    pub fn add_local<const N: usize, const M: usize>(
        &mut self,
        stencil: [u32; N],
        slots: &[u32; M],
        local: &[[Mat3; N]; N],
    ) {
        for (&slot, (a, b)) in slots.iter().zip(upper_pairs::<N>()) {
            self.blocks[slot as usize] += oriented(local[a][b], stencil[a], stencil[b]);
        }
    }

    /// Row `i`'s diagonal block.
    pub fn diagonal(&self, pattern: &BlockPattern, i: usize) -> Mat3 {
        self.blocks[pattern.upper[i] as usize]
    }

    /// Row `i`'s diagonal block, to add to.
    pub fn diagonal_mut(&mut self, pattern: &BlockPattern, i: usize) -> &mut Mat3 {
        &mut self.blocks[pattern.upper[i] as usize]
    }

    /// Adds `diagonal[i] · I` to each diagonal block.
    pub fn add_diagonal(&mut self, pattern: &BlockPattern, diagonal: impl Fn(usize) -> f32) {
        for i in 0..pattern.rows() {
            *self.diagonal_mut(pattern, i) += Mat3::from_diagonal(Vec3::splat(diagonal(i)));
        }
    }

    /// Lets `add(part, rows, blocks, first)` add to each part of the rows, between
    /// consecutive `bounds`, in parallel tasks: it gets the blocks stored for `rows`, the
    /// first of them at storage slot `first`, and must add only into those. Terms that
    /// each task adds in a fixed order keep that order, and so their sums, on any number
    /// of threads. Block `(p, q)` of an element belongs to row `min(p, q)`.
    pub fn add_by_parts(
        &mut self,
        pattern: &BlockPattern,
        bounds: &[usize],
        add: impl Fn(usize, std::ops::Range<usize>, &mut [Mat3], usize) + Sync,
    ) {
        add_by_parts(&pattern.upper, &mut self.blocks, bounds, &add);
    }

    /// [`SymmetricBlockMatrix::add_by_parts`] with `values`, one per row, cut at the same
    /// rows: `add(part, rows, blocks, first, values)` gets the part's values beside its
    /// blocks, so that one pass over the elements adds both (the forces and the blocks of
    /// an assembly).
    pub fn add_by_parts_beside<T: Send>(
        &mut self,
        pattern: &BlockPattern,
        bounds: &[usize],
        values: &mut [T],
        add: impl Fn(usize, std::ops::Range<usize>, &mut [Mat3], usize, &mut [T]) + Sync,
    ) {
        let offset = |row: usize| pattern.upper[row] as usize;
        let storages =
            (RowStorage { offset: &offset, items: &mut self.blocks }, RowStorage { offset: &|row| row, items: values });
        split_parts(storages, bounds, 0, &|part, rows, (blocks, values)| {
            let first = offset(rows.start);
            add(part, rows, blocks.items, first, values.items);
        });
    }

    /// Row `i` of the matrix times `x`: every block of the row in column order.
    #[inline]
    pub fn row_product(&self, pattern: &BlockPattern, i: usize, x: &[Vec3]) -> Vec3 {
        let mut sum = Vec3A::ZERO;
        self.for_row(pattern, i, |j, block, _| sum += times(&block, Vec3A::from(x[j as usize])));
        Vec3::from(sum)
    }

    /// Calls `visit(column, block, slot)` for every block of row `i`, columns ascending,
    /// `slot` being where the block or its mirror is stored: two plain loops, which a
    /// chained iterator's test at every block made slower.
    #[inline]
    pub fn for_row(&self, pattern: &BlockPattern, i: usize, mut visit: impl FnMut(u32, Mat3, usize)) {
        let row = pattern.symmetric_row(i);
        for (&j, &mirror) in row.below.iter().zip(row.mirrors) {
            visit(j, self.blocks[mirror as usize].transpose(), mirror as usize);
        }
        for ((&j, block), slot) in row.above.iter().zip(&self.blocks[row.storage.clone()]).zip(row.storage) {
            visit(j, *block, slot);
        }
    }

    /// `out = self · x`, each stored block read once: block `(i, j)` adds `B x_j` to row
    /// `i` and `Bᵀ x_i` to row `j`. Reading the mirrors row by row instead
    /// ([`SymmetricBlockMatrix::row_product`]) gathers them from a few hundred rows back,
    /// and took the product 40 % longer than one over every block stored (65 536
    /// particles, 1.84 ms against 1.34). The rows go in chunks of at least the pattern's
    /// [`BlockPattern::reach`], so that a chunk adds only to its own rows and the next
    /// chunk's: first every other chunk in parallel, then the rest. The chunks do not
    /// depend on the number of threads, nor, so, the sums.
    pub fn multiply(&self, pattern: &BlockPattern, x: &[Vec3], out: &mut [Vec3]) {
        let chunk = product_chunk(pattern);
        self.add_chunks(pattern, chunk, 0, x, out);
        self.add_chunks(pattern, chunk, chunk.min(out.len()), x, out);
    }

    /// One phase of [`SymmetricBlockMatrix::multiply`]: every other chunk of `chunk` rows
    /// from `start` in parallel, each adding to itself and the next with its two chunks of
    /// `x`; the first phase (from row 0), whose pairs of chunks cover every row, zeroes
    /// `out` first.
    fn add_chunks(&self, pattern: &BlockPattern, chunk: usize, start: usize, x: &[Vec3], out: &mut [Vec3]) {
        let n = out.len();
        out[start..].par_chunks_mut(2 * chunk).zip(x[start..].par_chunks(2 * chunk)).enumerate().for_each(
            |(c, (out, x))| {
                if start == 0 {
                    out.fill(Vec3::ZERO);
                }
                let first = start + 2 * c * chunk;
                self.add_rows_product(pattern, first..(first + chunk).min(n), x, out);
            },
        );
    }

    /// `out = self · x` as [`SymmetricBlockMatrix::multiply`] forms it, then
    /// `finish(first, x, out, beside)` on each run of rows from `first` as soon as their
    /// sums are whole, given those rows of `x`, `out` and `beside` to change: the pass
    /// over vectors that follows a product (a smoothing step's update, a residual) runs
    /// on rows the product has just left in the cache. A run is finished once no task
    /// still reads its rows of `x`, and runs begin at even rows, so that a pair of nodes
    /// (`2p`, `2p + 1`) is finished together. `beside` may be a vector of `()` where
    /// nothing else is kept by row. With the multigrid's smoothing updates, residuals and
    /// power iterations so finished, hang_256's solve took 54.0 to 56.3 ms a frame
    /// against 56.7 to 57.9, hang_64's 2.52 to 2.69 against 2.66 to 2.68 (alternating
    /// runs, 28 November 2026).
    pub fn multiply_then<T: Send>(
        &self,
        pattern: &BlockPattern,
        x: &mut [Vec3],
        out: &mut [Vec3],
        beside: &mut [T],
        finish: impl Fn(usize, &mut [Vec3], &mut [Vec3], &mut [T]) + Sync,
    ) {
        let (n, chunk) = (out.len(), product_chunk(pattern));
        self.add_chunks(pattern, chunk, 0, x, out);
        // Then the rest: once a chunk has added its rows, they and the next chunk's are
        // whole, and no other task reads their `x`.
        let start = chunk.min(n);
        let (x_first, x) = x.split_at_mut(start);
        let (out_first, out) = out.split_at_mut(start);
        let (beside_first, beside) = beside.split_at_mut(start);
        out.par_chunks_mut(2 * chunk)
            .zip(x.par_chunks_mut(2 * chunk))
            .zip(beside.par_chunks_mut(2 * chunk))
            .enumerate()
            .for_each(|(c, ((out, x), beside))| {
                let first = start + 2 * c * chunk;
                self.add_rows_product(pattern, first..(first + chunk).min(n), x, out);
                finish(first, x, out, beside);
            });
        // The first chunk was whole after the first phase.
        finish(0, x_first, out_first, beside_first);
    }

    /// Adds the product of `rows` with `x` into `out`, which begins at the first of them:
    /// each stored block once, `B x_j` to row `i` and `Bᵀ x_i` to row `j`. A function of its
    /// own, not inlined into rayon's task, so that where its loop lies in the code does not
    /// move with whatever else the task holds: a change elsewhere that only left three
    /// vectors unallocated took hang_64's solve from 2.24 to 2.37 ms a frame to 2.68 to
    /// 3.00, and hang_256's from 55 to 56 to 64 to 69, with the same bits (27 November
    /// 2026, alternating runs); with this loop kept apart, 2.43 to 2.46 and 57.2.
    #[inline(never)]
    fn add_rows_product(&self, pattern: &BlockPattern, rows: std::ops::Range<usize>, x: &[Vec3], out: &mut [Vec3]) {
        let first = rows.start;
        for i in rows {
            let (above, storage) = pattern.upper_row(i);
            let (blocks, xi) = (&self.blocks[storage], Vec3A::from(x[i - first]));
            // The diagonal block comes first.
            let mut sum = times(&blocks[0], xi);
            for (&j, block) in above[1..].iter().zip(&blocks[1..]) {
                let j = j as usize - first;
                sum += times(block, Vec3A::from(x[j]));
                out[j] += Vec3::from(transposed_times(block, xi));
            }
            out[i - first] += Vec3::from(sum);
        }
    }

    /// The block `(row, column)`, zero where the pattern has none.
    pub fn block(&self, pattern: &BlockPattern, row: u32, column: u32) -> Mat3 {
        pattern.upper_index(row, column).map_or(Mat3::ZERO, |s| oriented(self.blocks[s as usize], row, column))
    }
}

/// ∂f/∂v: a [`SymmetricBlockMatrix`] over the pattern where springs damp, else its
/// diagonal alone, a multiple of the identity per particle. Only damped springs fill it
/// off the diagonal, and only drag on it, `−c m I` for a particle of mass `m`: a second
/// matrix beside ∂f/∂x cost a cloth of triangles some 350 bytes a particle for zeros, and
/// a block per particle 36 (32 more than its scalar, on the 256² hang scene 2.1 MB of
/// zeros).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct VelocityJacobian {
    /// Over the pattern when `full`, else empty.
    matrix: SymmetricBlockMatrix,
    /// Unless `full`, per particle the multiple of the identity on its diagonal.
    diagonal: Vec<f32>,
    full: bool,
}

impl VelocityJacobian {
    /// Zeroes the matrix, sized for the whole `pattern` if `full`, else for its diagonal.
    pub fn reset(&mut self, pattern: &BlockPattern, full: bool) {
        self.full = full;
        if full {
            self.diagonal.clear();
            self.matrix.reset(pattern);
        } else {
            self.matrix.blocks.clear();
            self.diagonal.clear();
            self.diagonal.resize(pattern.rows(), 0.0);
        }
    }

    /// The matrix over the whole pattern, to add elements' blocks to, if reset `full`.
    pub fn full_matrix(&mut self) -> Option<&mut SymmetricBlockMatrix> {
        self.full.then_some(&mut self.matrix)
    }

    /// Adds `diagonal[i] · I` to each diagonal block.
    pub fn add_diagonal(&mut self, pattern: &BlockPattern, diagonal: impl Fn(usize) -> f32) {
        if self.full {
            return self.matrix.add_diagonal(pattern, diagonal);
        }
        for (i, scale) in self.diagonal.iter_mut().enumerate() {
            *scale += diagonal(i);
        }
    }

    /// `out = self · x`.
    pub fn multiply(&self, pattern: &BlockPattern, x: &[Vec3], out: &mut [Vec3]) {
        if self.full {
            return self.matrix.multiply(pattern, x, out);
        }
        out.par_iter_mut().zip(x.par_iter()).zip(self.diagonal.par_iter()).with_min_len(PARALLEL_MIN_LEN).for_each(
            |((out, x), scale)| {
                *out = *scale * *x;
            },
        );
    }

    /// The block `(row, column)`, zero where there is none.
    pub fn block(&self, pattern: &BlockPattern, row: u32, column: u32) -> Mat3 {
        match self.full {
            true => self.matrix.block(pattern, row, column),
            false if row == column => Mat3::from_diagonal(Vec3::splat(self.diagonal[row as usize])),
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
        matrix: &mut SymmetricBlockMatrix,
        diagonal: impl Fn(usize) -> f32 + Sync,
    ) {
        split_rows(&pattern.upper, 1, 0..pattern.rows(), &mut matrix.blocks, &|i, blocks| {
            let first = pattern.upper[i] as usize;
            // A row's first upper block is its diagonal.
            for (k, block) in blocks.iter_mut().enumerate() {
                *block = match (self.full, k == 0) {
                    (true, _) => a * self.matrix.blocks[first + k] - b * *block,
                    (false, true) => Mat3::from_diagonal(Vec3::splat(a * self.diagonal[i])) - b * *block,
                    (false, false) => -(b * *block),
                };
                if k == 0 {
                    *block += Mat3::from_diagonal(Vec3::splat(diagonal(i)));
                }
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The SIMD products add the same terms in the same order as glam's, so a step's
    /// frames keep their bits: equal to the last bit on blocks and vectors whose terms
    /// round differently in another order.
    #[test]
    fn the_simd_block_products_give_glams_bits() {
        let mut seed = 0x2545_f491_u32;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            (seed as f32 / u32::MAX as f32 - 0.5) * 10f32.powi((seed % 7) as i32 - 3)
        };
        for _ in 0..1000 {
            let a = Mat3::from_cols_array(&std::array::from_fn(|_| next()));
            let b = Mat3::from_cols_array(&std::array::from_fn(|_| next()));
            let v = Vec3::new(next(), next(), next());
            assert_eq!(
                Vec3::from(times(&a, Vec3A::from(v))).to_array().map(f32::to_bits),
                (a * v).to_array().map(f32::to_bits)
            );
            assert_eq!(
                Vec3::from(transposed_times(&a, Vec3A::from(v))).to_array().map(f32::to_bits),
                (a.transpose() * v).to_array().map(f32::to_bits)
            );
            assert_eq!(
                block_product(&a, &b).to_cols_array().map(f32::to_bits),
                (a * b).to_cols_array().map(f32::to_bits)
            );
            // A symmetric block kept by its six entries is itself, and multiplies as
            // itself whole; an unsymmetric one is kept as its symmetric part.
            let symmetric = a + a.transpose();
            let kept = SymmetricBlock::new(symmetric);
            assert_eq!(kept.matrix().to_cols_array().map(f32::to_bits), symmetric.to_cols_array().map(f32::to_bits));
            assert_eq!(
                Vec3::from(kept.times(Vec3A::from(v))).to_array().map(f32::to_bits),
                (symmetric * v).to_array().map(f32::to_bits)
            );
            let part = SymmetricBlock::new(a).matrix();
            assert!(part.abs_diff_eq(0.5 * (a + a.transpose()), 1e-6 * a.abs().to_cols_array().iter().sum::<f32>()));
        }
    }

    /// Only the blocks on and above the diagonal are stored; one below reads as its
    /// mirror transposed, in the product too, whichever order an element lists its
    /// particles in.
    #[test]
    fn a_symmetric_matrix_keeps_the_upper_blocks_and_mirrors_the_rest() {
        let pattern = BlockPattern::from_stencils(3, [&[0u32, 1][..], &[1, 2][..]]).with_upper();
        assert_eq!(pattern.offsets, vec![0, 2, 5, 7]);
        assert_eq!(pattern.columns, vec![0, 1, 0, 1, 2, 1, 2]);
        assert_eq!(pattern.slot(0, 2), None);
        // Stored: (0, 0) (0, 1) | (1, 1) (1, 2) | (2, 2); below, (1, 0) mirrors 1, (2, 1) 3.
        assert_eq!(pattern.upper, vec![0, 2, 4, 5]);
        assert_eq!(pattern.mirrors, vec![1, 3]);
        // Pairs (0, 0), (0, 1), (1, 1) of the stencil [2, 1]: (2, 2), (2, 1), (1, 1).
        assert_eq!(pattern.upper_slots([2, 1]), [4, 3, 2]);
        assert_eq!(pattern.upper_positions([2, 1]), [0, 1, 0]);
        assert_eq!(
            pattern.upper_slots_at([2, 1], &pattern.upper_positions::<2, 3>([2, 1])),
            pattern.upper_slots([2, 1])
        );
        let pairs: Vec<_> = upper_pairs::<4>().collect();
        for (k, &(a, b)) in pairs.iter().enumerate() {
            assert_eq!((upper_pair::<4>(a, b), upper_pair::<4>(b, a)), (k, k));
        }
        let b = Mat3::from_cols_array(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
        let mut m = SymmetricBlockMatrix::default();
        m.reset(&pattern);
        m.add_diagonal(&pattern, |i| i as f32 + 1.0);
        // An element over particles 2 and 1 whose block (2, 1) is b.
        m.add_local([2, 1], &pattern.upper_slots::<2, 3>([2, 1]), &[[Mat3::ZERO, b], [b.transpose(), Mat3::ZERO]]);
        assert_eq!(m.blocks.len(), 5);
        assert_eq!(m.block(&pattern, 2, 1), b);
        assert_eq!(m.block(&pattern, 1, 2), b.transpose());
        assert_eq!(m.block(&pattern, 0, 2), Mat3::ZERO);
        let mut row = Vec::new();
        m.for_row(&pattern, 2, |j, block, _| row.push((j, block)));
        assert_eq!(row, vec![(1, b), (2, 3.0 * Mat3::IDENTITY)]);
        let x = [Vec3::X, Vec3::Y, Vec3::new(1.0, -2.0, 0.5)];
        let mut out = vec![Vec3::ZERO; 3];
        m.multiply(&pattern, &x, &mut out);
        assert_eq!(out, vec![Vec3::X, 2.0 * Vec3::Y + b.transpose() * x[2], 3.0 * x[2] + b * Vec3::Y]);
    }

    /// Positions take a byte where every row's part from its diagonal on holds at most 256
    /// blocks, and two bytes once one holds more (the hub of a fan of 256 triangles), the
    /// same positions either way.
    #[test]
    fn element_positions_take_a_byte_while_every_row_is_short() {
        for spokes in [255u32, 256] {
            // A fan: particle 0 shares a triangle with each pair of its neighbours.
            let triangles: Vec<[u32; 3]> = (1..spokes).map(|k| [0, k, k + 1]).collect();
            let pattern =
                BlockPattern::from_stencils(spokes as usize + 1, triangles.iter().map(|t| &t[..])).with_upper();
            let positions = ElementPositions::<6>::new(&pattern, triangles.iter().copied());
            assert_eq!(matches!(positions, ElementPositions::Narrow(_)), spokes < 256, "{spokes} spokes");
            for (e, &t) in triangles.iter().enumerate() {
                assert_eq!(positions.get(e), pattern.upper_positions::<3, 6>(t));
            }
        }
    }

    /// The product that reads each stored block once, for both its row and its mirror's,
    /// is the row-by-row product within rounding, whether the pattern reaches less or
    /// farther than a chunk, and the same bits on one thread and on several.
    #[test]
    fn the_once_read_product_is_the_row_product_on_any_thread_count() {
        let n = 1500u32;
        let irregular = |k: u32| ((k.wrapping_mul(2_654_435_761) >> 16) % 1000) as f32 / 500.0 - 1.0;
        for far in [3, PRODUCT_CHUNK as u32 + 9] {
            let stencils: Vec<[u32; 3]> = (0..n - far).map(|i| [i + 1, i, i + far]).collect();
            let pattern = BlockPattern::from_stencils(n as usize, stencils.iter().map(|s| &s[..])).with_upper();
            assert_eq!(pattern.reach, far as usize);
            let mut m = SymmetricBlockMatrix::default();
            m.reset(&pattern);
            for (e, &stencil) in stencils.iter().enumerate() {
                let local = std::array::from_fn(|a| {
                    std::array::from_fn(|b| {
                        Mat3::from_cols_array(&std::array::from_fn(|k| irregular((e * 81 + a * 27 + b * 9 + k) as u32)))
                    })
                });
                m.add_local(stencil, &pattern.upper_slots::<3, 6>(stencil), &local);
            }
            let x: Vec<Vec3> =
                (0..n).map(|i| Vec3::new(irregular(3 * i), irregular(3 * i + 1), irregular(3 * i + 2))).collect();
            let on = |threads: usize| {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("pool");
                let mut out = vec![Vec3::ONE; n as usize];
                pool.install(|| m.multiply(&pattern, &x, &mut out));
                out
            };
            let one = on(1);
            assert_eq!(one, on(2));
            assert_eq!(one, on(3));
            for (i, product) in one.iter().enumerate() {
                let by_row = m.row_product(&pattern, i, &x);
                assert!(
                    (*product - by_row).length() <= 1e-5 * by_row.length().max(1.0),
                    "row {i}: {product} against {by_row}"
                );
            }
        }
    }

    /// Either part sees its own rows' blocks at their slots, wherever the split falls.
    #[test]
    fn parts_add_into_their_own_rows_only() {
        let pattern = BlockPattern::from_stencils(3, [&[0u32, 1][..], &[1, 2][..]]).with_upper();
        for split in 0..5 {
            let mut m = SymmetricBlockMatrix::default();
            m.reset(&pattern);
            m.add_by_parts(&pattern, &[0, split.min(3), 3], |_, rows, blocks, first| {
                for row in rows {
                    for slot in pattern.upper[row] as usize..pattern.upper[row + 1] as usize {
                        blocks[slot - first] += Mat3::from_diagonal(Vec3::splat((10 * row + slot) as f32));
                    }
                }
            });
            for row in 0..pattern.rows() {
                for slot in pattern.upper[row] as usize..pattern.upper[row + 1] as usize {
                    let expected = Mat3::from_diagonal(Vec3::splat((10 * row + slot) as f32));
                    assert_eq!(m.blocks[slot], expected, "split {split}, upper slot {slot}");
                }
            }
        }
    }

    /// With values beside the blocks, each part sees its own rows' values too, cut at the
    /// same rows, with its own part number, wherever the splits fall.
    #[test]
    fn parts_see_their_own_rows_values_beside_their_blocks() {
        let pattern = BlockPattern::from_stencils(4, [&[0u32, 1][..], &[1, 2][..], &[2, 3][..]]).with_upper();
        for bounds in [vec![0, 4], vec![0, 1, 4], vec![0, 2, 3, 4], vec![0, 1, 2, 3, 4], vec![0, 0, 4, 4]] {
            let mut m = SymmetricBlockMatrix::default();
            m.reset(&pattern);
            let mut values = vec![usize::MAX; pattern.rows()];
            m.add_by_parts_beside(&pattern, &bounds, &mut values, |part, rows, blocks, first, values| {
                assert_eq!((rows.len(), pattern.upper[rows.start] as usize), (values.len(), first));
                for (row, value) in rows.clone().zip(values.iter_mut()) {
                    *value = 100 * part + row;
                    for slot in pattern.upper[row] as usize..pattern.upper[row + 1] as usize {
                        blocks[slot - first] += Mat3::from_diagonal(Vec3::splat(slot as f32));
                    }
                }
            });
            let part_of = |row: usize| bounds.partition_point(|&b| b <= row) - 1;
            let expected: Vec<usize> = (0..pattern.rows()).map(|row| 100 * part_of(row) + row).collect();
            assert_eq!(values, expected, "bounds {bounds:?}");
            for (slot, block) in m.blocks.iter().enumerate() {
                assert_eq!(*block, Mat3::from_diagonal(Vec3::splat(slot as f32)), "bounds {bounds:?}, slot {slot}");
            }
        }
    }

    /// The diagonal-only velocity Jacobian multiplies, reads and combines as the full one
    /// holding the same diagonal does.
    #[test]
    fn a_diagonal_velocity_jacobian_acts_as_the_full_one() {
        let pattern = BlockPattern::from_stencils(3, [&[0u32, 1][..], &[1, 2][..]]).with_upper();
        let mut stiffness = SymmetricBlockMatrix::default();
        stiffness.reset(&pattern);
        stiffness.add_local(
            [0, 1],
            &pattern.upper_slots::<2, 3>([0, 1]),
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
        assert_eq!((diagonal.matrix.blocks.len(), diagonal.diagonal.len()), (0, 3));
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
