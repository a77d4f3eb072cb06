//! Runs that survive: a run of 2N steps and a run of N steps resumed for N more give bitwise
//! identical φ and identical CSV rows (every column but the wall time), for every engine, area
//! method, fixed and adaptive steps, full and mirrored boxes, in 2D and 3D;
//! SIGINT and SIGTERM end a run cleanly (exit 130/143, outputs and checkpoint written), also
//! with SIGINT ignored as in a background job; a `kill -9` in the middle of a checkpoint write
//! leaves the previous checkpoint loadable and the run resumable.

use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};
use tempfile::TempDir;

fn vesicle(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vesicle"))
        .args(args)
        .output()
        .expect("the vesicle binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn write_scene(dir: &Path, name: &str, scene: &Value) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_string_pretty(scene).unwrap()).unwrap();
    path
}

/// The CSV rows without the column `wall_seconds` (the last, or the last before the
/// area-difference columns).
fn rows_without_wall(dir: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(dir.join("timeseries.csv")).unwrap();
    let wall = text
        .lines()
        .next()
        .unwrap()
        .split(',')
        .position(|c| c == "wall_seconds")
        .expect("a wall_seconds column");
    text.lines()
        .map(|l| {
            let mut f: Vec<&str> = l.split(',').collect();
            f.remove(wall);
            f.join(",")
        })
        .collect()
}

fn summary(dir: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

/// A 2D ellipse on a 32² box with the engine settings of `extra`.
fn ellipse(extra: Value) -> Value {
    let mut v = json!({
        "dim": 2, "n": [32, 32], "dt": 0.5,
        "initial": {"shape": "ellipsoid", "axes": [10.0, 6.0]},
        "c0": 0.1, "prepare_steps": 5,
        "output": {"record_every": 1, "png": false, "vti": false}
    });
    v.as_object_mut()
        .unwrap()
        .extend(extra.as_object().unwrap().clone());
    v
}

/// The engine settings of the resume matrix: every engine (FD, SBDF1, SBDF2, relaxational) ×
/// every area method it accepts (projection, Lagrangian, none) × fixed and adaptive steps (the
/// spectral schemes; FD and the relaxational route run fixed steps only) × the full box and the
/// box mirrored on every axis, with its name.
fn resume_matrix(dim: usize) -> Vec<(String, Value)> {
    let mut cases = Vec::new();
    for engine in ["fd", "sbdf1", "sbdf2", "relaxational"] {
        for area in ["projection", "lagrangian", "none"] {
            if engine == "relaxational" && area == "lagrangian" {
                continue;
            }
            let steps: &[bool] = match engine {
                "sbdf1" | "sbdf2" => &[false, true],
                _ => &[false],
            };
            for &adaptive in steps {
                for mirror in [false, true] {
                    let mut v = match engine {
                        "fd" => json!({"method": "fd", "dt": 4e-4}),
                        "relaxational" => json!({"dynamics": "relaxational", "dt": 1.0}),
                        scheme => json!({"scheme": scheme}),
                    };
                    v["area"] = match area {
                        "lagrangian" => json!({"method": area, "alpha": 1e-3}),
                        _ => json!({"method": area}),
                    };
                    if adaptive {
                        v["adaptive"] = json!({"dt_max": 50.0});
                    }
                    if mirror {
                        v["symmetry"] = json!(["x", "y", "z"][..dim]);
                    }
                    let steps = if adaptive { "adaptive" } else { "fixed" };
                    let walls = if mirror { "mirrored" } else { "full" };
                    cases.push((format!("{engine} {area} {steps} {walls}"), v));
                }
            }
        }
    }
    cases
}

/// In `dir`, `scene` run for 2n steps into `whole` and for n steps into `split`, then `split`
/// resumed to 2n steps; the two folders.
fn whole_and_split(name: &str, dir: &Path, scene: &Value, n: usize) -> (PathBuf, PathBuf) {
    let scene = write_scene(dir, "s.json", scene);
    let scene = scene.to_str().unwrap();
    let (whole, split) = (dir.join("whole"), dir.join("split"));
    let steps = |k: usize| format!("max_steps={k}");
    for (out, k) in [(&whole, 2 * n), (&split, n)] {
        let o = vesicle(&[
            "run",
            scene,
            "--out",
            out.to_str().unwrap(),
            "--set",
            &steps(k),
        ]);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
    }
    let o = vesicle(&["resume", split.to_str().unwrap(), "--set", &steps(2 * n)]);
    assert!(o.status.success(), "{name}: {}", stderr(&o));
    (whole, split)
}

/// A run of 2n steps and a run of n steps resumed for n more: the same φ bit for bit, the same
/// CSV rows (every column but the wall time) and the same step count.
fn assert_resume_is_exact(name: &str, scene: &Value, n: usize) {
    let tmp = TempDir::new().unwrap();
    let (whole, split) = whole_and_split(name, tmp.path(), scene, n);
    let phi = |d: &Path| std::fs::read(d.join("phi_final.npy")).unwrap();
    assert!(
        phi(&whole) == phi(&split),
        "{name}: φ differs after resuming"
    );
    assert_eq!(
        rows_without_wall(&whole),
        rows_without_wall(&split),
        "{name}: CSV rows"
    );
    assert_eq!(summary(&split)["final"]["steps"], json!(2 * n), "{name}");
}

/// The whole matrix on a 2D ellipse (32², 15 + 15 steps). The Lagrangian update reads the area
/// of the state before each step, so a resumed run that recomputed that area in another
/// summation order (FD: forward differences against the step's Σ φ∇²φ) would take another σ
/// at its first step and differ in the σ column from there on.
#[test]
fn resumed_runs_are_bitwise_identical_to_uninterrupted_ones() {
    for (name, extra) in resume_matrix(2) {
        assert_resume_is_exact(&name, &ellipse(extra), 15);
    }
}

/// The matrix on a 3D ellipsoid (16³, 8 + 8 steps): the three-dimensional transforms, stencils
/// and sweeps, whose reductions are split differently from the 2D ones.
#[test]
fn resumed_3d_runs_are_bitwise_identical_to_uninterrupted_ones() {
    for (name, extra) in resume_matrix(3) {
        let mut scene = ellipse(extra);
        scene["dim"] = json!(3);
        scene["n"] = json!([16, 16, 16]);
        scene["initial"]["axes"] = json!([5.0, 3.5, 3.0]);
        assert_resume_is_exact(&name, &scene, 8);
    }
}

/// The area-difference term resumed in the middle of a run (3D ellipsoid, 16³, 8 + 8 steps):
/// ADE on every engine (SBDF2 adaptive with the implicit λ, SBDF1 with the lagged one, FD,
/// L-BFGS) and the bilayer couple (SBDF2 adaptive, L-BFGS). The checkpoint holds λ; SBDF2's
/// m̂ⁿ⁻¹ is evaluated again from φ̂ⁿ⁻¹, by the same sweeps, and L-BFGS's λ is solved again
/// from the evaluated state, as after an iteration, so φ and every row (the columns da, w,
/// c0_eff, lambda included) are bitwise those of the uninterrupted run.
#[test]
fn resumed_area_difference_runs_are_bitwise_identical_to_uninterrupted_ones() {
    let ade = json!({"alpha": 1.0, "da0": 1.3});
    let runs = [
        (
            "ade sbdf2",
            json!({"scheme": "sbdf2", "adaptive": {"dt_max": 20.0}, "ade": ade}),
        ),
        (
            "ade lagged sbdf1",
            json!({"ade": {"alpha": 1.0, "da0": 1.3, "multiplier": "lagged"}}),
        ),
        ("ade fd", json!({"method": "fd", "dt": 4e-4, "ade": ade})),
        (
            "ade relaxational",
            json!({"dynamics": "relaxational", "dt": 1.0, "ade": ade}),
        ),
        (
            "bilayer couple sbdf2",
            json!({"scheme": "sbdf2", "adaptive": {"dt_max": 20.0},
            "bilayer_couple": {"da": 1.05}}),
        ),
        (
            "bilayer couple relaxational",
            json!({"dynamics": "relaxational", "dt": 1.0, "bilayer_couple": {"da": 1.05}}),
        ),
    ];
    for (name, extra) in runs {
        let mut scene = ellipse(extra);
        scene["dim"] = json!(3);
        scene["n"] = json!([16, 16, 16]);
        scene["initial"]["axes"] = json!([5.0, 3.5, 3.0]);
        assert_resume_is_exact(name, &scene, 8);
    }
}

/// The Stokes dynamics resumed in the middle (SBDF2 adaptive with the area projection, SBDF1 at
/// fixed tension with an imposed shear, each with one global tension and with the inextensible
/// membrane, on the full 48² box at h = ε/2, 8 + 8 steps): the history T̂ⁿ⁻¹ of the flow's part
/// per unit σ is not saved but evaluated again from φ̂ⁿ⁻¹, and the inextensible membrane's
/// tension fields of both states are saved and replayed in those evaluations in place of
/// solves, so φ and every row (max_speed and dissipation included) are bitwise those of the
/// uninterrupted run. (A resume that solved again from the saved σ would follow the run to the
/// solve's tolerance only.)
#[test]
fn resumed_stokes_runs_are_bitwise_identical_to_uninterrupted_ones() {
    let flow = json!({"viscosity": 1.0, "mobility": 0.01});
    let runs = [
        (
            "stokes sbdf2 projection",
            json!({"dynamics": "stokes", "flow": flow, "scheme": "sbdf2",
                   "adaptive": {"dt_max": 3.0}}),
        ),
        (
            "stokes sbdf1 fixed shear",
            json!({"dynamics": "stokes", "scheme": "sbdf1", "dt": 0.5,
                   "flow": {"viscosity": 1.0, "mobility": 0.01, "shear_rate": 1e-3},
                   "area": {"method": "fixed", "sigma": 0.05}}),
        ),
    ];
    let inextensible = runs.clone().map(|(name, mut extra)| {
        extra["flow"]["inextensible"] = json!(true);
        (name.replace("stokes", "inextensible"), extra)
    });
    let drops = runs.map(|(name, extra)| (name.to_string(), extra));
    for (name, extra) in drops.into_iter().chain(inextensible) {
        let mut scene = ellipse(extra);
        scene["h"] = json!(0.5);
        scene["n"] = json!([48, 48]);
        scene["initial"]["axes"] = json!([8.0, 5.0]);
        scene["c0"] = json!(0.0);
        assert_resume_is_exact(&name, &scene, 8);
    }
}

/// A volume ramp (V0 from V_init to 0.9 V_init over t ∈ [0, 10]) resumed in the middle of the
/// ramp (15 + 15 steps of Δt = 0.5, split at t = 7.5) for SBDF1 and SBDF2, fixed and adaptive:
/// the target is a function of t and of V_init, which the checkpoint carries, so φ and every row
/// are bitwise those of the uninterrupted run.
#[test]
fn resumed_volume_ramps_are_bitwise_identical_to_uninterrupted_ones() {
    for scheme in ["sbdf1", "sbdf2"] {
        for adaptive in [false, true] {
            let mut v = ellipse(json!({"scheme": scheme,
                "volume": {"final_fraction": 0.9, "ramp_time": 10.0}}));
            if adaptive {
                v["adaptive"] = json!({"dt_max": 2.0});
            }
            assert_resume_is_exact(&format!("volume ramp {scheme} adaptive {adaptive}"), &v, 15);
        }
    }
}

#[test]
fn resume_refuses_changes_other_than_stop_rules_and_bad_checkpoints() {
    let tmp = TempDir::new().unwrap();
    let scene = write_scene(tmp.path(), "s.json", &ellipse(json!({"max_steps": 3})));
    let out = tmp.path().join("r");
    let out_s = out.to_str().unwrap();
    assert!(vesicle(&["run", scene.to_str().unwrap(), "--out", out_s])
        .status
        .success());
    let o = vesicle(&["resume", out_s, "--set", "dt=0.1"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("`dt`"), "{}", stderr(&o));
    // A corrupted checkpoint is refused, naming it, and nothing is changed.
    let ck = out.join("checkpoint.bin");
    let mut bytes = std::fs::read(&ck).unwrap();
    let mid = bytes.len() / 2;
    bytes[mid] ^= 0xff;
    std::fs::write(&ck, &bytes).unwrap();
    let before = std::fs::read(out.join("timeseries.csv")).unwrap();
    let o = vesicle(&["resume", out_s, "--set", "max_steps=6"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("checkpoint"), "{}", stderr(&o));
    assert_eq!(std::fs::read(out.join("timeseries.csv")).unwrap(), before);
    // A missing one too.
    std::fs::remove_file(&ck).unwrap();
    let o = vesicle(&["resume", out_s]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}

/// A long-running 3D FD run in `dir` (writes rows every step), started through `sh` so that the
/// shell can set signal dispositions first.
fn spawn_long_run(
    tmp: &Path,
    out: &Path,
    prelude: &str,
    env: &[(&str, &str)],
) -> std::process::Child {
    let scene = write_scene(
        tmp,
        "long.json",
        &json!({
            "dim": 3, "n": [48, 48, 48], "method": "fd", "dt": 4e-4, "max_steps": 10_000_000,
            "initial": {"shape": "sphere", "radius": 12.0},
            "output": {"record_every": 1, "png": false, "vti": false, "checkpoint_every": 1}
        }),
    );
    let mut cmd = Command::new("sh");
    cmd.arg("-c")
        .arg(format!(
            "{prelude} exec \"$0\" run \"$1\" --out \"$2\" --quiet",
        ))
        .arg(env!("CARGO_BIN_EXE_vesicle"))
        .arg(scene)
        .arg(out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd.spawn().unwrap()
}

fn wait_for(what: &str, limit: Duration, mut ready: impl FnMut() -> bool) {
    let start = Instant::now();
    while !ready() {
        assert!(start.elapsed() < limit, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn rows(dir: &Path) -> usize {
    std::fs::read_to_string(dir.join("timeseries.csv"))
        .map(|t| t.lines().count())
        .unwrap_or(0)
}

#[test]
fn sigterm_and_background_sigint_end_the_run_cleanly() {
    for (signal, code, prelude) in [
        ("-TERM", 143, ""),
        // As in a background job of a non-interactive shell: SIGINT ignored on entry.
        ("-INT", 130, "trap '' INT;"),
    ] {
        let tmp = TempDir::new().unwrap();
        let out = tmp.path().join("run");
        let mut child = spawn_long_run(tmp.path(), &out, prelude, &[]);
        wait_for("a few steps", Duration::from_secs(60), || rows(&out) >= 4);
        let kill = Command::new("kill")
            .args([signal, &child.id().to_string()])
            .status()
            .unwrap();
        assert!(kill.success());
        let status = child.wait().unwrap();
        assert_eq!(status.code(), Some(code), "{signal}");
        let s = summary(&out);
        assert_eq!(s["stopped"], json!("interrupted"), "{signal}");
        assert_eq!(s["final"]["stopped"], json!("interrupted"), "{signal}");
        assert!(out.join("phi_final.npy").exists() && out.join("checkpoint.bin").exists());
        assert!(
            !out.join(".lock").exists(),
            "{signal}: the lock is released"
        );
        // It continues from where it stopped.
        let steps = s["steps"].as_u64().unwrap();
        let more = format!("max_steps={}", steps + 2);
        let o = vesicle(&["resume", out.to_str().unwrap(), "--set", &more]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert_eq!(summary(&out)["steps"].as_u64(), Some(steps + 2));
    }
}

#[test]
fn kill_9_during_a_checkpoint_write_keeps_the_previous_checkpoint() {
    let tmp = TempDir::new().unwrap();
    let out = tmp.path().join("run");
    // 48³ f64 is 0.9 MiB: with 150 ms per MiB written a checkpoint write takes ~150 ms.
    let mut child = spawn_long_run(
        tmp.path(),
        &out,
        "",
        &[("VESICLE_TEST_SLOW_CHECKPOINT", "150")],
    );
    let ck = out.join("checkpoint.bin");
    let tmp_ck = out.join("checkpoint.bin.tmp");
    wait_for("a first checkpoint", Duration::from_secs(60), || {
        ck.exists()
    });
    wait_for(
        "a checkpoint write under way",
        Duration::from_secs(60),
        || tmp_ck.exists(),
    );
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    assert!(tmp_ck.exists(), "killed in the middle of a write");
    assert!(out.join(".lock").exists(), "a killed run leaves its lock");
    let o = vesicle(&["resume", out.to_str().unwrap(), "--set", "max_steps=1"]);
    // The checkpoint is whole: it loads (the stale lock is taken over), and with max_steps
    // below its step the run ends at once.
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(summary(&out)["stopped"], json!("max_steps"));
}

/// A fixed SBDF1 step far beyond its dissipative range (Δt = 200; the stabilised step stays
/// dissipative to about Δt = 5 here) raises F_eff: the run stops with exit 3 naming the step,
/// Δt and the check, keeps the time series, and its checkpoint holds the last good state, from
/// which it resumes (with adaptive steps the same Δt is retried smaller instead).
#[test]
fn energy_rise_at_a_fixed_step_stops_with_exit_3_and_a_good_checkpoint() {
    let tmp = TempDir::new().unwrap();
    let scene = write_scene(
        tmp.path(),
        "s.json",
        &ellipse(json!({"scheme": "sbdf1", "dt": 200.0, "max_steps": 200, "prepare_steps": 0})),
    );
    let out = tmp.path().join("r");
    let o = vesicle(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("F_eff rose") && err.contains("Δt = 2.0000e2"),
        "{err}"
    );
    let s = summary(&out);
    let steps = s["steps"].as_u64().unwrap();
    eprintln!("fixed Δt = 200: F_eff rose at step {}", steps + 1);
    assert!(s["stopped"].as_str().unwrap().starts_with("blew up"));
    assert_eq!(
        rows(&out),
        steps as usize + 2,
        "header, step 0 … the last good step"
    );
    // The checkpoint is the last good state: resuming at once (max_steps = its step) reproduces
    // the final field bit for bit.
    let phi = std::fs::read(out.join("phi_final.npy")).unwrap();
    let o = vesicle(&[
        "resume",
        out.to_str().unwrap(),
        "--set",
        &format!("max_steps={steps}"),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read(out.join("phi_final.npy")).unwrap(), phi);
    // Adaptive: the rise is a rejection, the step is retried smaller and the run goes on.
    let adaptive = write_scene(
        tmp.path(),
        "a.json",
        &ellipse(
            json!({"scheme": "sbdf1", "dt": 200.0, "max_steps": 200, "prepare_steps": 0,
                        "adaptive": {"dt_min": 1e-3}}),
        ),
    );
    let out = tmp.path().join("a");
    let o = vesicle(&[
        "run",
        adaptive.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = summary(&out);
    assert!(s["rejected_steps"].as_u64().unwrap() > 0, "{s}");
}

/// The times of the rows of `dir`'s time series (column `t`), the first and the last left out.
fn inner_row_times(dir: &Path) -> Vec<f64> {
    let text = std::fs::read_to_string(dir.join("timeseries.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = header.iter().position(|h| *h == "t").unwrap();
    let t: Vec<f64> = lines
        .map(|l| l.split(',').nth(col).unwrap().parse().unwrap())
        .collect();
    t[1..t.len() - 1].to_vec()
}

/// Outputs on simulated time: rows every 1.25 and snapshots every 2.5 of t, with fixed steps
/// of 0.5 (not a divisor of 1.25) and with adaptive steps. The driver shortens the step that
/// would pass a due time, so every row but the first and last lies on a multiple of 1.25 (to
/// the round-off of a sum of steps, 1e-9 here), and a run of 2N steps and a run of N steps
/// resumed for N more (its next due time read from the checkpoint, not found again from t)
/// give bitwise identical φ, identical rows and the same snapshot files.
#[test]
fn outputs_on_simulated_time_land_on_their_times_and_resume_bitwise() {
    // Fixed steps: 31 steps end at t = 13, between two due times (13.75 is due next; a timer
    // started again at the checkpoint would be due at 14.25).
    let n = 31;
    for (name, extra) in [
        ("sbdf1-fixed", json!({"scheme": "sbdf1"})),
        (
            "sbdf2-adaptive",
            json!({"scheme": "sbdf2", "adaptive": {"dt_max": 50.0}}),
        ),
    ] {
        let mut scene = ellipse(extra);
        scene["output"] = json!({
            "records": {"every_time": 1.25},
            "snapshots": {"every_time": 2.5},
            "png": false, "vti": false
        });
        let tmp = TempDir::new().unwrap();
        let (whole, split) = whole_and_split(name, tmp.path(), &scene, n);
        let times = inner_row_times(&whole);
        assert!(times.len() >= 3, "{name}: {times:?}");
        for (k, t) in times.iter().enumerate() {
            let due = 1.25 * (k + 1) as f64;
            assert!(
                (t - due).abs() <= 1e-9,
                "{name}: row {k} at t = {t}, due {due}"
            );
        }
        let phi = |d: &Path| std::fs::read(d.join("phi_final.npy")).unwrap();
        assert!(
            phi(&whole) == phi(&split),
            "{name}: φ differs after resuming"
        );
        // The split run also keeps the state it stopped at (step N), as every run keeps its
        // last state.
        let whole_rows = rows_without_wall(&whole);
        let split_rows: Vec<String> = rows_without_wall(&split)
            .into_iter()
            .filter(|r| whole_rows.contains(r) || !r.starts_with(&format!("{n},")))
            .collect();
        assert_eq!(whole_rows, split_rows, "{name}");
        let snaps = |d: &Path| {
            let mut v: Vec<_> = std::fs::read_dir(d.join("snapshots"))
                .unwrap()
                .map(|e| e.unwrap().file_name())
                .collect();
            v.sort();
            v
        };
        assert!(!snaps(&whole).is_empty(), "{name}: no snapshots");
        assert_eq!(snaps(&whole), snaps(&split), "{name}: snapshots");
    }
}

/// `max_wall_minutes`: a run that would step past it (0.001 min here, against a million steps)
/// stops after a step with `"stopped": "wall_time"`, exit 0 and a checkpoint; resumed without the
/// limit it continues to its stop rule and ends bitwise where an uninterrupted run ends.
#[test]
fn wall_time_limit_stops_cleanly_and_the_run_resumes() {
    let tmp = TempDir::new().unwrap();
    let scene = write_scene(
        tmp.path(),
        "s.json",
        &ellipse(json!({"scheme": "sbdf1", "max_steps": 1_000_000, "max_wall_minutes": 0.001})),
    );
    let out = tmp.path().join("r");
    let o = vesicle(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let s = summary(&out);
    assert_eq!(s["stopped"], json!("wall_time"), "{s}");
    let steps = s["steps"].as_u64().unwrap();
    assert!((1..1_000_000).contains(&steps), "{steps} steps");
    assert!(out.join("checkpoint.bin").exists());
    let target = format!("max_steps={}", steps + 5);
    let o = vesicle(&[
        "resume",
        out.to_str().unwrap(),
        "--set",
        "max_wall_minutes=null",
        "--set",
        &target,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = summary(&out);
    assert_eq!(s["stopped"], json!("max_steps"), "{s}");
    assert_eq!(s["steps"].as_u64(), Some(steps + 5));
    let whole = tmp.path().join("whole");
    let o = vesicle(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        whole.to_str().unwrap(),
        "--set",
        "max_wall_minutes=null",
        "--set",
        &target,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let phi = |d: &Path| std::fs::read(d.join("phi_final.npy")).unwrap();
    assert!(phi(&whole) == phi(&out), "φ differs after a wall-time stop");
    assert_eq!(rows_without_wall(&whole), rows_without_wall(&out));
}
