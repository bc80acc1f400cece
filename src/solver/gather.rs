//! Parallel gathering of variable-length lists (contact candidates, contacts, impacts)
//! into buffers kept from step to step: once they have grown to their working size a
//! step gathers without allocating, and the items come out in index order on any number
//! of threads. (A rayon `filter_map(..).collect()` allocates per thread and per step.)

use rayon::prelude::*;

/// Indices one task visits: large enough that a task outweighs its scheduling, small
/// enough that uneven work (dense contact regions) still spreads over the threads.
const CHUNK: usize = 256;

/// The per-chunk buffers of a parallel gather.
#[derive(Debug, Clone)]
pub struct Gather<T> {
    chunks: Vec<Vec<T>>,
}

impl<T> Default for Gather<T> {
    fn default() -> Self {
        Self { chunks: Vec::new() }
    }
}

impl<T: Copy + Send + Sync> Gather<T> {
    /// Calls `visit(i, out)` for every `i` in `0..n`, in parallel over chunks of indices,
    /// and leaves in `into` everything the visits pushed onto `out`, in order of `i` (and
    /// of pushing). A visit may reorder what it pushed itself (`out[start..]`).
    pub fn run(&mut self, n: usize, into: &mut Vec<T>, visit: impl Fn(usize, &mut Vec<T>) + Sync) {
        let count = n.div_ceil(CHUNK);
        if self.chunks.len() < count {
            self.chunks.resize_with(count, Vec::new);
        }
        self.chunks[..count].par_iter_mut().enumerate().for_each(|(chunk, out)| {
            out.clear();
            for i in chunk * CHUNK..((chunk + 1) * CHUNK).min(n) {
                visit(i, out);
            }
        });
        into.clear();
        for chunk in &self.chunks[..count] {
            into.extend_from_slice(chunk);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gathers_in_index_order_and_reuses_its_buffers() {
        let mut gather = Gather::default();
        let mut out = Vec::new();
        // Each i pushes i copies of itself: 0, 1, 2, 2, 3, 3, 3, …
        let visit = |i: usize, out: &mut Vec<usize>| out.extend(std::iter::repeat_n(i, i % 5));
        gather.run(1000, &mut out, visit);
        let expected: Vec<usize> = (0..1000).flat_map(|i| std::iter::repeat_n(i, i % 5)).collect();
        assert_eq!(out, expected);
        let capacity: Vec<usize> = gather.chunks.iter().map(Vec::capacity).collect();
        gather.run(1000, &mut out, visit);
        assert_eq!(out, expected);
        assert_eq!(gather.chunks.iter().map(Vec::capacity).collect::<Vec<_>>(), capacity, "no chunk grew");
        gather.run(0, &mut out, visit);
        assert!(out.is_empty());
    }
}
