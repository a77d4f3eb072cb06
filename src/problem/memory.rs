//! Peak-memory estimate of a run, checked against the machine's available memory before
//! anything is allocated, so that a grid that cannot fit is refused (exit 2, field `n`)
//! instead of aborting in the allocator or being killed by the kernel half-way.
//!
//! The figures are f64 per computed point (after the mirror reduction), measured with
//! `/usr/bin/time -v` (maximum resident set size) on 96³ runs, one thread, minus the
//! [`BASE_BYTES`] a tiny run takes:
//!
//! | engine | periodic last axis | mirrored last axis | every axis mirrored |
//! |---|---|---|---|
//! | FD explicit Euler | 5.5 | 8.4 | 8.4 |
//! | spectral SBDF1 | 7.9 | 16.1 | 10.9 |
//! | spectral SBDF2 | 9.9 | 20.0 | 12.7 |
//! | relaxational (L-BFGS, m pairs) | 9.9 + 1.03 m | 20.3 + 2.0 m | 12.7 + 0.98 m |
//!
//! A mirrored last axis makes every spectrum a full complex array (2 f64 per point) instead of
//! the real-to-complex half spectrum (about 1), unless every axis is mirrored: that spectrum is
//! real and stored packed, 1 f64 per point ([`crate::engines::spectral::transform::Transform::packed`]).
//! A reduced box also pays [`FULL_BOX_F64`] f64 per point of the full box: writing the final
//! field unfolds it into one new full-box array while the engine is still alive. A full box
//! writes its field as it is, with no copy.
//!
//! Measured 2026-12-03 at 44f1b66 (14 steps or iterations of a 96³ ellipsoid, then the final
//! outputs and checkpoint; the mirrored figures on the eighth box less its 1 × 8 full-box f64;
//! the L-BFGS rows from memories 2 and 8); the last column the same way at the build that packed
//! those spectra, when the build before still gave the middle column's figures (16.0, 20.0, and
//! 24.1 and 35.7 with memories 2 and 8). The run's last checkpoint is inside them: it is written
//! from the engine's own arrays (φ̂, SBDF2's previous step, the L-BFGS pairs, stored in single
//! precision) through a 1 MiB buffer, with no copy of them beside the engine.

use crate::error::{Error, Result};
use crate::problem::config::{Dynamics, Method, Scene, Scheme, Symmetry};

/// Resident memory of a run on a tiny grid: binary, thread stacks, font and plot buffers.
pub const BASE_BYTES: f64 = 12.0 * 1024.0 * 1024.0;

/// f64 per full-box point a reduced-box run adds when it writes the unfolded final field.
pub const FULL_BOX_F64: f64 = 1.0;

/// The estimate for one scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// Peak resident bytes.
    pub bytes: f64,
    /// Computed points (after the mirror reduction).
    pub points: f64,
    /// `bytes` (less [`BASE_BYTES`]) as f64 per computed point.
    pub f64_per_point: f64,
}

/// f64 per computed point of the scene's engine, with the mirror flags `mirror` (one per scene
/// axis): a column of the table above.
pub fn engine_f64_per_point(scene: &Scene, mirror: &[bool]) -> f64 {
    let (last, all) = (mirror.last() == Some(&true), mirror.iter().all(|&m| m));
    let pick = |periodic: f64, mirrored: f64, packed: f64| match (last, all) {
        (false, _) => periodic,
        (true, false) => mirrored,
        (true, true) => packed,
    };
    match (scene.method, scene.dynamics, scene.scheme) {
        (Method::Fd, _, _) => pick(5.5, 8.4, 8.4),
        (Method::Spectral, Dynamics::Relaxational, _) => {
            let m = scene.lbfgs_memory as f64;
            pick(9.9 + 1.03 * m, 20.3 + 2.0 * m, 12.7 + 0.98 * m)
        }
        (Method::Spectral, Dynamics::Conserved, Scheme::Sbdf1) => pick(7.9, 16.1, 10.9),
        (Method::Spectral, Dynamics::Conserved, Scheme::Sbdf2) => pick(9.9, 20.0, 12.7),
        // The flow's scratch on the periodic box: 3 + d real fields and 1 + d half spectra
        // (10 f64 per point in 3D), beside the conserved step's arrays.
        (Method::Spectral, Dynamics::Stokes, Scheme::Sbdf1) => 7.9 + 10.0 + flow_solves(scene),
        (Method::Spectral, Dynamics::Stokes, Scheme::Sbdf2) => 9.9 + 10.0 + flow_solves(scene),
    }
}

