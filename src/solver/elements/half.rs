//! 3×3 blocks kept in bfloat16 (the upper half of an `f32`: its sign, exponent and 7
//! bits of mantissa), for matrices that need their span rather than their digits: the
//! multigrid's prolongators on its large levels ([`crate::solver::multigrid`], which
//! says why and what it measured), and [`StoredBlock`], over which a kernel reads either
//! kind of block.
//!
//! A rounded entry is within 2⁻⁸ of itself. Widening is a shift, done in SIMD registers:
//! widened entry by entry into a `Mat3` first, the Galerkin product took twice as long.

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

    /// The block's columns, widened in SIMD registers.
    #[inline]
    fn columns(&self) -> [Vec3A; 3] {
        let e = self.0.map(|half| f32::from_bits(u32::from(half) << 16));
        [Vec3A::from_slice(&e[0..3]), Vec3A::from_slice(&e[3..6]), Vec3A::from_slice(&e[6..9])]
    }
}

/// A 3×3 block as a matrix may keep it, in `f32` ([`Mat3`]) or in bfloat16
/// ([`HalfBlock`]), read widened into SIMD registers: kernels generic over it compile a
/// loop for each.
pub trait StoredBlock: Copy + Send + Sync {
    /// The block, exactly as stored.
    fn get(&self) -> Mat3A;

    /// `b v`, as [`super::block::times`] does (the same sums, so the same bits).
    #[inline]
    fn times(&self, v: Vec3A) -> Vec3A {
        let b = self.get();
        b.x_axis * v.x + b.y_axis * v.y + b.z_axis * v.z
    }

    /// `bᵀ v`, as [`super::block::transposed_times`] does.
    #[inline]
    fn transposed_times(&self, v: Vec3A) -> Vec3A {
        let t = self.get().transpose();
        t.x_axis * v.x + t.y_axis * v.y + t.z_axis * v.z
    }
}

impl StoredBlock for Mat3 {
    #[inline]
    fn get(&self) -> Mat3A {
        Mat3A::from(*self)
    }
}

impl StoredBlock for HalfBlock {
    #[inline]
    fn get(&self) -> Mat3A {
        let [x, y, z] = self.columns();
        Mat3A::from_cols(x, y, z)
    }
}

/// Row `i` of the matrix of `blocks` over `pattern` times `x`, blocks in column order.
#[inline]
pub fn row_product<B: StoredBlock>(blocks: &[B], pattern: &BlockPattern, i: usize, x: &[Vec3]) -> Vec3 {
    let mut sum = Vec3A::ZERO;
    for k in pattern.slots(i) {
        sum += blocks[k].times(Vec3A::from(x[pattern.columns[k] as usize]));
    }
    Vec3::from(sum)
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
        let back = Mat3::from(StoredBlock::get(&HalfBlock::rounded(Mat3::from_cols_array(&entries)))).to_cols_array();
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
