//! Couplings beside a block matrix: constant multiples of the identity between particles
//! its pattern leaves out, kept as scalars (the quadratic bending's across an edge).

use glam::{Mat3, Vec3, Vec3A};
use rayon::prelude::*;

use super::columns::RowColumns;
use crate::solver::PARALLEL_MIN_LEN;
use crate::solver::multigrid::scalar_lump;

/// Couplings of a cloth's particles outside its block pattern that are a multiple of the
/// identity and constant: the quadratic bending's across an edge, whose Jacobian there is
/// `s I`. Kept as scalars, 6 bytes where their columns fit 16-bit offsets (8 where not)
/// where a block of ∂f/∂x and of the system took 36 (a third of a regular sheet's
/// blocks), and products over them take 3 operations where a block took 18; found once
/// per topology. The system's pattern is then the multigrid's finest level's, and what
/// its lumping would move onto the diagonal from them is known ahead (`lumps`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ConstantCouplings {
    /// Particle `i`'s couplings are its columns and `scales` from `offsets[i]` to
    /// `offsets[i + 1]`, columns ascending, and both directions of a pair with the same
    /// scale.
    offsets: Vec<u32>,
    /// The columns, kept as offsets from their row where they fit (11.9 a row of a
    /// regular sheet, 24 bytes a particle less than whole indices).
    columns: RowColumns,
    scales: Vec<f32>,
    /// Per particle, what the multigrid's lumping moves onto its diagonal from the
    /// system's blocks `−w s I` per unit stiffness weight `w`, as a multiple of `I`
    /// ([`scalar_lump`]).
    lumps: Vec<f32>,
}

impl ConstantCouplings {
    /// The couplings of `rows` particles from the distinct pairs `(i, j, s)`, `i < j`, that
    /// `pairs()` gives sorted by `i` then `j`, each kept in both directions. Walked twice,
    /// to count each row's couplings and then to place them: row `r` takes its pairs with
    /// smaller particles while the walk is on them, in their order, and then its own, so
    /// its columns come out ascending with no list of both directions sorted. That list
    /// (12 bytes an entry) and its sort's scratch, freed in the first frame, had left
    /// their memory to the allocator: peak resident 1 381 to 1 431 bytes a particle of
    /// hang_256 against 1 522 to 1 575 with them, hang_64 1 735 to 1 760 against 1 867 to
    /// 1 895 (`bench --quick`, alternating).
    pub fn new<I: Iterator<Item = (u32, u32, f32)>>(rows: usize, pairs: impl Fn() -> I) -> Self {
        let mut offsets = vec![0u32; rows + 1];
        for (i, j, _) in pairs() {
            offsets[i as usize + 1] += 1;
            offsets[j as usize + 1] += 1;
        }
        for r in 0..rows {
            offsets[r + 1] += offsets[r];
        }
        let total = offsets[rows] as usize;
        let (mut columns, mut scales) = (vec![0; total], vec![0.0; total]);
        let mut next = offsets[..rows].to_vec();
        for (i, j, s) in pairs() {
            debug_assert!(i < j, "pairs are given once, the smaller particle first");
            for (row, column) in [(i, j), (j, i)] {
                let at = &mut next[row as usize];
                (columns[*at as usize], scales[*at as usize]) = (column, s);
                *at += 1;
            }
        }
        let columns = RowColumns::new(&offsets, columns);
        let mut couplings = Self { offsets, columns, scales, lumps: Vec::new() };
        couplings.lumps = (0..rows)
            .into_par_iter()
            .with_min_len(PARALLEL_MIN_LEN)
            .map(|i| couplings.fold(i, 0.0, |moved, _, s| moved + scalar_lump(s)))
            .collect();
        couplings
    }

    /// `f(…f(init, j, s)…)` over particle `i`'s couplings `(j, s)`, columns ascending, in
    /// a loop over plain slices ([`RowColumns::fold`]): the one walk of a row, for the
    /// products and every other visit.
    #[inline(always)]
    pub fn fold<T>(&self, i: usize, init: T, f: impl FnMut(T, u32, f32) -> T) -> T {
        let range = self.offsets[i] as usize..self.offsets[i + 1] as usize;
        self.columns.fold(i, range.clone(), &self.scales[range], init, f)
    }

