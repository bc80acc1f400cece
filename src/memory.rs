//! Giving large temporary lists back to the allocator without changing how it serves the
//! lists that follow.

/// Frees `list`, a temporary that may be large, as a block of one element: the block is
/// first shrunk in place (`realloc`), then freed.
///
/// glibc serves a block of 128 KiB or more by a mapping of its own, returned whole when
/// freed, but freeing such a block of up to 32 MiB raises that threshold to the block's
/// size, and every smaller block after it comes from the threads' arenas, where freed
/// memory stays resident and which one holds what follows rayon's scheduling. Building
/// hang_256 freed lists of up to 23 MB before its first frame, and its peak resident
/// memory was 1 063 to 1 275 bytes a particle over five runs of one binary, for a heap
/// peak of 1 023. Shrinking a mapped block remaps it (`mremap`), which leaves the
/// threshold alone, and a block of a page is below it when freed: with the build's
/// temporaries freed this way, five runs peaked at 1 048 to 1 055. Under other
/// allocators this is one `realloc` more.
pub fn release<T>(mut list: Vec<T>) {
    list.truncate(1);
    list.shrink_to(1);
}
