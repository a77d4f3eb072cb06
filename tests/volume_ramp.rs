//! The time-dependent volume of the scene file, `"volume": {"final_fraction": f, "ramp_time": T}`:
//! every accepted step of the spectral engine sets the k = 0 mode of φ so that the diffuse
//! volume V = ∫(1 + φ)/2 equals V0(t) = V_init (1 + (f − 1) min(t/T, 1)) exactly, so every row
//! of `timeseries.csv` holds V0 at its own t to round-off: the only error is the summation of
//! φ over the grid (measured worst row 8.3e-16 relative on these runs; the bound 1e-12 is what
//! round-off on a 32² sum can never reach, while a ramp ignored or a step late misses by ~1e-3).

use serde_json::{json, Value};
use std::path::Path;
use std::process::Command;
use tempfile::TempDir;

/// A 2D ellipse (32², reduced area 0.93) with c0 = 0.1 whose volume ramps to `fraction` of the
/// prepared one over t ∈ [0, 12], run to t = 20 (40 fixed steps of Δt = 0.5), past the ramp's
/// end, with the engine settings of `extra`.
fn ramped_ellipse(fraction: f64, extra: Value) -> Value {
    let mut v = json!({
        "dim": 2, "n": [32, 32], "dt": 0.5, "t_end": 20.0,
        "initial": {"shape": "ellipsoid", "axes": [10.0, 6.0]},
        "c0": 0.1, "prepare_steps": 5,
        "volume": {"final_fraction": fraction, "ramp_time": 12.0},
        "output": {"record_every": 1, "png": false, "vti": false}
    });
    v.as_object_mut()
        .unwrap()
        .extend(extra.as_object().unwrap().clone());
    v
}

/// Run `scene` into a fresh folder under `tmp`; the folder.
fn run(tmp: &TempDir, name: &str, scene: &Value) -> std::path::PathBuf {
    let path = tmp.path().join(format!("{name}.json"));
    std::fs::write(&path, scene.to_string()).unwrap();
    let out = tmp.path().join(name);
    let o = Command::new(env!("CARGO_BIN_EXE_vesicle"))
        .args([
            "run",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    out
}

/// (t, V) of every row of the run's `timeseries.csv`.
fn times_and_volumes(dir: &Path) -> Vec<(f64, f64)> {
    let text = std::fs::read_to_string(dir.join("timeseries.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (t, v) = (col("t"), col("volume"));
    lines
        .map(|l| {
            let f: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            (f[t], f[v])
        })
        .collect()
}

/// SBDF1 and SBDF2, fixed and adaptive steps, full and mirrored boxes, deflation (f = 0.9) and
/// inflation (f = 1.05): on every row |V − V0(t)|/V0 < 1e-12 with V_init the volume of the
/// step-0 row (the prepared field). The run must also reach V0 = f V_init and stay there
/// (rows after t = 12), so a ramp that was ignored, lagged a step, or overshot fails by ~1e-3.
#[test]
fn the_ramp_holds_the_volume_to_its_target_at_every_step() {
    let cases = [
        ("sbdf1 fixed", 0.9, json!({"scheme": "sbdf1"})),
        ("sbdf2 fixed", 0.9, json!({"scheme": "sbdf2"})),
        (
            "sbdf2 adaptive mirrored",
            0.9,
            json!({"scheme": "sbdf2", "adaptive": {"dt_max": 2.0}, "symmetry": ["x", "y"]}),
        ),
        (
            "sbdf2 inflation",
            1.05,
            json!({"scheme": "sbdf2", "area": {"method": "none"}}),
        ),
    ];
    for (name, fraction, extra) in cases {
        let tmp = TempDir::new().unwrap();
        let scene = tmp.path().join("s.json");
        std::fs::write(&scene, ramped_ellipse(fraction, extra).to_string()).unwrap();
        let out = tmp.path().join("out");
        let o = Command::new(env!("CARGO_BIN_EXE_vesicle"))
            .args([
                "run",
                scene.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ])
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let rows = times_and_volumes(&out);
        let (t0, v_init) = rows[0];
        assert_eq!(t0, 0.0, "{name}: the first row is the prepared field");
        let target = |t: f64| v_init * (1.0 + (fraction - 1.0) * (t / 12.0).min(1.0));
        let mut worst = 0.0f64;
        for &(t, v) in &rows {
            let rel = (v - target(t)).abs() / target(t);
            assert!(rel < 1e-12, "{name}: t {t}: V {v} against V0 {}", target(t));
            worst = worst.max(rel);
        }
        let (t_last, v_last) = *rows.last().unwrap();
        assert!(t_last > 12.0, "{name}: the run passes the ramp's end");
        assert!(
            ((v_last - fraction * v_init) / v_init).abs() < 1e-12,
            "{name}: ends at V {v_last}, not {}",
            fraction * v_init
        );
        println!(
            "{name}: {} rows, worst |V − V0|/V0 = {worst:.1e}",
            rows.len()
        );
    }
}

/// The ramp starts after the preparation: the prepared field (row 0, V_init) of a scene with
/// `volume` is bitwise that of the same scene without it, so V_init is the volume the scene
/// would otherwise conserve.
#[test]
fn the_ramp_starts_from_the_unramped_preparation() {
    let tmp = TempDir::new().unwrap();
    let ramped = ramped_ellipse(0.9, json!({"t_end": 1.0}));
    let mut plain = ramped.clone();
    plain.as_object_mut().unwrap().remove("volume");
    let first_row = |dir: &Path| {
        let text = std::fs::read_to_string(dir.join("timeseries.csv")).unwrap();
        let row = text.lines().nth(1).unwrap().to_string();
        row.rsplit_once(',').unwrap().0.to_string() // without the wall time
    };
    assert_eq!(
        first_row(&run(&tmp, "ramped", &ramped)),
        first_row(&run(&tmp, "plain", &plain))
    );
}
