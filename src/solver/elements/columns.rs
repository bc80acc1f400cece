//! The column lists of sparse rows whose columns lie near their row, as a cloth's
//! bandwidth-reducing ordering leaves a sheet's couplings: kept as 16-bit offsets from the
//! row, half the bytes of whole indices.

use std::ops::Range;

use crate::memory::release;

/// Each row's columns, the rows' lists one after another (where each begins is kept
/// beside, by the owner): as offsets `j − i` from row `i` where every one fits 16 bits,
/// else as whole indices. On the 256² hang scene the quadratic bending's couplings lie
/// within 2 × 256 + 2 rows of their row; a mesh its ordering could not narrow, or a
/// torn cloth's new particles, keep whole indices.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RowColumns {
    /// The offsets, where all fit; else empty.
    near: Vec<i16>,
    /// The indices, where some offset does not fit; else empty.
    wide: Vec<u32>,
}

impl RowColumns {
    /// The `columns` of rows whose lists begin at `offsets` (one more than there are
    /// rows; the last is the total).
    pub fn new(offsets: &[u32], columns: Vec<u32>) -> Self {
        let rows = offsets.len().saturating_sub(1);
        let range = |r: usize| offsets[r] as usize..offsets[r + 1] as usize;
        let offset = |r: usize, c: u32| i16::try_from(i64::from(c) - r as i64);
        if !(0..rows).all(|r| columns[range(r)].iter().all(|&c| offset(r, c).is_ok())) {
            return Self { near: Vec::new(), wide: columns };
        }
        let mut near = Vec::with_capacity(columns.len());
        for r in 0..rows {
            near.extend(columns[range(r)].iter().map(|&c| offset(r, c).expect("checked to fit")));
        }
        release(columns);
        Self { near, wide: Vec::new() }
    }

    /// How many columns all the rows hold.
    pub fn len(&self) -> usize {
        self.near.len() + self.wide.len()
    }

    /// Whether no row holds a column.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The columns of row `row`, which lie at `range` of the lists.
    #[inline]
    pub fn row(&self, row: usize, range: Range<usize>) -> impl Iterator<Item = u32> + '_ {
        // One of the two is empty.
        let near = self.near.get(range.clone()).unwrap_or_default();
        let wide = self.wide.get(range).unwrap_or_default();
        near.iter().map(move |&d| (row as i64 + i64::from(d)) as u32).chain(wide.iter().copied())
    }

    /// `f(…f(f(init, c₀, w₀), c₁, w₁)…)` over the columns `c` of row `row` (at `range`
    /// of the lists) and the `with` kept beside them in the same order: the same sum as
    /// over [`RowColumns::row`] zipped with them, in a loop over two plain slices. Through
    /// the chained iterator, hang_64's products with the quadratic bending's couplings
    /// (the conjugate gradients' curvature pass) took 217 to 234 µs a frame; so, 167 to
    /// 175 (same bits).
    #[inline(always)]
    pub fn fold<W: Copy, T>(
        &self,
        row: usize,
        range: Range<usize>,
        with: &[W],
        init: T,
        mut f: impl FnMut(T, u32, W) -> T,
    ) -> T {
        if self.wide.is_empty() {
            let near = &self.near[range];
            near.iter().zip(with).fold(init, |sum, (&d, &w)| f(sum, (row as i64 + i64::from(d)) as u32, w))
        } else {
            self.wide[range].iter().zip(with).fold(init, |sum, (&c, &w)| f(sum, c, w))
        }
    }

    /// Whether the columns are kept as offsets.
    #[cfg(test)]
    pub fn as_offsets(&self) -> bool {
        self.wide.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Columns within 16 bits of their row are kept as offsets, the others whole, and
    /// either way each row reads back its own.
    #[test]
    fn rows_read_back_their_columns_kept_as_offsets_or_whole() {
        let offsets = [0, 2, 3, 3, 5];
        for (columns, offsets_kept) in [
            (vec![1, 32_767, 0, 0, 40_000], false),
            (vec![1, 32_767, 0, 0, 32_770], true),
            (vec![1, 32_768, 0, 0, 3], false),
        ] {
            let kept = RowColumns::new(&offsets, columns.clone());
            assert_eq!(kept.as_offsets(), offsets_kept, "{columns:?}");
            assert_eq!(kept.len(), 5);
            let read: Vec<u32> =
                (0..4).flat_map(|r| kept.row(r, offsets[r] as usize..offsets[r + 1] as usize)).collect();
            assert_eq!(read, columns);
        }
    }
}