    /// Whether these are couplings of `rows` particles.
    pub fn has_rows(&self, rows: usize) -> bool {
        self.lumps.len() == rows
    }

    /// These couplings at `weight`.
    pub fn weighted(&self, weight: f32) -> WeightedCouplings<'_> {
        WeightedCouplings { couplings: self, weight }
    }
}

/// [`ConstantCouplings`] in a matrix: the blocks `weight s I`, weight 1 in ∂f/∂x and
/// `−w` in the system, `w` its stiffness weight `hβ + h²θ²`.
#[derive(Debug, Clone, Copy)]
pub struct WeightedCouplings<'a> {
    couplings: &'a ConstantCouplings,
    weight: f32,
}

impl WeightedCouplings<'_> {
    /// Row `i` of these blocks times `x`: `weight Σ_j s_ij x_j`. Always inlined, with the
    /// folds under it: left to itself the compiler called it once a row in the conjugate
    /// gradients' curvature pass, its result through the stack, and hang_64's solve took
    /// 2.27 to 2.29 ms a frame against 2.08 to 2.19 (alternating runs, same bits).
    #[inline(always)]
    pub fn row_product(&self, i: usize, x: &[Vec3]) -> Vec3 {
        let sum = self.couplings.fold(i, Vec3A::ZERO, |sum, j, s| sum + s * Vec3A::from(x[j as usize]));
        self.weight * Vec3::from(sum)
    }

    /// Calls `visit(j, block)` for each of row `i`'s blocks, columns ascending.
    pub fn for_row(&self, i: usize, mut visit: impl FnMut(u32, Mat3)) {
        self.couplings.fold(i, (), |(), j, s| visit(j, Mat3::from_diagonal(Vec3::splat(self.weight * s))));
    }

    /// What the multigrid's lumping moves onto row `i`'s diagonal from these blocks, as a
    /// multiple of `I`, given their weight is the system's `−w`.
    #[inline]
    pub(crate) fn lump(&self, i: usize) -> f32 {
        -self.weight * self.couplings.lumps[i]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The couplings of `rows` particles from `pairs`, and every row as it reads back.
    fn rows_of(rows: usize, pairs: &[(u32, u32, f32)]) -> (ConstantCouplings, Vec<Vec<(u32, f32)>>) {
        let couplings = ConstantCouplings::new(rows, || pairs.iter().copied());
        let read = (0..rows)
            .map(|i| {
                couplings.fold(i, Vec::new(), |mut row, j, s| {
                    row.push((j, s));
                    row
                })
            })
            .collect();
        (couplings, read)
    }

    /// Columns within 16 bits of their row are kept as offsets, the others whole; either
    /// way each row reads back its couplings in both directions, columns ascending, and
    /// its product is `Σ s x_j`.
    #[test]
    fn rows_read_back_the_same_whether_kept_as_offsets_or_whole() {
        let n = 40_000;
        let near = [(0, 2, 0.5), (2, 5, -1.5), (1, 32_767, 2.0)];
        let (couplings, read) = rows_of(n, &near);
        assert!(couplings.columns.as_offsets(), "kept as offsets");
        let far = [(0, 2, 0.5), (2, 5, -1.5), (1, 39_999, 2.0)];
        let (whole, far_read) = rows_of(n, &far);
        assert!(!whole.columns.as_offsets(), "kept whole");
        for (pairs, read) in [(&near, &read), (&far, &far_read)] {
            let mut expected = vec![Vec::new(); n];
            for &(i, j, s) in pairs {
                expected[i as usize].push((j, s));
                expected[j as usize].push((i, s));
            }
            for row in &mut expected {
                row.sort_by_key(|&(j, _)| j);
            }
            assert_eq!(read, &expected);
        }
        let x: Vec<Vec3> = (0..n).map(|i| Vec3::new(i as f32, 1.0, -2.0)).collect();
        let product = whole.weighted(2.0).row_product(2, &x);
        assert_eq!(product, 2.0 * (0.5 * x[0] - 1.5 * x[5]));
    }
}
