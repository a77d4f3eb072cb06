//! One complete time step of each engine (criterion): the spectral SBDF1 step (four real
//! transforms, the fused pointwise passes and the area projection) and the FD explicit-Euler
//! step, on full periodic boxes of 64³ and 128³ and on the eighth box, 1 and 2 threads.
//! Compare with `benches/fft.rs` (the transforms alone) and DESIGN.md §3's C/FFTW figures
//! (3.7 ms at 64³, 49 ms at 128³, one thread).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use serde_json::json;
use vesicle::config;
use vesicle::engine::Engine;
use vesicle::setup;
use vesicle::simulation::Simulation;

/// A prepared engine for a prolate (v = 0.85, R0 = n/4) on an n³ box.
fn engine(method: &str, n: usize, symmetry: serde_json::Value) -> Box<dyn Engine + Send> {
    let scene = config::from_value(json!({
        "dim": 3, "n": [n, n, n], "h": 1.0, "eps": 1.0, "method": method,
        "dt": if method == "fd" { 4e-4 } else { 0.5 }, "max_steps": 1,
        "initial": {"shape": "spheroid", "reduced_volume": 0.85, "r0": n as f64 / 4.0},
        "symmetry": symmetry
    }))
    .expect("scene");
    let problem = setup::build(&scene).expect("problem");
    Simulation::of_scene(&scene, &problem)
        .expect("engine")
        .0
        .into_engine()
}

fn bench_steps(c: &mut Criterion) {
    let mut group = c.benchmark_group("step");
    for (method, dt) in [("spectral", 0.5), ("fd", 4e-4)] {
        for n in [64usize, 128] {
            if n == 128 {
                group.sample_size(10);
            }
            for threads in [1, 2] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .expect("thread pool");
                let mut e = pool.install(|| engine(method, n, json!([])));
                let mut t = 0.0;
                let id = BenchmarkId::new(format!("{method}/full"), format!("{n}^3/t{threads}"));
                group.bench_function(id, |b| {
                    b.iter(|| {
                        pool.install(|| {
                            e.step(t, dt).expect("step");
                            t += dt;
                        })
                    })
                });
            }
        }
        let mut e = engine(method, 64, json!(["x", "y", "z"]));
        let mut t = 0.0;
        group.bench_function(
            BenchmarkId::new(format!("{method}/eighth"), "64^3/t2"),
            |b| {
                b.iter(|| {
                    e.step(t, dt).expect("step");
                    t += dt;
                })
            },
        );
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench_steps
}
criterion_main!(benches);
