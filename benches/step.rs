//! One complete time step of each engine (criterion): the spectral SBDF1 step (four real
//! transforms, the fused sweeps and the area projection; `spectral_unconstrained`: the area not
//! held, σ = 0, as the C floor `fft_limit` times its step) and the FD explicit-Euler step, on
//! full periodic boxes of 64³ and 128³ and on the eighth box, 1 and 2 threads; and one L-BFGS
//! iteration of the relaxational engine against one conserved step on the 48³ prolate of the
//! route to stationary shapes (docs/src/performance.md); and the Stokes dynamics' step beside
//! the conserved one (docs/src/theory/flow.md). Compare with `benches/fft.rs` (the
//! transforms alone) and with the C floors timed in the same session (`benches/floors.sh`;
//! docs/src/performance.md, "One step against a C floor").

use criterion::measurement::WallTime;
use criterion::{criterion_group, criterion_main, BenchmarkGroup, BenchmarkId, Criterion};
use serde_json::json;
use std::time::{Duration, Instant};
use vesicle::driver::awake::KeepAwake;
use vesicle::driver::simulation::Simulation;
use vesicle::engines::Engine;
use vesicle::problem::config;
use vesicle::problem::setup;

/// One benched step: its name, the scene's `method`, `area` and `dt`, and whether the eighth box
/// is benched too.
struct Variant {
    name: &'static str,
    method: &'static str,
    area: serde_json::Value,
    dt: f64,
    eighth: bool,
}

/// A prepared engine of `v` for a prolate (v = 0.85, R0 = n/4) on an n³ box, for `threads`.
fn engine(
    v: &Variant,
    n: usize,
    symmetry: serde_json::Value,
    threads: usize,
) -> Box<dyn Engine + Send> {
    engine_of(json!({
        "dim": 3, "n": [n, n, n], "h": 1.0, "eps": 1.0, "method": v.method, "dt": v.dt,
        "max_steps": 1, "threads": threads,
        "initial": {"shape": "spheroid", "reduced_volume": 0.85, "r0": n as f64 / 4.0},
        "symmetry": symmetry, "area": v.area
    }))
}

/// The engine of a scene given as JSON.
fn engine_of(scene: serde_json::Value) -> Box<dyn Engine + Send> {
    let scene = config::from_value(scene).expect("scene");
    let problem = setup::build(&scene).expect("problem");
    Simulation::of_scene(&scene, &problem)
        .expect("engine")
        .0
        .into_engine()
}

/// Time `steps` of an engine made by `make` in a pool of `threads`. The timing loop runs inside
/// the pool with the other workers kept awake, as `vesicle run`'s step loop does (the whole run
/// is one `install`): installing each step from outside would add two thread wake-ups per
/// step, which the program never pays.
fn time_steps(
    group: &mut BenchmarkGroup<WallTime>,
    id: BenchmarkId,
    threads: usize,
    make: impl FnOnce() -> Box<dyn Engine + Send> + Send,
    dt: f64,
) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool");
    let mut e = pool.install(make);
    let mut t = 0.0;
    group.bench_function(id, |b| {
        pool.install(|| {
            let _awake = KeepAwake::start();
            b.iter(|| {
                e.step(t, dt).expect("step");
                t += dt;
            })
        })
    });
}

fn bench_steps(c: &mut Criterion) {
    let mut group = c.benchmark_group("step");
    // The spectral step with the exact area projection (its default), the same with the area
    // not held (σ = 0, no quadratic sweep; A still summed) as `fft_limit` times its step, and
    // the FD step (the Lagrangian area update, its default).
    let variant = |name, method, area, dt, eighth| Variant {
        name,
        method,
        area,
        dt,
        eighth,
    };
    for v in [
        variant("spectral", "spectral", json!({}), 0.5, true),
        variant(
            "spectral_unconstrained",
            "spectral",
            json!({"method": "none"}),
            0.5,
            false,
        ),
        variant("fd", "fd", json!({}), 4e-4, true),
    ] {
        let name = v.name;
        for n in [64usize, 128] {
            group.sample_size(if n == 128 { 10 } else { 100 });
            for threads in [1, 2] {
                let id = BenchmarkId::new(format!("{name}/full"), format!("{n}^3/t{threads}"));
                let make = || engine(&v, n, json!([]), threads);
                time_steps(&mut group, id, threads, make, v.dt);
            }
        }
        group.sample_size(100);
        if !v.eighth {
            continue;
        }
        // 32³ computed points: `vesicle run` takes one thread below 2¹⁷ (`cli::SERIAL_BELOW`).
        for threads in [1, 2] {
            let id = BenchmarkId::new(format!("{name}/eighth"), format!("64^3/t{threads}"));
            let make = || engine(&v, 64, json!(["x", "y", "z"]), threads);
            time_steps(&mut group, id, threads, make, v.dt);
        }
    }
    group.finish();
}

