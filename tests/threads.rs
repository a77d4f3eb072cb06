//! Results against the thread count: the same run on 1, 2 and 3 threads gives the same bits,
//! in φ and in every measured column (F, A, V, σ), for every engine.
//!
//! Why it holds: every sum over the box is a sum of partials of fixed pieces of the data
//! (chunks, groups of rows, spectral tasks), combined over a binary tree whose shape depends
//! only on their number (`engines::numerics::sum_in_fixed_tree`), or, where each thread owns a
//! slab (the FD sweep's planes, the fused transform's slabs), kept per plane or slab and added
//! in index order. Rayon's plain `reduce`/`sum` stop splitting where the pool runs out of
//! threads and would add in another order on each thread count (measured before the change:
//! FD φ apart by 3e-18–2e-15 after 10–20 steps, every engine's F, A, V in the last bits). The
//! transforms compute each line alike whatever the split.

use serde_json::{json, Value};
use std::path::Path;
use std::process::Command;
use tempfile::TempDir;

/// `vesicle ARGS`, asserting success.
fn vesicle(args: &[&str]) {
    let o = Command::new(env!("CARGO_BIN_EXE_vesicle"))
        .args(args)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// φ of the run in `out`: the payload of its `phi_final.npy` as f64.
fn phi_of(out: &Path) -> Vec<f64> {
    let bytes = std::fs::read(out.join("phi_final.npy")).unwrap();
    let header = 10 + u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    bytes[header..]
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
        .collect()
}

/// φ and the CSV rows (columns F, A, V, σ as numbers) of `scene` run for `steps` steps on
/// `threads` threads.
fn run(dir: &Path, scene: &Value, steps: usize, threads: usize) -> (Vec<f64>, Vec<Vec<f64>>) {
    let spec = dir.join("s.json");
    std::fs::write(&spec, scene.to_string()).unwrap();
    let out = dir.join(format!("t{threads}"));
    vesicle(&[
        "run",
        spec.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--set",
        &format!("max_steps={steps}"),
        "--set",
        &format!("threads={threads}"),
    ]);
    let phi = phi_of(&out);
    let csv = std::fs::read_to_string(out.join("timeseries.csv")).unwrap();
    let rows = csv
        .lines()
        .skip(1)
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            [3, 4, 5, 8]
                .iter()
                .map(|&i| c[i].parse().unwrap())
                .collect()
        })
        .collect();
    (phi, rows)
}

/// A 48³ ellipsoid (full box or mirrored on every axis) with the engine settings of `extra`:
/// large enough that every reduction has several pieces (the computed box is 13 824 points
/// even when mirrored, against 8 192 a chunk) and 3 threads split its 48 or 24 planes unevenly.
fn ellipsoid(extra: Value, mirrored: bool) -> Value {
    let mut v = json!({
        "dim": 3, "n": [48, 48, 48], "dt": 0.5,
        "initial": {"shape": "ellipsoid", "axes": [15.0, 10.5, 9.0]},
        "c0": 0.1, "prepare_steps": 5,
        "output": {"record_every": 1, "png": false, "vti": false}
    });
    v.as_object_mut()
        .unwrap()
        .extend(extra.as_object().unwrap().clone());
    if mirrored {
        v["symmetry"] = json!(["x", "y", "z"]);
    }
    v
}

