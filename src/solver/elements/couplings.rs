//! Couplings beside a block matrix: constant multiples of the identity between particles
//! its pattern leaves out, kept as scalars (the quadratic bending's across an edge).

use glam::{Mat3, Vec3, Vec3A};
use rayon::prelude::*;

use crate::solver::PARALLEL_MIN_LEN;
use crate::solver::multigrid::scalar_lump;

/// Couplings of a cloth's particles outside its block pattern that are a multiple of the
/// identity and constant: the quadratic bending's across an edge, whose Jacobian there is
/// `s I`. Kept as scalars, 8 bytes where a block of ∂f/∂x and of the system took 36 (a
/// third of a regular sheet's blocks), and products over them take 3 operations where a
/// block took 18; found once per topology. The system's pattern is then the multigrid's
/// finest level's, and what its lumping would move onto the diagonal from them is known
/// ahead (`lumps`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ConstantCouplings {
    /// Particle `i`'s couplings are `columns` and `scales` from `offsets[i]` to
    /// `offsets[i + 1]`, columns ascending, and both directions of a pair with the same
    /// scale.
    offsets: Vec<u32>,
    columns: Vec<u32>,
    scales: Vec<f32>,
    /// Per particle, what the multigrid's lumping moves onto its diagonal from the
    /// system's blocks `−w s I` per unit stiffness weight `w`, as a multiple of `I`
    /// ([`scalar_lump`]).
    lumps: Vec<f32>,
}

impl ConstantCouplings {
    /// The couplings of `rows` particles from `entries` `(i, j, s)`, `i ≠ j`, each pair
    /// in both directions: those of one pair summed in the order given.
    pub fn new(rows: usize, mut entries: Vec<(u32, u32, f32)>) -> Self {
        entries.sort_by_key(|&(i, j, _)| (i, j));
        let mut couplings = Self { offsets: Vec::with_capacity(rows + 1), ..Self::default() };
        let distinct = entries.windows(2).filter(|w| (w[0].0, w[0].1) != (w[1].0, w[1].1)).count() + 1;
        couplings.columns.reserve_exact(distinct);
        couplings.scales.reserve_exact(distinct);
        couplings.offsets.push(0);
        let mut next = entries.iter().peekable();
        for i in 0..rows as u32 {
            while let Some(&(_, j, s)) = next.next_if(|entry| entry.0 == i) {
                match couplings.columns.last() {
                    Some(&last) if last == j && couplings.columns.len() > couplings.offsets[i as usize] as usize => {
                        *couplings.scales.last_mut().expect("a column has its scale") += s;
                    }
                    _ => {
                        couplings.columns.push(j);
                        couplings.scales.push(s);
                    }
                }
            }
            couplings.offsets.push(couplings.columns.len() as u32);
        }
        couplings.lumps = (0..rows)
            .into_par_iter()
            .with_min_len(PARALLEL_MIN_LEN)
            .map(|i| couplings.row(i).fold(0.0, |moved, (_, s)| moved + scalar_lump(s)))
            .collect();
        couplings
    }

    /// Particle `i`'s couplings, `(j, s)`, columns ascending.
    pub fn row(&self, i: usize) -> impl Iterator<Item = (u32, f32)> + '_ {
        let range = self.offsets[i] as usize..self.offsets[i + 1] as usize;
        self.columns[range.clone()].iter().copied().zip(self.scales[range].iter().copied())
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
    /// Row `i` of these blocks times `x`: `weight Σ_j s_ij x_j`.
    #[inline]
    pub fn row_product(&self, i: usize, x: &[Vec3]) -> Vec3 {
        let sum = self.couplings.row(i).fold(Vec3A::ZERO, |sum, (j, s)| sum + s * Vec3A::from(x[j as usize]));
        self.weight * Vec3::from(sum)
    }

    /// Calls `visit(j, block)` for each of row `i`'s blocks, columns ascending.
    pub fn for_row(&self, i: usize, mut visit: impl FnMut(u32, Mat3)) {
        for (j, s) in self.couplings.row(i) {
            visit(j, Mat3::from_diagonal(Vec3::splat(self.weight * s)));
        }
    }

    /// What the multigrid's lumping moves onto row `i`'s diagonal from these blocks, as a
    /// multiple of `I`, given their weight is the system's `−w`.
    #[inline]
    pub(crate) fn lump(&self, i: usize) -> f32 {
        -self.weight * self.couplings.lumps[i]
    }
}
