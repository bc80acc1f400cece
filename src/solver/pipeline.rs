//! Serial sums overlapped with parallel work: chunks of terms are computed in parallel
//! into one half of a buffer while the chunk before is added, serially and in order, from
//! the other half. Sums that must not depend on the number of threads (a Galerkin product
//! scattered from fine rows) keep their one order, and
//! the additions run beside the work instead of after it, in a buffer of two chunks.

/// For each chunk `c` in `0..count`: `compute(c, half)` fills a half of `buffer` (it may
/// run in parallel within), then `add(c, half)` consumes it, while `compute(c + 1, ..)`
/// fills the other half. `buffer` is sized to two halves of `half_len` items; what it
/// holds before `compute` writes is left from earlier use.
pub fn pipelined<T: Copy + Default + Send + Sync>(
    count: usize,
    buffer: &mut Vec<T>,
    half_len: usize,
    compute: impl Fn(usize, &mut [T]) + Sync,
    mut add: impl FnMut(usize, &[T]) + Send,
) {
    buffer.resize(2 * half_len, T::default());
    let (mut ready, mut next) = buffer.split_at_mut(half_len);
    if count > 0 {
        compute(0, ready);
    }
    for chunk in 0..count {
        rayon::join(
            || add(chunk, ready),
            || {
                if chunk + 1 < count {
                    compute(chunk + 1, next);
                }
            },
        );
        std::mem::swap(&mut ready, &mut next);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every chunk is added once, in order, with what was computed for it.
    #[test]
    fn chunks_are_added_in_order_with_their_own_terms() {
        let mut buffer = vec![0usize; 6];
        let mut seen = Vec::new();
        pipelined(
            5,
            &mut buffer,
            3,
            |c, half| half.iter_mut().enumerate().for_each(|(k, x)| *x = 10 * c + k),
            |c, half| seen.push((c, half.to_vec())),
        );
        let expected: Vec<_> = (0..5).map(|c| (c, vec![10 * c, 10 * c + 1, 10 * c + 2])).collect();
        assert_eq!(seen, expected);
    }
}
