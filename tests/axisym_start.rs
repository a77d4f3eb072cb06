//! Initial shapes from the axisymmetric reference (`{"shape": "axisym", ...}`, issue 12): the
//! built field reproduces the requested reduced volume, a contour file gives the same field as
//! the solver, a relaxation started this way keeps its branch, and the reference start needs
//! fewer L-BFGS iterations than a spheroid start.

mod common;
use common::{relax, scene, simulation};
use ndarray::Array3;
use serde_json::{json, Value};
use std::time::Instant;
use vesicle::analysis::axisym::{self, Branch, Options};
use vesicle::analysis::levelset;
use vesicle::problem::setup::{self, Problem};

/// The full-box initial field of `v` (unfolding the mirror planes the setup detected).
fn full_initial(v: Value) -> (Problem, Array3<f64>) {
    let s = scene(v);
    let p = setup::build(&s).expect("problem");
    let full = p.grid.unfold(&p.phi).into_owned();
    (p, full)
}

/// Zero crossings of φ along `line`.
fn crossings(line: impl Iterator<Item = f64>) -> usize {
    let v: Vec<f64> = line.collect();
    v.windows(2)
        .filter(|w| (w[0] > 0.0) != (w[1] > 0.0))
        .count()
}

/// Largest number of zero crossings along the lines parallel to internal axis 2 (the scene's
/// z) through the plane y = the central cell; and the count on the central line.
fn z_line_crossings(phi: &Array3<f64>) -> (usize, usize) {
    let (nx, ny, _) = phi.dim();
    let j = ny / 2;
    let count = |i: usize| crossings(phi.slice(ndarray::s![i, j, ..]).iter().copied());
    ((0..nx).map(count).max().unwrap(), count(nx / 2))
}

/// Extent (cells with φ > 0) of the shape along internal axis `a`.
fn extent(phi: &Array3<f64>, a: usize) -> usize {
    phi.axis_iter(ndarray::Axis(a))
        .filter(|plane| plane.iter().any(|x| *x > 0.0))
        .count()
}

/// The φ = 0 surface of the field built at R0 = 12h, ε = h reproduces the requested v to 0.01:
/// the tanh profile's zero sits on the contour (d = 0) and the level set's piecewise-linear
/// interpolation of φ moves it by O(h²κ) ≈ h²/(8R) per cell, a relative error in V/A^{3/2} of a
/// few 1e-3 at R0 = 12h. Measured errors are printed.
#[test]
fn built_field_reproduces_the_requested_reduced_volume() {
    for (branch, v, n) in [
        ("prolate", 0.8, [28, 28, 48]),
        ("oblate", 0.7, [36, 36, 16]),
    ] {
        let t = Instant::now();
        let (_, phi) = full_initial(json!({
            "dim": 3, "n": n, "h": 1.0, "eps": 1.0, "dt": 1.0, "max_steps": 1,
            "initial": {"shape": "axisym", "branch": branch, "reduced_volume": v, "r0": 12.0}
        }));
        let built = t.elapsed().as_secs_f64();
        let ls = levelset::measure(&phi, 3, 1.0);
        let r0 = (ls.area / (4.0 * std::f64::consts::PI)).sqrt();
        eprintln!(
            "{branch} v = {v}: φ = 0 surface v = {:.5} (error {:+.2e}), R0 = {r0:.4} (12), built in {built:.2} s",
            ls.reduced_volume,
            ls.reduced_volume - v
        );
        assert!(
            (ls.reduced_volume - v).abs() < 0.01,
            "{branch}: v = {}",
            ls.reduced_volume
        );
        assert!((r0 - 12.0).abs() < 0.12, "{branch}: R0 = {r0}");
    }
}

