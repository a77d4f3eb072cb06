//! The comparison and study commands, end to end on tiny scenes.

use std::path::Path;
use std::process::Command;

fn vesicle(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_vesicle"))
        .args(args)
        .output()
        .expect("run vesicle")
}

/// Data rows of a CSV whose first column may be quoted (and hold commas).
fn csv_rows(path: &Path) -> Vec<Vec<String>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| {
            let (first, rest) = match l.strip_prefix('"') {
                Some(q) => q.split_once("\",").unwrap(),
                None => l.split_once(',').unwrap(),
            };
            std::iter::once(first)
                .chain(rest.split(','))
                .map(str::to_string)
                .collect()
        })
        .collect()
}

/// `compare` starts both engines from the same field (difference 0 at t = 0) and writes one
/// row per common time.
#[test]
fn compare_writes_the_table() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("cmp");
    let o = vesicle(&[
        "compare",
        "runs/compare2d.json",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "t_end=0.05",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows = csv_rows(&out.join("compare.csv"));
    assert_eq!(rows.len(), 11);
    let dphi0: f64 = rows[0][13].parse().unwrap();
    let dphi_end: f64 = rows[10][13].parse().unwrap();
    assert!(dphi0 < 1e-12, "initial fields differ by {dphi0}");
    assert!(
        dphi_end > 0.0 && dphi_end < 0.1,
        "final difference {dphi_end}"
    );
    assert!(String::from_utf8_lossy(&o.stdout).contains("wall-time ratio"));
}

/// `study stability` finds the FD scheme stable below its bound (DESIGN.md §2: 1.25e-3 in 2D
/// with ε = h = 1) and failing within a factor 2 above it; the stabilised SBDF1 stays stable
/// three decades beyond it.
#[test]
fn stability_study_brackets_the_fd_bound() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("stab");
    let o = vesicle(&[
        "study",
        "stability",
        "runs/stability2d.json",
        "--out",
        out.to_str().unwrap(),
        "--steps",
        "60",
        "--dt-min",
        "1e-4",
        "--dt-max",
        "3",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows = csv_rows(&out.join("stability.csv"));
    let bound = 1.25e-3;
    let of = |name: &str| -> Vec<(f64, String)> {
        rows.iter()
            .filter(|r| r[0] == name)
            .map(|r| (r[1].parse().unwrap(), r[2].clone()))
            .collect()
    };
    for (dt, outcome) in of("fd explicit Euler") {
        if dt < bound {
            assert_eq!(outcome, "stable", "fd at dt {dt}");
        } else if dt > 2.0 * bound {
            assert_ne!(outcome, "stable", "fd at dt {dt}");
        }
    }
    let stabilised = of("spectral SBDF1, S");
    assert!(stabilised
        .iter()
        .filter(|(dt, _)| *dt <= 1.0)
        .all(|(_, o)| o == "stable"));
    assert!(out.join("stability.png").exists());
}

/// `study stationary` on a small 2D ellipse: every route (L-BFGS, SBDF1, SBDF2) passes
/// residual 1e-6 at a state within 1e-6 (relative) of F* in energy (the README's guidance: the
/// energy error goes as the residual squared), each tighter tolerance gives a smaller error on
/// the conserved routes, and L-BFGS needs fewer evaluations than SBDF1 to 1e-6.
#[test]
fn stationary_study_tolerances_mean_the_same_on_every_route() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("stat");
    let o = vesicle(&[
        "study",
        "stationary",
        "runs/ellipse2d.json",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "n=[64,64]",
        "--set",
        "initial.r0=10",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows = csv_rows(&out.join("stationary.csv"));
    // route,stop_residual,steps,evaluations,t,wall_seconds,residual,energy,relative_energy_error
    let at = |route: &str, tol: f64| -> (f64, f64) {
        let r = rows
            .iter()
            .find(|r| r[0].contains(route) && r[1].parse::<f64>().unwrap() == tol)
            .unwrap_or_else(|| panic!("{route} reaches {tol}"));
        (r[3].parse().unwrap(), r[8].parse::<f64>().unwrap().abs())
    };
    for route in ["L-BFGS", "SBDF1", "SBDF2"] {
        let (_, error) = at(route, 1e-6);
        assert!(
            error < 1e-6,
            "{route}: energy error {error:e} at residual 1e-6"
        );
    }
    for route in ["SBDF1", "SBDF2"] {
        let errors: Vec<f64> = [1e-4, 1e-5, 1e-6, 1e-7]
            .iter()
            .map(|&t| at(route, t).1)
            .collect();
        assert!(
            errors.windows(2).all(|w| w[1] < w[0]),
            "{route}: errors {errors:?}"
        );
    }
    assert!(at("L-BFGS", 1e-6).0 < at("SBDF1", 1e-6).0);
    assert!(out.join("convergence.png").exists() && out.join("residual.png").exists());
}

/// `study precision`: SBDF2's error falls as Δt² down the ladder (order within 2 ± 0.2 over
/// four halvings), SBDF1's as Δt (1 ± 0.1), and FD's is its spatial error, the same at every Δt
/// (within 1%) and above both spectral steppers'.
#[test]
fn precision_study_shows_the_orders() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("prec");
    let o = vesicle(&[
        "study",
        "precision",
        "runs/compare2d.json",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "t_end=1",
        "--set",
        "dt=0.02",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows = csv_rows(&out.join("precision.csv"));
    let errors = |name: &str| -> Vec<f64> {
        rows.iter()
            .filter(|r| r[0] == name)
            .map(|r| r[4].parse().unwrap())
            .collect()
    };
    let order = |e: &[f64]| (e[0] / e[e.len() - 1]).log2() / (e.len() - 1) as f64;
    let (fd, s1, s2) = (
        errors("fd explicit Euler"),
        errors("spectral SBDF1"),
        errors("spectral SBDF2"),
    );
    assert!((order(&s2) - 2.0).abs() < 0.2, "SBDF2 order {}", order(&s2));
    assert!((order(&s1) - 1.0).abs() < 0.1, "SBDF1 order {}", order(&s1));
    assert!((fd[0] - fd[2]).abs() < 0.01 * fd[0], "FD errors {fd:?}");
    assert!(fd[2] > s1[0] && fd[2] > s2[0]);
    assert!(out.join("precision.png").exists());
}
