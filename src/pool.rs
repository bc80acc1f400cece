//! Rayon's pool kept awake through a frame.
//!
//! A frame starts a few hundred parallel loops (hang_64: some thirty a conjugate-gradient
//! iteration, down the V-cycle's levels), most of them tens of microseconds long, with
//! stretches of one thread between them (a level of a few dozen nodes, the coarsest
//! solve, a system of the schedule that runs alone). A rayon worker that finds no work
//! yields some thirty times and then sleeps; the next loop wakes it through the kernel,
//! and on the project's virtual machines the wake-up took longer than many a loop. While
//! a frame runs, [`run_awake`] keeps the pool's other workers looking for work without
//! sleeping, as OpenMP's active wait policy does.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// A worker that has found no work for this long goes back to rayon's own idling (and
/// sleep) for the rest of the frame: longer than nearly every stretch of one thread in
/// the bench scenes (a worker gave up in 7 of hang_256's 120 frames and 16 of fold_64's
/// 180), so that the workers stay awake through their frames, and short enough that a
/// worker that took up a keep-awake task while it waited inside another loop (possible
/// where several simulations share the pool) is held up by no more than this.
const IDLE_LIMIT: Duration = Duration::from_millis(2);

/// Runs `work` on a worker of rayon's pool while the pool's other workers keep looking
/// for work instead of sleeping: each spins in a task of its own, running whatever it
/// steals, until `work` is done or it has found nothing for [`IDLE_LIMIT`]. `work` runs on
/// a worker even where this is called from outside the pool. The results do not depend on
/// the workers' spinning: which worker runs a task never changes what the task computes.
pub fn run_awake<R: Send>(work: impl FnOnce() -> R + Send) -> R {
    let done = AtomicBool::new(false);
    // The scope moves the work onto a worker where it is called from outside the pool.
    rayon::scope(|_| with_spinners(rayon::current_num_threads() - 1, &done, work))
}

/// Runs `work` beside `count` keep-awake tasks, each the second half of a `rayon::join`:
/// a task on the stack, where a spawned one would allocate in every frame.
fn with_spinners<R: Send>(count: usize, done: &AtomicBool, work: impl FnOnce() -> R + Send) -> R {
    if count == 0 {
        // Set even if `work` panics: the join waits for its other half before it passes
        // the panic on.
        let _done = SetOnDrop(done);
        return work();
    }
    rayon::join(|| with_spinners(count - 1, done, work), || stay_awake(done)).0
}

/// Runs whatever this worker can steal until `done`, or until it has found nothing for
/// [`IDLE_LIMIT`].
fn stay_awake(done: &AtomicBool) {
    let mut idle_since = Instant::now();
    while !done.load(Ordering::Acquire) {
        match rayon::yield_now() {
            Some(rayon::Yield::Executed) => idle_since = Instant::now(),
            Some(rayon::Yield::Idle) if idle_since.elapsed() < IDLE_LIMIT => std::hint::spin_loop(),
            _ => return,
        }
    }
}

/// Sets its flag when dropped.
struct SetOnDrop<'a>(&'a AtomicBool);

impl Drop for SetOnDrop<'_> {
    fn drop(&mut self) {
        self.0.store(true, Ordering::Release);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;

    /// The work's result comes back, its parallel loops run, and the keep-awake tasks
    /// stop whether the work returns or panics (else the join would wait for ever).
    #[test]
    fn the_work_runs_and_the_workers_stop_spinning_after_it() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().expect("pool");
        let sum = pool.install(|| run_awake(|| (0..10_000u64).into_par_iter().sum::<u64>()));
        assert_eq!(sum, 49_995_000);
        let worker = run_awake(rayon::current_thread_index);
        assert!(worker.is_some(), "called from outside the pool, the work runs on a worker");
        let panicked = pool.install(|| std::panic::catch_unwind(|| run_awake(|| panic!("the work failed"))));
        assert!(panicked.is_err(), "the panic comes through");
        assert_eq!(pool.install(|| run_awake(|| 7)), 7, "the pool still works");
    }
}