/// The prolate branch at v = 1 is the sphere: its field matches the sphere's tanh profile to
/// 1e-4 (resampling sag and the solver's contour), including on the axis and at the poles.
#[test]
fn sphere_from_the_reference_matches_the_sphere() {
    let base =
        json!({"dim": 3, "n": [32, 32, 32], "h": 1.0, "eps": 1.0, "dt": 1.0, "max_steps": 1});
    let with = |initial: Value| {
        let mut v = base.clone();
        v["initial"] = initial;
        full_initial(v).1
    };
    let a =
        with(json!({"shape": "axisym", "branch": "prolate", "reduced_volume": 1.0, "r0": 10.0}));
    let b = with(json!({"shape": "sphere", "radius": 10.0}));
    let diff = a
        .iter()
        .zip(&b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    eprintln!("axisym v = 1 vs sphere: max |Δφ| = {diff:.2e}");
    assert!(diff < 1e-4, "max |Δφ| = {diff}");
}

/// A contour file as `vesicle axisym` writes it gives the solver's field (to the 13 digits of
/// the file), along `x` and off centre; and the field is even about planes containing the axis.
#[test]
fn contour_file_gives_the_solver_field() {
    let sol = axisym::solve(Branch::Oblate, 0.7, &Options::default()).unwrap();
    let dir = tempfile::TempDir::new().unwrap();
    let path = dir.path().join("oblate_v0.700.csv");
    let mut text = String::from("r,z\n");
    for (r, z) in sol.r.iter().zip(&sol.z) {
        text.push_str(&format!("{r:.12e},{z:.12e}\n"));
    }
    std::fs::write(&path, text).unwrap();
    let base = json!({"dim": 3, "n": [16, 36, 36], "h": 1.0, "eps": 1.0, "dt": 1.0,
                      "max_steps": 1, "symmetry": []});
    let with = |initial: Value| {
        let mut v = base.clone();
        v["initial"] = initial;
        full_initial(v).1
    };
    let a = with(
        json!({"shape": "axisym", "branch": "oblate", "reduced_volume": 0.7,
                        "r0": 10.0, "axis": "x", "center": [0.5, 1.0, -1.5]}),
    );
    let b = with(
        json!({"shape": "axisym", "contour": path, "r0": 10.0, "axis": "x",
                        "center": [0.5, 1.0, -1.5]}),
    );
    let diff = a
        .iter()
        .zip(&b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    assert!(diff < 1e-9, "max |Δφ| = {diff}");
    // centred: even about every plane through the centre (the axial mirror by construction)
    let c = with(json!({"shape": "axisym", "contour": path, "r0": 10.0, "axis": "x"}));
    for a in 0..3 {
        let mut f = c.view();
        f.invert_axis(ndarray::Axis(a));
        let d = c
            .iter()
            .zip(f.iter())
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        assert!(d <= 1e-12, "axis {a}: {d}");
    }
}

/// A stomatocyte is not even about the plane normal to its axis: declaring that mirror is
/// refused by the symmetry check; the other two are accepted.
#[test]
fn stomatocyte_refuses_the_axial_mirror() {
    let v = |sym: Value| {
        json!({"dim": 3, "n": [24, 24, 24], "h": 1.0, "eps": 1.0, "dt": 1.0, "max_steps": 1,
               "initial": {"shape": "axisym", "branch": "stomatocyte", "reduced_volume": 0.6,
                           "r0": 6.0},
               "symmetry": sym})
    };
    let err = setup::build(&scene(v(json!(["z"]))))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("symmetry") && err.contains("not even"),
        "{err}"
    );
    let p = setup::build(&scene(v(json!(["x", "y"])))).unwrap();
    assert_eq!(p.mirror, vec![true, true, false]);
    // auto detection finds the same two
    let p = setup::build(&scene(v(json!("auto")))).unwrap();
    assert_eq!(p.mirror, vec![true, true, false]);
}

/// Started from the reference, the L-BFGS relaxation keeps the branch: a stomatocyte at
/// v = 0.6 (R0 = 10ε, quarter box of 40³) still has two sheets above each other (4 zero
/// crossings on some line parallel to the axis, 2 on the axis) and its reduced energy lies
/// within 10% of the reference e at its final φ = 0 v; a prolate at v = 0.8 stays longer along
/// its axis than across.
#[test]
fn relaxation_from_the_reference_keeps_the_branch() {
    let s = scene(json!({
        "dim": 3, "n": [40, 40, 40], "h": 1.0, "eps": 1.0, "dt": 1.0,
        "dynamics": "relaxational", "stop_residual": 1e-5, "max_steps": 400,
        "initial": {"shape": "axisym", "branch": "stomatocyte", "reduced_volume": 0.6, "r0": 10.0},
        "symmetry": ["x", "y"]
    }));
    let (problem, mut sim) = simulation(&s);
    let start = problem.grid.unfold(&problem.phi);
    assert_eq!(
        z_line_crossings(&start),
        (4, 2),
        "the start is a stomatocyte"
    );
    let steps = relax(&mut sim, 1e-5, 400);
    let phi = problem.grid.unfold(sim.engine().phi());
    let (most, axis) = z_line_crossings(&phi);
    let v = levelset::measure(&phi, 3, 1.0).reduced_volume;
    let e = sim.engine().measures().reduced(3, 1.0).energy;
    let e_ref = axisym::solve(Branch::Stomatocyte, v.min(0.66), &Options::default())
        .unwrap()
        .e;
    eprintln!(
        "stomatocyte: {steps:?} iterations to 1e-5, crossings {most} (axis {axis}), v = {v:.4}, \
         e = {e:.4}, reference e = {e_ref:.4} ({:+.1}%)",
        100.0 * (e / e_ref - 1.0)
    );
    // Two sheets above each other somewhere; on the axis 2 crossings (open neck) or 4: at
    // R0 = 10ε the neck, under ε wide, fuses on the axis during the relaxation (measured: 4).
    assert_eq!(most, 4, "no longer a stomatocyte");
    assert!(axis == 2 || axis == 4, "axis crossings {axis}");
    assert!((e / e_ref - 1.0).abs() < 0.1, "e = {e}, reference {e_ref}");

    let s = scene(json!({
        "dim": 3, "n": [24, 24, 40], "h": 1.0, "eps": 1.0, "dt": 1.0,
        "dynamics": "relaxational", "stop_residual": 1e-5, "max_steps": 400,
        "initial": {"shape": "axisym", "branch": "prolate", "reduced_volume": 0.8, "r0": 10.0}
    }));
    let (problem, mut sim) = simulation(&s);
    let steps = relax(&mut sim, 1e-5, 400);
    let phi = problem.grid.unfold(sim.engine().phi());
    let (along, across) = (extent(&phi, 2), extent(&phi, 0));
    eprintln!("prolate: {steps:?} iterations, extent {along} along the axis, {across} across");
    assert!(along as f64 > 1.5 * across as f64, "{along} vs {across}");
}

/// An oblate at v = 0.65: at R0 = 15ε the reference start reaches residual 1e-5 in fewer L-BFGS
/// iterations than the spheroid of the same v and R0 (measured 157 against 223), and ends near
/// the requested v. At R0 = 10ε (printed, not asserted) the spheroid needs fewer (82 against
/// 95), but it relaxes to another shape: its φ = 0 v ends at 0.698, the reference's at 0.649.
#[test]
fn reference_start_needs_fewer_iterations_than_a_spheroid() {
    let run = |initial: Value| {
        let r0 = initial["r0"].as_f64().unwrap();
        let n = if r0 > 12.0 {
            [52, 52, 24]
        } else {
            [32, 32, 16]
        };
        let s = scene(json!({
            "dim": 3, "n": n, "h": 1.0, "eps": 1.0, "dt": 1.0,
            "dynamics": "relaxational", "stop_residual": 1e-5, "max_steps": 3000,
            "initial": initial
        }));
        let (problem, mut sim) = simulation(&s);
        let steps = relax(&mut sim, 1e-5, 3000).expect("relaxes to 1e-5");
        let phi = problem.grid.unfold(sim.engine().phi());
        (steps, levelset::measure(&phi, 3, 1.0).reduced_volume)
    };
    for r0 in [10.0, 15.0] {
        let (spheroid, v_s) = run(json!({"shape": "spheroid", "kind": "oblate",
                                     "reduced_volume": 0.65, "r0": r0}));
        let (reference, v_r) = run(json!({"shape": "axisym", "branch": "oblate",
                                      "reduced_volume": 0.65, "r0": r0}));
        eprintln!(
            "oblate v = 0.65, R0 = {r0}ε, to residual 1e-5: spheroid start {spheroid} iterations \
             (final v {v_s:.4}), axisym start {reference} iterations (final v {v_r:.4})"
        );
        if r0 > 12.0 {
            assert!(reference < spheroid, "{reference} vs {spheroid}");
        }
    }
}

/// A 96³ field (R0 = 30ε, the §7 scale) is built, its φ = 0 surface reproducing the requested
/// v to 0.01 (as at R0 = 12 above, with a smaller h/R0); its build time is printed, not
/// asserted (a wall-clock bound fails on a loaded machine).
#[test]
fn field_of_96_cubed_builds() {
    let s = scene(json!({
        "dim": 3, "n": [96, 96, 96], "h": 1.0, "eps": 1.0, "dt": 1.0, "max_steps": 1,
        "initial": {"shape": "axisym", "branch": "stomatocyte", "reduced_volume": 0.6, "r0": 30.0},
        "symmetry": []
    }));
    let t = Instant::now();
    let p = setup::build(&s).expect("problem");
    let secs = t.elapsed().as_secs_f64();
    eprintln!("96³ stomatocyte field (solve + distance): {secs:.2} s");
    assert_eq!(p.phi.len(), 96 * 96 * 96);
    let full = p.grid.unfold(&p.phi).into_owned();
    let ls = levelset::measure(&full, 3, 1.0);
    assert!(
        (ls.reduced_volume - 0.6).abs() < 0.01,
        "v = {}",
        ls.reduced_volume
    );
}
