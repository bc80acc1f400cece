//! Parallel reductions whose result does not depend on the number of threads.
//!
//! A rayon `sum()` of floating-point terms adds them in an order set by how the work was
//! split among the threads, so a probe would differ in its last bits between one and two
//! threads. Here the range is halved down to fixed leaves whatever the thread count, each
//! leaf is folded in index order and the halves are combined in a fixed tree: the same
//! additions in the same order on any number of threads, and nothing allocated.

use std::ops::Range;

/// Indices a leaf folds serially: enough that a leaf outweighs the task that runs it.
const LEAF: usize = 2048;

/// Folds `leaf` over `range` split into fixed halves down to [`LEAF`] indices, combining
/// the halves with `combine` (left, right), in parallel.
pub fn reduce<T: Send>(
    range: Range<usize>,
    leaf: &(impl Fn(Range<usize>) -> T + Sync),
    combine: &(impl Fn(T, T) -> T + Sync),
) -> T {
    if range.len() <= LEAF {
        return leaf(range);
    }
    let middle = range.start + range.len() / 2;
    let (left, right) =
        rayon::join(|| reduce(range.start..middle, leaf, combine), || reduce(middle..range.end, leaf, combine));
    combine(left, right)
}

/// `Σ term(i)` over `0..n` in double precision, in parallel, the same on any number of
/// threads.
pub fn sum(n: usize, term: impl Fn(usize) -> f64 + Sync) -> f64 {
    reduce(0..n, &|range: Range<usize>| range.map(&term).sum::<f64>(), &|a, b| a + b)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Terms whose sum depends on the order of addition (large and tiny alternating):
    /// the parallel sum is the fixed tree's on one thread and on several, and equals the
    /// serial sum where the range is one leaf.
    #[test]
    fn sums_do_not_depend_on_the_thread_count() {
        let term = |i: usize| if i.is_multiple_of(2) { 1e16 * (i % 7) as f64 } else { 0.1 * i as f64 };
        let n = 50 * LEAF + 17;
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("pool");
            pool.install(|| sum(n, term))
        };
        let one = on(1);
        assert_eq!(one.to_bits(), on(2).to_bits());
        assert_eq!(one.to_bits(), on(3).to_bits());
        let exact: f64 = (0..n).map(term).sum();
        assert!((one - exact).abs() <= 1e-12 * exact, "{one} against {exact}");
        assert_eq!(sum(LEAF, term).to_bits(), (0..LEAF).map(term).sum::<f64>().to_bits());
    }

    /// A reduction that keeps the first index of the largest value finds it wherever it
    /// falls among the leaves.
    #[test]
    fn reductions_combine_every_leaf() {
        let values: Vec<u32> = (0..10 * LEAF as u32 + 3).map(|i| i.wrapping_mul(2_654_435_761) >> 20).collect();
        let largest = |range: Range<usize>| range.map(|i| (values[i], std::cmp::Reverse(i))).max();
        let found = reduce(0..values.len(), &largest, &|a, b| a.max(b)).expect("values");
        let expected = values.iter().enumerate().max_by_key(|&(i, v)| (*v, std::cmp::Reverse(i))).expect("values");
        assert_eq!((found.0, found.1.0), (*expected.1, expected.0));
    }
}
