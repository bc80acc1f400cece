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
use crate::memory::release;
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
    ///
    /// Each face's blocks between two particles go to the row of the lower one, in face
    /// order (counted, then placed: a counting sort), and each row is sorted by column,
    /// stably, and summed pair by pair, so each pair's scales add in face order. (Sorted
    /// whole, the list of pairs and the sort's scratch were 35 MB on hang_256 freed at
    /// once, which raised glibc's mmap threshold: [`release`].)
    pub fn assemble(rest: &[Vec3], surface: &BendingSurface<'_>, warp: Vec3) -> Self {
        let particles = rest.len();
        let ends = |f: usize| {
            let vertices = surface.faces[f].vertices;
            upper_pairs::<6>().map(move |(a, b)| (vertices[a], vertices[b]))
        };
        let mut offsets = vec![0u32; particles + 1];
        for f in 0..surface.faces.len() {
            for (p, q) in ends(f).filter(|(p, q)| p != q) {
                offsets[p.min(q) as usize + 1] += 1;
            }
        }
        for r in 0..particles {
            offsets[r + 1] += offsets[r];
        }
        // While placing, `offsets[r]` is where row `r`'s next pair goes; once placed, where
        // row `r + 1` starts.
        let mut diagonal = vec![0.0; particles];
        let mut pairs = vec![(0u32, 0.0f32); offsets[particles] as usize];
        for f in 0..surface.faces.len() {
            for ((p, q), scale) in ends(f).zip(surface.quadratic_jacobian(f)) {
                if p == q {
                    diagonal[p as usize] += scale;
                } else {
                    let next = &mut offsets[p.min(q) as usize];
                    pairs[*next as usize] = (p.max(q), scale);
                    *next += 1;
                }
            }
        }
        for r in (1..particles).rev() {
            offsets[r] = offsets[r - 1];
        }
        if let Some(first) = offsets.first_mut() {
            *first = 0;
        }
        // Each row by column, stably (a row's few dozen pairs sort in a buffer on the
        // stack), its pairs summed into one, moved down over the ones merged.
        let mut kept = 0;
        for r in 0..particles {
            let (start, end) = (offsets[r] as usize, offsets[r + 1] as usize);
            offsets[r] = kept as u32;
            pairs[start..end].sort_by_key(|&(column, _)| column);
            for k in start..end {
                let (column, scale) = pairs[k];
                if kept > offsets[r] as usize && pairs[kept - 1].0 == column {
                    pairs[kept - 1].1 += scale;
                } else {
                    pairs[kept] = (column, scale);
                    kept += 1;
                }
            }
        }
        offsets[particles] = kept as u32;
        pairs.truncate(kept);
        let scales = pairs.iter().map(|p| p.1).collect();
        let columns = RowColumns::new(&offsets, pairs.iter().map(|p| p.0).collect());
        release(pairs);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builders::surface::build_bending;
    use crate::components::{BendingDesc, BendingLawDesc};
    use crate::solver::elements::bending::quadratic_weights;

    /// Each pair's scale is its faces' blocks summed in face order, to the bit: the same as
    /// sorting every face's blocks by pair, stably, and summing each pair's run. On a
    /// flat sheet whose particles are jittered within its plane, so that the faces give
    /// each pair scales of their own.
    #[test]
    fn each_pair_sums_its_faces_blocks_in_face_order() {
        let n = 7u32;
        // Knuth's multiplicative hash: fixed, irregular numbers in [0, 1).
        let scatter = |k: u32| (k.wrapping_mul(2_654_435_761) >> 8) as f32 / (1u32 << 24) as f32;
        let x: Vec<Vec3> = (0..n * n)
            .map(|p| {
                0.01 * Vec3::new((p % n) as f32 + 0.3 * scatter(2 * p), (p / n) as f32 + 0.3 * scatter(2 * p + 1), 0.0)
            })
            .collect();
        let triangles: Vec<[u32; 3]> = (0..n - 1)
            .flat_map(|i| (0..n - 1).map(move |j| (i * n + j, i * n + j + 1, (i + 1) * n + j)))
            .flat_map(|(a, b, c)| [[a, b, c], [b, c + 1, c]])
            .collect();
        let desc = BendingDesc { warp: 1e-5, weft: 3e-5, twist: None, law: BendingLawDesc::Linear };
        let hinges = build_bending(&x, &triangles, &desc, Vec3::X).expect("a flat sheet of proper triangles");
        let weights: Vec<[f32; 4]> = hinges
            .vertices
            .iter()
            .map(|h| quadratic_weights(h.map(|v| x[v as usize])).expect("proper triangles"))
            .collect();
        let surface = BendingSurface { quadratic: &weights, ..hinges.view() };
        let bending = QuadraticBending::assemble(&x, &surface, Vec3::X);

        let (mut diagonal, mut pairs) = (vec![0.0f32; x.len()], Vec::new());
        for (f, face) in surface.faces.iter().enumerate() {
            for ((a, b), scale) in upper_pairs::<6>().zip(surface.quadratic_jacobian(f)) {
                let (p, q) = (face.vertices[a], face.vertices[b]);
                if p == q {
                    diagonal[p as usize] += scale;
                } else {
                    pairs.push((p.min(q), p.max(q), scale));
                }
            }
        }
        pairs.sort_by_key(|&(i, j, _)| (i, j));
        pairs.dedup_by(|next, kept| {
            let same = (next.0, next.1) == (kept.0, kept.1);
            if same {
                kept.2 += next.2;
            }
            same
        });
        assert!(pairs.len() > 100, "{} pairs", pairs.len());
        assert_eq!(bending.diagonal(), diagonal.as_slice());
        assert_eq!(bending.pairs().collect::<Vec<_>>(), pairs);
    }
}
