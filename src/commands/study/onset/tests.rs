use super::report::extrapolate;
use super::*;

fn onset(r0: f64, seed: f64, shift: f64) -> Onset {
    Onset {
        r0,
        seed,
        below: f64::NAN,
        above: f64::NAN,
        onset: 3.6 + shift,
        v: 0.787,
        c0: 3.6 + shift,
        da_surface: f64::NAN,
        sharp: 3.6,
        shift,
        sharp_c0: 3.6,
        shift_c0: shift,
        relaxations: 0,
        wall_seconds: 0.0,
    }
}

/// Shifts that follow s = s0 + b ε/R0 exactly (s0 = 0.01, b = −4) extrapolate to s0 by both
/// fits; a seed whose finest two points bend away from the line over every R0 gives two
/// different intercepts (here the finest pair's line, through (1/40, 0) and (1/28, −0.05),
/// meets ε/R0 = 0 at +0.1167).
#[test]
fn the_shift_extrapolates_linearly_in_eps_over_r0() {
    let spec: Spec = serde_json::from_value(serde_json::json!({
        "study": "onset", "scene": {}, "v": 0.8, "r0": [20.0, 28.0, 40.0],
        "seeds": [0.02, 0.05], "c0": [3.0, 3.5], "bisections": 3
    }))
    .expect("a spec");
    let mut onsets: Vec<Onset> = [20.0, 28.0, 40.0]
        .iter()
        .map(|&r| onset(r, 0.02, 0.01 - 4.0 / r))
        .collect();
    onsets.extend([(20.0, -0.3), (28.0, -0.05), (40.0, 0.0)].map(|(r, s)| onset(r, 0.05, s)));
    let e = extrapolate(&spec, &onsets);
    assert!((e[0].all - 0.01).abs() < 1e-12 && (e[0].finest - 0.01).abs() < 1e-12);
    let finest = 0.05 / (1.0 / 28.0 - 1.0 / 40.0) / 40.0;
    assert!((e[1].finest - finest).abs() < 1e-12, "{}", e[1].finest);
    assert!((e[1].all - e[1].finest).abs() > 0.05);
}

/// Shifts that follow s(δ) = s0 − gδ² (s0 = 0.1, g = 400: 0.09, 0.06, −0.06 at δ = 0.005,
/// 0.01, 0.02) give s0 and g back to round-off, with no misfit; moving one seed's shift by 0.01
/// shows as a misfit of that order.
#[test]
fn the_shift_of_a_vanishing_seed_is_the_intercept_in_seed_squared() {
    let spec: Spec = serde_json::from_value(serde_json::json!({
        "study": "onset", "scene": {}, "v": 0.8, "r0": [20.0],
        "seeds": [0.005, 0.01, 0.02], "c0": [3.0, 3.5], "bisections": 3
    }))
    .expect("a spec");
    let mut onsets: Vec<Onset> = spec
        .seeds
        .iter()
        .map(|&d| onset(20.0, d, 0.1 - 400.0 * d * d))
        .collect();
    let limits = super::report::seed_limits(&spec, &onsets);
    assert_eq!(limits.len(), 1);
    let l = limits[0];
    assert_eq!(l.seeds, 3);
    assert!((l.shift - 0.1).abs() < 1e-12, "{}", l.shift);
    assert!((l.g - 400.0).abs() < 1e-9, "{}", l.g);
    assert!(l.misfit < 1e-12);
    onsets[1].shift += 0.01;
    let moved = super::report::seed_limits(&spec, &onsets)[0];
    assert!(
        moved.misfit > 0.003 && moved.misfit < 0.01,
        "{}",
        moved.misfit
    );
}
