//! Parallel gathering of variable-length lists (contact candidates, contacts, impacts)
//! into buffers kept from step to step: once they have grown to their working size a
//! step gathers without allocating, and the items come out in index order on any number
//! of threads. (A rayon `filter_map(..).collect()` allocates per thread and per step.)

use rayon::prelude::*;

/// Indices one task visits: large enough that a task outweighs its scheduling, small
/// enough that uneven work (dense contact regions) still spreads over the threads.
const CHUNK: usize = 256;

/// Items a gathered list makes room for when it first takes one, and a chunk's buffer
/// ([`CHUNK_FLOOR`]). A `Vec` starts at four and doubles, so a list that grows from
/// nothing to a few dozen items reallocates four or five times: contact starting in a warm
/// frame, or moving into chunks that had none, allocated in frames long after the warm-up
/// (34 times in frames 31 to 60 of the draped sheet of `tests/allocation.rs` over its 20
/// solvers, all here or in the self-contact springs' list). A few kilobytes a list.
pub const FLOOR: usize = 64;

/// A chunk's floor, smaller than a list's: a gather over the candidate pairs has a chunk
/// for every [`CHUNK`] of them, most holding a few contacts or none, and their floors add
/// up; 16 is what the draped sheet's contacts needed to start without reallocating.
const CHUNK_FLOOR: usize = 16;

/// Makes room for `additional` more items in `list`, and at least [`FLOOR`] in all.
pub fn reserve_floored<T>(list: &mut Vec<T>, additional: usize) {
    list.reserve(additional.max(FLOOR.saturating_sub(list.len())));
}

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
        // One chunk even for no indices, so that the first run makes the room a list
        // that starts to grow in a later step (contact beginning) finds there.
        let count = n.div_ceil(CHUNK).max(1);
        if self.chunks.len() < count {
            let missing = count - self.chunks.len();
            reserve_floored(&mut self.chunks, missing);
            self.chunks.resize_with(count, || Vec::with_capacity(CHUNK_FLOOR));
        }
        self.chunks[..count].par_iter_mut().enumerate().for_each(|(chunk, out)| {
            out.clear();
            for i in chunk * CHUNK..((chunk + 1) * CHUNK).min(n) {
                visit(i, out);
            }
        });
        into.clear();
        let total = self.chunks[..count].iter().map(Vec::len).sum();
        reserve_floored(into, total);
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

    #[test]
    fn contact_starting_after_an_empty_first_run_finds_room() {
        let mut gather = Gather::default();
        let mut out: Vec<u32> = Vec::new();
        // The first runs gather nothing (no contact yet) over no indices, then over some.
        gather.run(0, &mut out, |_, _| {});
        gather.run(600, &mut out, |_, _| {});
        let room = |gather: &Gather<u32>, out: &Vec<u32>| {
            (gather.chunks.iter().map(|c| c.as_ptr()).collect::<Vec<_>>(), out.as_ptr(), out.capacity())
        };
        let before = room(&gather, &out);
        // Then contact starts: the chunk floor in each of the three chunks, within the
        // list's floor in all.
        gather.run(600, &mut out, |i, out| {
            if i % CHUNK < CHUNK_FLOOR {
                out.push(i as u32);
            }
        });
        assert!(out.len() == 3 * CHUNK_FLOOR && out.len() <= FLOOR);
        assert_eq!(room(&gather, &out), before, "no buffer moved or grew");
    }
}