/// The 48³ full-box prolate of the route to stationary shapes (`runs/prolate3d_full.json`,
/// docs/src/performance.md) with `dynamics`, for `threads`.
fn prolate48(dynamics: &str, threads: usize) -> Box<dyn Engine + Send> {
    let mut scene = json!({
        "dim": 3, "n": [48, 48, 48], "h": 1.0, "eps": 1.0, "method": "spectral",
        "dynamics": dynamics, "dt": 0.5, "max_steps": 1, "threads": threads,
        "initial": {"shape": "ellipsoid", "axes": [17.0, 10.0, 10.0]}
    });
    if dynamics == "relaxational" {
        scene["dt"] = json!(1.0);
    }
    engine_of(scene)
}

/// One L-BFGS iteration and one conserved SBDF1 step on the 48³ prolate. Every timed
/// iteration is one of iterations 10 to 39 of a fresh relaxation (the memory full, the line
/// search past its start-up), so the figure does not drift as the shape converges.
fn bench_relaxation(c: &mut Criterion) {
    let mut group = c.benchmark_group("relax");
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool");
        let fresh = || {
            let mut e = prolate48("relaxational", threads);
            (0..10).for_each(|i| {
                e.step(i as f64, 1.0).expect("iteration");
            });
            e
        };
        let mut e = pool.install(fresh);
        let mut taken = 0;
        let id = BenchmarkId::new("lbfgs_iteration", format!("48^3/t{threads}"));
        group.bench_function(id, |b| {
            b.iter_custom(|iters| {
                pool.install(|| {
                    let _awake = KeepAwake::start();
                    let mut total = Duration::ZERO;
                    for _ in 0..iters {
                        if taken == 30 {
                            e = fresh();
                            taken = 0;
                        }
                        let start = Instant::now();
                        e.step(0.0, 1.0).expect("iteration");
                        total += start.elapsed();
                        taken += 1;
                    }
                    total
                })
            })
        });
        let id = BenchmarkId::new("conserved_step", format!("48^3/t{threads}"));
        time_steps(
            &mut group,
            id,
            threads,
            || prolate48("conserved", threads),
            0.5,
        );
    }
    group.finish();
}

/// The Stokes dynamics' step (docs/src/theory/flow.md: the conserved step plus 3d + 2
/// transforms of the flow at a fixed tension, 5d + 4 with the area held) beside the conserved
/// step, SBDF2 on the same full periodic boxes (a quasi-sphere on 64³, a quasi-circle on 512²),
/// 1 and 2 threads: at fixed tension (`conserved`, `stokes`) and with the area held by the
/// projection (`conserved_area`, `stokes_area`); the two with the area held also on the
/// mirror-reduced boxes (`…/half`: mirrored about x; `…/quarter`: x and y; `…/eighth`: x, y
/// and z, 3D), for the cost per point against the full box.
fn bench_stokes(c: &mut Criterion) {
    let mut group = c.benchmark_group("stokes");
    for (dim, n, radius) in [(3usize, 64usize, 16.0), (2, 512, 128.0)] {
        for (name, dynamics, area) in [
            (
                "conserved",
                "conserved",
                json!({"method": "fixed", "sigma": 0.01}),
            ),
            (
                "stokes",
                "stokes",
                json!({"method": "fixed", "sigma": 0.01}),
            ),
            (
                "conserved_area",
                "conserved",
                json!({"method": "projection"}),
            ),
            ("stokes_area", "stokes", json!({"method": "projection"})),
        ] {
            let reduced: &[(&str, &[&str])] = match (area["method"] == "projection", dim) {
                (false, _) => &[],
                (true, 2) => &[("half", &["x"]), ("quarter", &["x", "y"])],
                (true, _) => &[
                    ("half", &["x"]),
                    ("quarter", &["x", "y"]),
                    ("eighth", &["x", "y", "z"]),
                ],
            };
            let boxes = std::iter::once((name.to_string(), &[][..]))
                .chain(reduced.iter().map(|&(b, m)| (format!("{name}/{b}"), m)));
            for (label, mirror) in boxes {
                for threads in [1, 2] {
                    let id = BenchmarkId::new(&label, format!("{n}^{dim}/t{threads}"));
                    let make = || {
                        engine_of(json!({
                            "dim": dim, "n": vec![n; dim], "h": 1.0, "eps": 1.0,
                            "scheme": "sbdf2", "dt": 1.0, "max_steps": 1, "threads": threads,
                            "dynamics": dynamics, "symmetry": mirror,
                            "flow": if dynamics == "stokes" {
                                json!({"viscosity": 1.0, "mobility": 0.01})
                            } else {
                                serde_json::Value::Null
                            },
                            "area": area,
                            "initial": {"shape": "harmonic", "radius": radius, "mode": 2,
                                        "amplitude": 0.02}
                        }))
                    };
                    time_steps(&mut group, id, threads, make, 1.0);
                }
            }
        }
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench_steps, bench_relaxation, bench_stokes
}
criterion_main!(benches);
