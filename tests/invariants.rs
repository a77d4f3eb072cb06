//! Property tests: for random smooth initial fields (a few random Fourier modes around a
//! circle), both engines conserve V to round-off and never raise F_eff at a stable Δt.

mod common;
use common::{rel, scene};
use proptest::prelude::*;
use serde_json::json;
use vesicle::driver::simulation::Simulation;
use vesicle::problem::setup;

/// A circle of radius 7 with a perturbation Σ a_m cos(m θ + b_m) of its radius, as a `.npy`.
fn perturbed_field(dir: &std::path::Path, modes: &[(f64, f64)]) -> std::path::PathBuf {
    let n = 32usize;
    let phi = ndarray::Array3::from_shape_fn((1, n, n), |(_, i, j)| {
        let (x, y) = (i as f64 + 0.5 - 16.0, j as f64 + 0.5 - 16.0);
        let theta = y.atan2(x);
        let r = 7.0
            + modes
                .iter()
                .enumerate()
                .map(|(m, (a, b))| a * ((m as f64 + 2.0) * theta + b).cos())
                .sum::<f64>();
        ((r - (x * x + y * y).sqrt()) / std::f64::consts::SQRT_2).tanh()
    });
    let path = dir.join("phi.npy");
    vesicle::output::npy::write_npy(&path, &phi, 2).unwrap();
    path
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]

    /// V to 1e-12 (relative) and F_eff(φⁿ⁺¹) + σⁿA(φⁿ⁺¹) ≤ F_eff(φⁿ) + σⁿA(φⁿ) on every
    /// step, FD at half its bound (Lagrangian area) and spectral SBDF1 at Δt = 0.5 (projection).
    #[test]
    fn volume_conserved_and_energy_non_increasing(
        modes in prop::collection::vec((-1.0f64..1.0, 0.0f64..std::f64::consts::TAU), 1..4),
        c0 in -0.2f64..0.2,
    ) {
        let dir = tempfile::tempdir().unwrap();
        let file = perturbed_field(dir.path(), &modes);
        for (method, dt) in [("fd", 6e-4), ("spectral", 0.5)] {
            let s = scene(json!({
                "dim": 2, "n": [32, 32], "method": method, "dt": dt, "max_steps": 40,
                "initial": {"file": file}, "c0": c0
            }));
            let problem = setup::build(&s).unwrap();
            let mut e = Simulation::of_scene(&s, &problem).unwrap().0.into_engine();
            let v0 = e.measures().volume;
            for n in 0..40 {
                let (before, sigma) = (e.measures(), e.sigma());
                e.step(n as f64 * dt, dt).unwrap();
                let after = e.measures();
                let f0 = before.energy + sigma * before.area;
                let f1 = after.energy + sigma * after.area;
                prop_assert!(rel(after.volume, v0) < 1e-12, "{method}: V drifted");
                prop_assert!(f1 <= f0 + 1e-12 * f0.abs(), "{method} step {n}: F_eff {f0} -> {f1}");
            }
        }
    }
}