/// The iterative solves' scratch, counted (3D, periodic box). Unequal viscosities: 2 real fields
/// and 1 + 5d half spectra (the right-hand sides of both parts and three of conjugate gradients
/// per component), 18 f64 a point. The inextensible membrane's tension solve: 21 real fields (the
/// six weights T_ab and |g|², the four of conjugate gradients, ∇p, a scratch field, σ of the
/// last solves and of the two accepted states) and 8 half spectra (two of scratch, S Bᵀp and
/// the unconstrained flow per component): 29 f64 a point (23 in 2D). Measured in 2D at 1024²
/// at a fixed tension (3 steps, peak resident): 20.0 f64 a point above the same run at one
/// global tension, the count less the three fields of the part per unit σ, which a fixed
/// tension never writes.
fn flow_solves(scene: &Scene) -> f64 {
    match &scene.flow {
        Some(flow) if flow.inextensible => 29.0,
        Some(flow) if flow.contrast().is_some() => 18.0,
        _ => 0.0,
    }
}

/// Estimate with the given mirror flags (one per scene axis).
fn estimate_with(scene: &Scene, mirror: &[bool]) -> Estimate {
    let full: f64 = scene.n.iter().map(|&m| m as f64).product();
    let mirrored = mirror.iter().filter(|m| **m).count();
    let points = full / f64::from(1u32 << mirrored);
    let per_point = engine_f64_per_point(scene, mirror);
    let full_box = if mirrored > 0 {
        FULL_BOX_F64 * full
    } else {
        0.0
    };
    let f64s = per_point * points + full_box;
    Estimate {
        bytes: 8.0 * f64s + BASE_BYTES,
        points,
        f64_per_point: f64s / points,
    }
}

/// Peak-memory estimate of a validated scene. With `"symmetry": "auto"` the mirror planes are
/// not known before the field is built: the larger of no mirror and every even axis mirrored.
pub fn estimate(scene: &Scene) -> Estimate {
    match &scene.symmetry {
        Symmetry::Axes(names) => {
            let mirror: Vec<bool> = (0..scene.dim)
                .map(|a| {
                    names
                        .iter()
                        .any(|s| crate::problem::config::axis_index(s, scene.dim) == Some(a))
                })
                .collect();
            estimate_with(scene, &mirror)
        }
        Symmetry::Auto(_) => {
            let none = estimate_with(scene, &vec![false; scene.dim]);
            let even: Vec<bool> = scene.n.iter().map(|m| m % 2 == 0).collect();
            let all = estimate_with(scene, &even);
            if all.bytes > none.bytes {
                all
            } else {
                none
            }
        }
    }
}

/// `MemAvailable` of `/proc/meminfo` in bytes, or `None` if it cannot be read.
pub fn available_bytes() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    parse_mem_available(&text)
}

fn parse_mem_available(text: &str) -> Option<f64> {
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let mut words = line.split_whitespace().skip(1);
    let value: f64 = words.next()?.parse().ok()?;
    let unit = match words.next() {
        Some("kB") | Some("KB") => 1024.0,
        Some("mB") | Some("MB") => 1024.0 * 1024.0,
        None | Some("B") => 1.0,
        Some(_) => return None,
    };
    Some(value * unit)
}

/// Bytes in decimal units: "912 B", "3.4 MB", "1.9 TB".
pub fn human_bytes(bytes: f64) -> String {
    const UNITS: [&str; 7] = ["B", "kB", "MB", "GB", "TB", "PB", "EB"];
    let mut x = bytes;
    let mut u = 0;
    while x >= 1000.0 && u + 1 < UNITS.len() {
        x /= 1000.0;
        u += 1;
    }
    if u == 0 {
        format!("{x:.0} B")
    } else {
        format!("{x:.1} {}", UNITS[u])
    }
}

/// The engine's name in messages.
fn engine_name(scene: &Scene) -> &'static str {
    match (scene.method, scene.dynamics, scene.scheme) {
        (Method::Fd, _, _) => "fd",
        (_, Dynamics::Relaxational, _) => "relaxational (L-BFGS)",
        (_, Dynamics::Stokes, Scheme::Sbdf1) => "spectral sbdf1 with stokes flow",
        (_, Dynamics::Stokes, Scheme::Sbdf2) => "spectral sbdf2 with stokes flow",
        (_, _, Scheme::Sbdf1) => "spectral sbdf1",
        (_, _, Scheme::Sbdf2) => "spectral sbdf2",
    }
}

