//! The time-step loop allocates nothing (an engine makes its FFT plans and scratch buffers once,
//! when it is built: docs/src/performance.md, "Memory"): after a warm-up, steps of the spectral
//! engine (SBDF1 and SBDF2, fixed and adaptive Δt, with the projection and a c0 field; the
//! Stokes dynamics on the periodic box and on the eighth box, whose spectra are packed), of the
//! FD engine and of the L-BFGS relaxation make zero heap allocations. On one thread: with several, rayon's work-stealing deques now and then grow
//! on their own (seen: 2 allocations in 10 steps, once in 15 runs), which is not our code.
//! One test in its own binary, so no other test allocates meanwhile.

mod common;
use common::scene;
use serde_json::json;
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};
use vesicle::driver::simulation::{Simulation, StopRules};
use vesicle::problem::setup;

struct CountingAlloc;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: every call goes on to the system allocator unchanged, so its memory and layouts are
// the system allocator's; counting allocates nothing and cannot unwind.
unsafe impl GlobalAlloc for CountingAlloc {
    /// # Safety
    /// As for [`GlobalAlloc::alloc`].
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: the caller's `layout`, as `GlobalAlloc::alloc` requires.
        unsafe { System.alloc(layout) }
    }
    /// # Safety
    /// As for [`GlobalAlloc::dealloc`].
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` was allocated by `alloc` above, that is by `System`, with `layout`.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: CountingAlloc = CountingAlloc;

#[test]
fn step_loop_allocates_nothing() {
    for threads in [1] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        for extra in [
            json!({"method": "spectral", "scheme": "sbdf1", "dt": 0.5}),
            json!({"method": "spectral", "scheme": "sbdf2", "dt": 0.5}),
            json!({"method": "spectral", "scheme": "sbdf2", "dt": 0.1, "adaptive": {"dt_max": 5.0}}),
            json!({"method": "fd", "dt": 4e-4}),
            json!({"method": "spectral", "dynamics": "relaxational", "dt": 1.0}),
            json!({"method": "spectral", "scheme": "sbdf2", "dt": 0.5, "dynamics": "stokes",
                   "flow": {"viscosity": 1.0, "mobility": 0.01}}),
            json!({"method": "spectral", "scheme": "sbdf2", "dt": 0.5, "dynamics": "stokes",
                   "flow": {"viscosity": 1.0, "mobility": 0.01}, "symmetry": ["x", "y", "z"]}),
        ] {
            let mut v = json!({
                "dim": 3, "n": [24, 24, 24], "max_steps": 1,
                "initial": {"shape": "spheroid", "reduced_volume": 0.9, "r0": 6.0},
                "c0": {"inside": 0.2, "radius": 4.0}
            });
            v.as_object_mut()
                .unwrap()
                .extend(extra.as_object().unwrap().clone());
            let s = scene(v);
            pool.install(|| {
                let problem = setup::build(&s).unwrap();
                let (mut sim, _) = Simulation::of_scene(&s, &problem).unwrap();
                // Warm-up: SBDF2 keeps its previous state, L-BFGS fills its memory (5 pairs).
                sim.run(&StopRules::steps(8), &mut []).unwrap();
                let before = ALLOCATIONS.load(Ordering::SeqCst);
                sim.run(&StopRules::steps(18), &mut []).unwrap();
                let made = ALLOCATIONS.load(Ordering::SeqCst) - before;
                assert_eq!(
                    made, 0,
                    "{threads} thread(s), {extra}: {made} allocations in 10 steps"
                );
            });
        }
    }
}