/// Largest |a − b| over two equally long sequences.
fn max_difference(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Runs `scene` for `steps` steps on 1, 2 and 3 threads and asserts the same bits.
fn assert_thread_independent(name: &str, scene: &Value, steps: usize) {
    let tmp = TempDir::new().unwrap();
    let (phi1, rows1) = run(tmp.path(), scene, steps, 1);
    for threads in [2, 3] {
        let (phi, rows) = run(tmp.path(), scene, steps, threads);
        assert!(
            phi1 == phi,
            "{name}: φ on {threads} threads differs from 1 thread by {:e}",
            max_difference(&phi1, &phi)
        );
        assert_eq!(rows1, rows, "{name}: F, A, V, σ on {threads} threads");
    }
}

#[test]
fn spectral_runs_do_not_depend_on_the_thread_count() {
    for (name, extra) in [
        ("sbdf1", json!({"scheme": "sbdf1"})),
        (
            "sbdf2 adaptive, Lagrangian area",
            json!({"scheme": "sbdf2", "adaptive": {"dt_max": 50.0},
                   "area": {"method": "lagrangian", "alpha": 1e-3}}),
        ),
    ] {
        for mirrored in [false, true] {
            let what = format!("{name} (mirrored: {mirrored})");
            assert_thread_independent(&what, &ellipsoid(extra.clone(), mirrored), 10);
        }
    }
}

/// The second affine term's sweeps (task by task in parallel, added in a fixed tree): the
/// Stokes flow with the area held (T̂ in the update's sweeps, the projection's sums in its
/// halving tree of tasks; on the ellipsoid's full box, on its half box about z, whose flow
/// keeps a twisted component, and on its eighth box, whose spectra are packed) and ADE with its
/// multiplier solved in the step (the ellipsoid's eighth box).
#[test]
fn second_term_runs_do_not_depend_on_the_thread_count() {
    let stokes = json!({"scheme": "sbdf2", "dynamics": "stokes", "c0": 0.0,
                        "flow": {"viscosity": 1.0, "mobility": 0.01}});
    assert_thread_independent("stokes, area held", &ellipsoid(stokes.clone(), false), 6);
    let mut half = ellipsoid(stokes.clone(), false);
    half["symmetry"] = json!(["z"]);
    assert_thread_independent("stokes, area held, half box", &half, 6);
    assert_thread_independent("stokes, area held, eighth box", &ellipsoid(stokes, true), 6);
    let ade = json!({"scheme": "sbdf2", "c0": 0.0, "ade": {"alpha": 1.0, "da0": 1.1}});
    assert_thread_independent("ade", &ellipsoid(ade, true), 6);
}

#[test]
fn relaxational_runs_do_not_depend_on_the_thread_count() {
    for mirrored in [false, true] {
        let scene = ellipsoid(json!({"dynamics": "relaxational", "dt": 1.0}), mirrored);
        assert_thread_independent(&format!("relaxational (mirrored: {mirrored})"), &scene, 10);
    }
}

/// FD with the projection and with the paper's Lagrangian update (σ from A_h, whose sum the
/// fused sweep forms per plane and adds in plane order).
#[test]
fn fd_runs_do_not_depend_on_the_thread_count() {
    for area in [
        json!({"method": "projection"}),
        json!({"method": "lagrangian", "alpha": 1e-3}),
    ] {
        for mirrored in [false, true] {
            let scene = ellipsoid(json!({"method": "fd", "dt": 4e-4, "area": area}), mirrored);
            assert_thread_independent(&format!("fd {area} (mirrored: {mirrored})"), &scene, 10);
        }
    }
}

/// A run of 10 steps on 1 thread resumed for 10 more on 3 threads ends on the bits of the
/// 20-step run on 1 thread, so a checkpoint may move to a machine with another core count.
#[test]
fn a_run_resumed_on_more_threads_continues_bit_for_bit() {
    for (name, extra) in [
        (
            "fd lagrangian",
            json!({"method": "fd", "dt": 4e-4, "area": {"method": "lagrangian", "alpha": 1e-3}}),
        ),
        (
            "sbdf2 adaptive",
            json!({"scheme": "sbdf2", "adaptive": {"dt_max": 50.0}}),
        ),
        (
            "relaxational",
            json!({"dynamics": "relaxational", "dt": 1.0}),
        ),
    ] {
        let tmp = TempDir::new().unwrap();
        let scene = ellipsoid(extra, true);
        let (whole, _) = run(tmp.path(), &scene, 20, 1);
        let (spec, split) = (tmp.path().join("s.json"), tmp.path().join("split"));
        let (spec, split_dir) = (spec.to_str().unwrap(), split.to_str().unwrap());
        vesicle(&[
            "run",
            spec,
            "--out",
            split_dir,
            "--set",
            "max_steps=10",
            "--set",
            "threads=1",
        ]);
        vesicle(&[
            "resume",
            split_dir,
            "--set",
            "max_steps=20",
            "--set",
            "threads=3",
        ]);
        let resumed = phi_of(&split);
        assert!(
            whole == resumed,
            "{name}: resumed on 3 threads differs by {:e}",
            max_difference(&whole, &resumed)
        );
    }
}