/// Refuse a scene whose estimated peak memory exceeds `available` bytes.
///
/// # Errors
/// `Error::Config` on field `n` with the estimate (bytes and f64 per point) and the memory
/// available.
pub fn check_against(scene: &Scene, available: f64) -> Result<()> {
    let e = estimate(scene);
    if e.bytes <= available {
        return Ok(());
    }
    Err(Error::config(
        "n",
        format!(
            "the grid {:?} ({:.3e} computed points) needs about {} ({:.0} bytes, {:.1} f64 per \
             computed point with the {} engine), more than the {} available (MemAvailable in \
             /proc/meminfo); use a smaller n or mirror planes (`symmetry`)",
            scene.n,
            e.points,
            human_bytes(e.bytes),
            e.bytes,
            e.f64_per_point,
            engine_name(scene),
            human_bytes(available)
        ),
    ))
}

/// Refuse a scene that would not fit in the machine's available memory; no check when
/// `/proc/meminfo` cannot be read.
///
/// # Errors
/// As [`check_against`].
pub fn check(scene: &Scene) -> Result<()> {
    match available_bytes() {
        Some(avail) => check_against(scene, avail),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn scene(extra: serde_json::Value) -> Scene {
        let mut v = json!({
            "dim": 3, "n": [96, 96, 96], "dt": 0.01, "max_steps": 5,
            "initial": {"shape": "sphere", "radius": 6.0}
        });
        v.as_object_mut()
            .unwrap()
            .extend(extra.as_object().unwrap().clone());
        crate::problem::config::from_value(v).unwrap()
    }

    #[test]
    fn meminfo_is_parsed() {
        let text = "MemTotal:       24683584 kB\nMemFree: 1 kB\nMemAvailable:   23562016 kB\n";
        assert_eq!(parse_mem_available(text), Some(23562016.0 * 1024.0));
        assert_eq!(parse_mem_available("MemTotal: 3 kB\n"), None);
        assert_eq!(parse_mem_available("MemAvailable: x kB\n"), None);
    }

    #[test]
    fn human_units() {
        assert_eq!(human_bytes(912.0), "912 B");
        assert_eq!(human_bytes(1.9e12), "1.9 TB");
        assert_eq!(human_bytes(3.45e6), "3.5 MB");
    }

    #[test]
    fn estimates_follow_the_measured_figures() {
        let n = 96f64.powi(3);
        let e = estimate(&scene(json!({})));
        assert_eq!(e.points, n);
        assert!((e.f64_per_point - 7.9).abs() < 1e-12);
        let e = estimate(&scene(json!({"symmetry": ["x", "y", "z"]})));
        assert_eq!(e.points, n / 8.0);
        assert!((e.f64_per_point - (10.9 + 8.0)).abs() < 1e-12);
        let e = estimate(&scene(json!({"symmetry": ["y", "z"]})));
        assert_eq!(e.points, n / 4.0);
        assert!((e.f64_per_point - (16.1 + 4.0)).abs() < 1e-12);
        let stokes = |inextensible: bool| {
            let flow = json!({"viscosity": 1.0, "mobility": 0.01, "inextensible": inextensible});
            estimate(&scene(
                json!({"dynamics": "stokes", "flow": flow, "scheme": "sbdf2"}),
            ))
        };
        assert!((stokes(false).f64_per_point - 19.9).abs() < 1e-12);
        assert!((stokes(true).f64_per_point - 48.9).abs() < 1e-12);
        let flow = json!({"viscosity": 1.0, "mobility": 0.01, "viscosity_inside": 5.0});
        let e = estimate(&scene(json!({"dynamics": "stokes", "flow": flow})));
        assert!((e.f64_per_point - (7.9 + 10.0 + 18.0)).abs() < 1e-12);
        let e = estimate(&scene(
            json!({"dynamics": "relaxational", "lbfgs_memory": 10}),
        ));
        assert!((e.f64_per_point - 20.2).abs() < 1e-12);
        // auto: the larger of the two layouts
        let auto = estimate(&scene(json!({"symmetry": "auto"})));
        let all = estimate(&scene(json!({"symmetry": ["x", "y", "z"]})));
        assert_eq!(auto.bytes, all.bytes.max(estimate(&scene(json!({}))).bytes));
    }

    #[test]
    fn a_huge_grid_is_refused_naming_n() {
        let s = scene(json!({"n": [4096, 4096, 4096]}));
        match check_against(&s, 16e9) {
            Err(Error::Config { field, reason }) => {
                assert_eq!(field, "n");
                assert!(reason.contains("4.3 TB"), "{reason}");
                assert!(reason.contains("7.9 f64 per"), "{reason}");
                assert!(reason.contains("16.0 GB"), "{reason}");
            }
            other => panic!("{other:?}"),
        }
        assert!(check_against(&scene(json!({})), 16e9).is_ok());
    }
}
