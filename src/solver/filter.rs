//! Baraff & Witkin's constraint filters `S`, one per particle: the identity for a free
//! particle, zero for a pinned or sticking one, `I − n nᵀ` for one held on a contact
//! normal `n`. The implicit step's solvers apply them to every residual and product.
//!
//! Nearly every particle of a cloth is free, so only the others keep a 3 × 3 block: each
//! particle has a 4-byte index, [`FREE`] or its block's. Kept as a block per particle, the
//! filters were 36 bytes a particle, read (with a matrix–vector product) by each of the
//! conjugate gradients' passes that filter and by the multigrid's finest residuals and
//! corrections, some six times an iteration.

use glam::{Mat3, Vec3};

/// The index of a free particle, which has no block.
const FREE: u32 = u32::MAX;

/// The filter of every particle of a system.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Filters {
    /// Per particle, [`FREE`] or the index of its block in `blocks`.
    index: Vec<u32>,
    /// The blocks of the particles that are not free.
    blocks: Vec<Mat3>,
}

impl Filters {
    /// `n` particles, all free.
    pub fn free(n: usize) -> Self {
        let mut filters = Filters::default();
        filters.reset(n, |_| true);
        filters
    }

    /// Makes the filters those of `n` particles, each free where `free` says so and pinned
    /// (zero) otherwise, keeping the storage.
    pub fn reset(&mut self, n: usize, free: impl Fn(usize) -> bool) {
        self.index.clear();
        self.blocks.clear();
        for i in 0..n {
            let index = if free(i) {
                FREE
            } else {
                self.blocks.push(Mat3::ZERO);
                (self.blocks.len() - 1) as u32
            };
            self.index.push(index);
        }
    }

    /// Makes room for `constrained` more particles to be restricted ([`Filters::constrain`])
    /// at once, rather than by doubling as contact begins.
    pub fn reserve(&mut self, constrained: usize) {
        self.blocks.reserve(constrained);
    }

    /// Restricts particle `i` further: its filter becomes `projection · S_i`.
    pub fn constrain(&mut self, i: usize, projection: Mat3) {
        let filtered = projection * self.block(i);
        match self.index[i] {
            FREE => {
                self.index[i] = self.blocks.len() as u32;
                self.blocks.push(filtered);
            }
            k => self.blocks[k as usize] = filtered,
        }
    }

    /// Pins particle `i`: its filter becomes zero.
    pub fn pin(&mut self, i: usize) {
        self.constrain(i, Mat3::ZERO);
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.index.len()
    }

    /// Whether there are no particles.
    pub fn is_empty(&self) -> bool {
        self.index.is_empty()
    }

    /// Whether particle `i` is free (its filter the identity).
    #[inline]
    pub fn is_free(&self, i: usize) -> bool {
        self.index[i] == FREE
    }

    /// Whether particle `i` is pinned (its filter zero): the solve leaves it where its
    /// prescribed part puts it.
    pub fn is_pinned(&self, i: usize) -> bool {
        self.index[i] != FREE && self.blocks[self.index[i] as usize] == Mat3::ZERO
    }

    /// Particle `i`'s Jacobi step for the diagonal block `diagonal`, `(S D S + I − S)⁻¹ S`
    /// ([`filtered_inverse`]), without products with the identity where it is free.
    #[inline]
    pub fn inverse(&self, i: usize, diagonal: Mat3) -> Mat3 {
        match self.index[i] {
            FREE => free_inverse(diagonal),
            k => filtered_inverse(self.blocks[k as usize], diagonal),
        }
    }

    /// Particle `i`'s filter as a block.
    #[inline]
    pub fn block(&self, i: usize) -> Mat3 {
        match self.index[i] {
            FREE => Mat3::IDENTITY,
            k => self.blocks[k as usize],
        }
    }

    /// `S_i v`.
    #[inline]
    pub fn apply(&self, i: usize, v: Vec3) -> Vec3 {
        match self.index[i] {
            FREE => v,
            k => self.blocks[k as usize] * v,
        }
    }
}

/// `(S D S + I − S)⁻¹ S`, for a node with diagonal block `D` and filter `S`: its Jacobi
/// (or Newton) step, which stays within the filter. A one stands in for any empty diagonal
/// entry (a coarse rotation the multigrid dropped from an aggregate's frame leaves an empty
/// row and column); zero where the block is singular still.
pub fn filtered_inverse(s: Mat3, diagonal: Mat3) -> Mat3 {
    free_inverse(s * diagonal * s + (Mat3::IDENTITY - s)) * s
}

/// [`filtered_inverse`] of a free node, whose filter is the identity: `D⁻¹`, a one standing
/// in for any empty diagonal entry, zero where singular still. The same bits as with the
/// identity's products, which on hang_256's 65 536 particles were most of the finest
/// smoother's inverses (1.44 ms a frame).
pub fn free_inverse(mut diagonal: Mat3) -> Mat3 {
    let empty = Vec3::new(diagonal.x_axis.x, diagonal.y_axis.y, diagonal.z_axis.z).cmpeq(Vec3::ZERO);
    diagonal += Mat3::from_diagonal(Vec3::select(empty, Vec3::ONE, Vec3::ZERO));
    if diagonal.determinant().abs() > 0.0 { diagonal.inverse() } else { Mat3::ZERO }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn filters_act_as_their_blocks() {
        let normal = Vec3::new(0.6, 0.8, 0.0);
        let tangent = Mat3::IDENTITY - Mat3::from_cols(normal * normal.x, normal * normal.y, normal * normal.z);
        let mut filters = Filters::free(4);
        filters.pin(1);
        filters.constrain(2, tangent);
        filters.constrain(1, tangent);
        let v = Vec3::new(1.0, -2.0, 3.0);
        assert_eq!(filters.apply(0, v), v);
        assert_eq!(filters.apply(1, v), Vec3::ZERO);
        assert!(filters.apply(2, v).dot(normal).abs() < 1e-6);
        assert!((filters.apply(2, v) - (v - v.dot(normal) * normal)).length() < 1e-6);
        assert!(filters.is_free(3) && !filters.is_free(2));
        assert_eq!(filters.block(0), Mat3::IDENTITY);
        assert_eq!(filters.block(1), Mat3::ZERO);
        for i in 0..4 {
            assert_eq!(filters.apply(i, v), filters.block(i) * v);
        }
    }
}
