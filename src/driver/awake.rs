//! Keep a rayon pool's other workers awake through a step loop.
//!
//! Between two parallel regions rayon's idle workers spin only briefly (a few dozen
//! `sched_yield`s) and then sleep on a futex, so a step made of several short regions pays a
//! sleep and a wake-up (a system call and an inter-processor interrupt on the waking side) in
//! most of them; OpenMP's threads spin instead. [`KeepAwake`] parks one job on every other worker
//! of the current pool that looks for work without pause (stealing, as an idle worker would)
//! until the guard is dropped: the regions' halves are taken at once, at the price of those
//! cores running flat out while the guard lives.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;

/// While alive, every other worker of the pool it was started in busy-waits for work instead
/// of sleeping. Dropping it releases them (and waits until they have left).
pub struct KeepAwake {
    /// Shared with the waiting jobs; `None` outside a pool or in a pool of one thread.
    shared: Option<Arc<Waiting>>,
}

/// The waiting jobs' flag and count.
struct Waiting {
    /// Set by `drop`: the waiting jobs return.
    stop: AtomicBool,
    /// Waiting jobs that have not yet returned.
    left: AtomicUsize,
}

/// Idle polls of a waiting job before it also offers its core to other processes
/// (`sched_yield`) between polls: about 10 µs, so that an oversubscribed machine loses little.
const POLLS_BEFORE_YIELD: u32 = 256;

impl KeepAwake {
    /// Start waiting jobs on the current pool's other workers; a no-op (and no allocation)
    /// outside a pool or in a pool of one thread.
    pub fn start() -> Self {
        let threads = rayon::current_num_threads();
        let (Some(me), true) = (rayon::current_thread_index(), threads > 1) else {
            return KeepAwake { shared: None };
        };
        let shared = Arc::new(Waiting {
            stop: AtomicBool::new(false),
            left: AtomicUsize::new(threads - 1),
        });
        let waiting = shared.clone();
        rayon::spawn_broadcast(move |ctx| {
            if ctx.index() == me {
                return;
            }
            let mut idle = 0u32;
            while !waiting.stop.load(Ordering::Acquire) {
                if rayon::yield_now() == Some(rayon::Yield::Executed) {
                    idle = 0;
                } else if idle < POLLS_BEFORE_YIELD {
                    idle += 1;
                    std::hint::spin_loop();
                } else {
                    std::thread::yield_now();
                }
            }
            waiting.left.fetch_sub(1, Ordering::AcqRel);
        });
        KeepAwake {
            shared: Some(shared),
        }
    }
}

impl Drop for KeepAwake {
    fn drop(&mut self) {
        let Some(shared) = &self.shared else { return };
        shared.stop.store(true, Ordering::Release);
        // A waiting job whose worker was busy may not have started yet: it returns as soon as
        // it does, so this only waits for each job to see `stop`.
        while shared.left.load(Ordering::Acquire) > 0 {
            std::hint::spin_loop();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;

    /// Parallel work runs to the same result while the workers are kept awake, the guard's drop
    /// returns (every waiting job has left), and a pool of one thread is untouched.
    #[test]
    fn work_runs_and_the_guard_releases_its_workers() {
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let sum = pool.install(|| {
                let _awake = KeepAwake::start();
                (0..200)
                    .map(|_| (0..10_000u64).into_par_iter().sum::<u64>())
                    .sum::<u64>()
            });
            assert_eq!(sum, 200 * 49_995_000, "{threads} threads");
        }
    }

    /// A guard dropped before its waiting job has started (the other worker busy elsewhere)
    /// waits for that job to start and leave, and the busy work finishes: no deadlock.
    #[test]
    fn guard_dropped_before_its_job_starts() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        let done = Arc::new(AtomicBool::new(false));
        pool.install(|| {
            let flag = done.clone();
            let (left, ()) = rayon::join(
                || {
                    let guard = KeepAwake::start();
                    let left = guard.shared.as_ref().map(|w| w.left.load(Ordering::SeqCst));
                    drop(guard);
                    left
                },
                || {
                    std::thread::sleep(std::time::Duration::from_millis(30));
                    flag.store(true, Ordering::SeqCst);
                },
            );
            assert_eq!(left, Some(1), "one job waits on the other worker");
        });
        assert!(done.load(Ordering::SeqCst));
    }
}
