//! 3×3 blocks kept in bfloat16 (the upper half of an `f32`: its sign, exponent and 7
//! bits of mantissa), for matrices that need their span rather than their digits: the
//! multigrid's prolongators ([`crate::solver::multigrid`]).
//!
//! A prolongator is a basis of the coarse space. Rounded, each entry within 2⁻⁸ of
//! itself, it is another basis, and since the Galerkin product, the restriction and the
//! prolongation all use the rounded one, the V-cycle stays symmetric and positive
//! definite. What the rounding adds to a coarse motion is rough, which the smoother
//! damps: over the hang bench scenes' 40 first frames the solves took 299, 334 and 470
//! iterations at 64², 128² and 256² against 301, 334 and 463 unrounded.
//!
//! The finest prolongator is the largest array of the levels (3.75 blocks a particle on
//! the 256² sheet) and a V-cycle reads it twice, restricting and prolongating. Halved,
//! hang_256's heap peaked at 84.1 MB against 89.1 over 20 frames, and its solve took
//! 57.4 and 61.3 ms a frame against 61.4 and 66.4 (whole benches, alternating). Widening
//! is a shift, done in SIMD registers: widened entry by entry into a `Mat3` first, the
//! Galerkin product took twice as long.

use glam::{Mat3, Mat3A, Vec3, Vec3A};

use super::block::BlockPattern;

/// A 3×3 block in bfloat16, column-major as [`Mat3::to_cols_array`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct HalfBlock([u16; 9]);

impl HalfBlock {
    /// `block` rounded to the nearest bfloat16 entry by entry, ties to even; a NaN stays
    /// a NaN.
    #[inline]
    pub fn rounded(block: Mat3) -> Self {
        Self(block.to_cols_array().map(|entry| {
            let bits = entry.to_bits();
            let nearest = (bits.wrapping_add(0x7fff + ((bits >> 16) & 1)) >> 16) as u16;
            // A NaN's payload may be in the dropped bits alone: keep it quiet instead.
            if entry.is_nan() { (bits >> 16) as u16 | 0x40 } else { nearest }
        }))
    }

    /// The block, exactly as stored, widened in SIMD registers.
    #[inline]
    pub fn get(&self) -> Mat3A {
        let [x, y, z] = self.columns();
        Mat3A::from_cols(x, y, z)
    }

    /// `a b`, as [`super::block::block_product`] does for two `f32` blocks.
    #[inline]
    pub fn after(&self, a: &Mat3) -> Mat3 {
        Mat3::from(Mat3A::from(*a) * self.get())
    }

    /// The block's columns, widened in SIMD registers.
    #[inline]
    pub fn columns(&self) -> [Vec3A; 3] {
        let e = self.0.map(|half| f32::from_bits(u32::from(half) << 16));
        [Vec3A::from_slice(&e[0..3]), Vec3A::from_slice(&e[3..6]), Vec3A::from_slice(&e[6..9])]
    }

    /// `b v`, as [`super::block::times`] does for an `f32` block.
    #[inline]
    pub fn times(&self, v: Vec3A) -> Vec3A {
        let [x, y, z] = self.columns();
        x * v.x + y * v.y + z * v.z
    }

    /// `bᵀ v`, as [`super::block::transposed_times`] does for an `f32` block.
    #[inline]
    pub fn transposed_times(&self, v: Vec3A) -> Vec3A {
        let t = self.get().transpose();
        t.x_axis * v.x + t.y_axis * v.y + t.z_axis * v.z
    }
}

/// A matrix of [`HalfBlock`]s over a [`BlockPattern`], every block stored (both
/// triangles, where it has them), so that a product is a gather over rows.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct HalfBlockMatrix {
    /// One block per pattern slot.
    pub blocks: Vec<HalfBlock>,
}

impl HalfBlockMatrix {
    /// Row `i` of the matrix times `x`, blocks in column order.
    #[inline]
    pub fn row_product(&self, pattern: &BlockPattern, i: usize, x: &[Vec3]) -> Vec3 {
        let mut sum = Vec3A::ZERO;
        for k in pattern.slots(i) {
            sum += self.blocks[k].times(Vec3A::from(x[pattern.columns[k] as usize]));
        }
        Vec3::from(sum)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_block_rounds_to_the_nearest_bfloat16_ties_to_even() {
        // 1 + 2⁻⁸ lies halfway between 1 and 1 + 2⁻⁷: to the even mantissa, 1; 1 + 3·2⁻⁸
        // lies halfway between 1 + 2⁻⁷ and 1 + 2⁻⁶: to 1 + 2⁻⁶.
        let ties = [1.0 + 2f32.powi(-8), 1.0 + 3.0 * 2f32.powi(-8)];
        let exact = [0.0, -0.0, 1.0, -2.5, 0.375, 2f32.powi(-60), -3.0 * 2f32.powi(50)];
        let mut entries = [0.0f32; 9];
        entries[..2].copy_from_slice(&ties);
        entries[2..].copy_from_slice(&exact);
        let back = Mat3::from(HalfBlock::rounded(Mat3::from_cols_array(&entries)).get()).to_cols_array();
        assert_eq!(back[..2], [1.0, 1.0 + 2f32.powi(-6)]);
        assert_eq!(back[2..].iter().map(|v| v.to_bits()).collect::<Vec<_>>(), exact.map(f32::to_bits));
        let special = HalfBlock::rounded(Mat3::from_cols_array(&[
            f32::NAN,
            f32::INFINITY,
            f32::MIN_POSITIVE,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
        ]))
        .get();
        assert!(special.x_axis.x.is_nan());
        assert_eq!(special.x_axis.y, f32::INFINITY);
        assert_eq!(special.x_axis.z, f32::MIN_POSITIVE);
    }

    #[test]
    fn a_rounded_entry_is_within_half_a_unit_in_the_last_of_eight_bits() {
        // Entries spread over twelve decades, both signs: each comes back within 2⁻⁸ of
        // itself (half a unit in the last place of 8 significant bits, at the bottom of
        // its binade), and a second rounding changes nothing.
        let mut worst = 0.0f32;
        for k in 0..2000 {
            let value = (-1.0f32).powi(k) * 10f32.powf(-6.0 + 12.0 * ((k as f32 * 0.618_034).fract()));
            let block = HalfBlock::rounded(Mat3::from_diagonal(Vec3::splat(value)));
            let back = block.get().x_axis.x;
            worst = worst.max(((back - value) / value).abs());
            assert_eq!(HalfBlock::rounded(block.get().into()), block);
        }
        assert!(worst <= 2f32.powi(-8) && worst > 2f32.powi(-9), "worst relative error {worst}");
    }
}
