//! Quadratic bending kept as what it is: a constant matrix. Under Bergou et al.'s
//! isometric measure (`law: Quadratic`) the bending energy is `−½ xᵀ J x` with `J` a
//! constant multiple of the identity in every 3×3 block, so once the faces have given
//! their blocks ([`BendingSurface::quadratic_jacobian`]) nothing else of them is needed
//! in a step: not the hinges, nor the faces, nor their weights. Kept as their summed
//! scalars, particle pair by particle pair, a regular sheet's bending holds some 80 bytes
//! a particle where its faces and hinges held 284.

use glam::Vec3;

use super::bending::BendingSurface;
use super::block::upper_pairs;
use super::columns::RowColumns;
use crate::solver::reduce;

/// The constant Jacobian of a cloth's quadratic bending: `s_ii` on the diagonal and `s_ij`
/// between particles `i < j` of a face, each the multiple of the identity its block is,
/// summed over the faces in face order (so that the matrices formed from it have the bits
/// the faces' own blocks summed in that order gave).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct QuadraticBending {
    /// The warp direction the faces were built with (world frame), kept so that a tear
    /// can build them again over what it leaves.
    pub warp: Vec3,
    /// How many hinges gave these blocks.
    hinges: usize,
    /// What [`Self::energy`]'s sum makes of the rest positions: the scales' rounding
    /// (zero for exact scales, which vanish on any flat shape), taken off every energy.
    rest_energy: f64,
    /// `s_ii` of each particle.
    diagonal: Vec<f32>,
    /// Particle `i`'s pairs with higher-numbered particles are `columns` and `scales`
    /// from `offsets[i]` to `offsets[i + 1]`, columns ascending. Every pair of particles
    /// that share a face is there, even where its scales cancel: the pairs are also the
    /// couplings the cloth's pattern and ordering must know.
    offsets: Vec<u32>,
    /// Kept as offsets from their row where they fit: 9.4 a particle of a regular sheet,
    /// 19 bytes a particle less than whole indices.
    columns: RowColumns,
    scales: Vec<f32>,
}

impl QuadraticBending {
    /// The Jacobian of `surface`'s faces over the particles at rest positions `rest`, the
    /// surface's hinges carrying their
    /// [`quadratic_weights`](super::bending::quadratic_weights) there.
    pub fn assemble(rest: &[Vec3], surface: &BendingSurface<'_>, warp: Vec3) -> Self {
        let particles = rest.len();
        let mut diagonal = vec![0.0; particles];
        let mut pairs = Vec::with_capacity(15 * surface.faces.len());
        for (f, face) in surface.faces.iter().enumerate() {
            let ends = upper_pairs::<6>().map(|(a, b)| (face.vertices[a], face.vertices[b]));
            for ((p, q), scale) in ends.zip(surface.quadratic_jacobian(f)) {
                match p == q {
                    true => diagonal[p as usize] += scale,
                    false => pairs.push((p.min(q), p.max(q), scale)),
                }
            }
        }
        // Stable, so each pair's scales are summed in face order.
        pairs.sort_by_key(|&(i, j, _)| (i, j));
        pairs.dedup_by(|next, kept| {
            let same = (next.0, next.1) == (kept.0, kept.1);
            if same {
                kept.2 += next.2;
            }
            same
        });
        let mut offsets = vec![0u32; particles + 1];
        for &(i, _, _) in &pairs {
            offsets[i as usize + 1] += 1;
        }
        for r in 0..particles {
            offsets[r + 1] += offsets[r];
        }
        let scales = pairs.iter().map(|p| p.2).collect();
        let columns = RowColumns::new(&offsets, pairs.iter().map(|p| p.1).collect());
        let mut bending =
            Self { warp, hinges: surface.hinges.len(), rest_energy: 0.0, diagonal, offsets, columns, scales };
        bending.rest_energy = bending.stored(rest);
        bending
    }

    /// Whether there is no bending (no hinge).
    pub fn is_empty(&self) -> bool {
        self.hinges == 0
    }

    /// How many hinges gave these blocks.
    pub fn hinge_count(&self) -> usize {
        self.hinges
    }

    /// How many particle pairs share a face.
    pub fn pair_count(&self) -> usize {
        self.columns.len()
    }

    /// `s_ii` of each particle.
    pub fn diagonal(&self) -> &[f32] {
        &self.diagonal
    }

    /// Every pair `(i, j, s_ij)`, `i < j`, by `i` then `j`.
    pub fn pairs(&self) -> impl Iterator<Item = (u32, u32, f32)> + '_ {
        (0..self.diagonal.len()).flat_map(move |i| {
            let range = self.offsets[i] as usize..self.offsets[i + 1] as usize;
            self.columns.row(i, range.clone()).zip(&self.scales[range]).map(move |(j, &s)| (i as u32, j, s))
        })
    }

    /// Energy at positions `x` [J]: `−½ xᵀ J x = ½ Σ_{i<j} s_ij |x_i − x_j|²`, since the
    /// blocks of a row sum to zero, less the same sum at rest, which exact scales make
    /// zero. Taken off, it leaves of the scales' rounding only what multiplies the change
    /// of each `|x_i − x_j|²` from rest: a flat cloth moved rigidly stores nothing (a
    /// 10⁻⁴ part of a 1 cm bend of a 20 cm patch without it), and a bend, which hardly
    /// stretches, the faces' own energy within 10⁻⁵. The differences are taken in double
    /// precision, exact for single-precision positions, so a cloth far from the origin
    /// stores what it stores at it.
    pub fn energy(&self, x: &[Vec3]) -> f64 {
        self.stored(x) - self.rest_energy
    }

    /// `½ Σ_{i<j} s_ij |x_i − x_j|²` [J].
    fn stored(&self, x: &[Vec3]) -> f64 {
        0.5 * reduce::sum(self.diagonal.len(), |i| {
            let range = self.offsets[i] as usize..self.offsets[i + 1] as usize;
            let xi = x[i].as_dvec3();
            self.columns
                .row(i, range.clone())
                .zip(&self.scales[range])
                .map(|(j, &s)| f64::from(s) * (xi - x[j as usize].as_dvec3()).length_squared())
                .sum()
        })
    }
}
