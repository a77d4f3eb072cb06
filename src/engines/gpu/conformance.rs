//! The GPU's passes against the CPU's, pass by pass, on random fields (a GPU is needed: the
//! tests are ignored by default and run by `benches/device_check.sh` with `--ignored`; CI
//! compiles them). Each pass of [`super::GpuPasses`] (the kernels of `kernels.cu`, their launch
//! arguments, cuFFT's layout and scaling) must give what the same pass of
//! [`CpuPasses`](crate::engines::spectral::CpuPasses) gives from the same state, to round-off:
//! the two differ only in the order of their sums (1e-12 relative for sums, 1e-12 of the largest
//! value for arrays). A kernel argument out of place, a table or a factor wrong, a transform
//! scaled by n, misses by far more.

use super::GpuEngine;
use crate::engines::spectral::{DeviceState, Passes, SpectralEngine};
use crate::engines::{AreaConstraint, Engine, SavedArray};
use crate::problem::config::{self, AreaMethod};
use ndarray::Array3;
use num_complex::Complex64;

/// A scene on a 32 × 24 × 28 periodic box with a uniform c0 and the given `scheme`.
fn scene(scheme: &str, adaptive: bool) -> config::Scene {
    config::from_value(
        serde_json::json!({"dim": 3, "n": [32, 24, 28], "h": 1.0, "eps": 1.0,
        "method": "spectral", "scheme": scheme, "dt": 0.5, "adaptive": adaptive,
        "max_steps": 30, "c0": 0.02, "device": "gpu",
        "initial": {"shape": "ellipsoid", "axes": [10.0, 7.0, 8.0]}}),
    )
    .expect("scene")
}

/// An ellipsoid's profile with uniform noise of amplitude 0.05 (a fixed-seed LCG): every mode
/// of the box is populated.
fn random_field(scene: &config::Scene) -> (crate::problem::setup::Problem, Array3<f64>) {
    let pb = crate::problem::setup::build(scene).expect("problem");
    let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
    let phi = pb.phi.mapv(|p| {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        p + 0.05 * ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5)
    });
    (pb, phi)
}

/// The engines on the CPU and the GPU holding the same random field.
fn engines(scheme: &str, adaptive: bool) -> (SpectralEngine, GpuEngine) {
    let scene = scene(scheme, adaptive);
    let (pb, phi) = random_field(&scene);
    let cpu = SpectralEngine::new(&scene, pb.grid.clone(), pb.c0.clone(), phi.clone())
        .expect("cpu engine");
    let gpu = GpuEngine::new(&scene, pb.grid, pb.c0, phi).expect("a usable GPU");
    (cpu, gpu)
}

/// |a − b| ≤ 1e-12 |b| (sums).
fn close(what: &str, a: f64, b: f64) {
    assert!(
        (a - b).abs() <= 1e-12 * b.abs().max(1e-300),
        "{what}: GPU {a:e} against CPU {b:e}"
    );
}

/// max|a − b| ≤ 1e-12 max|b| over two arrays.
fn close_arrays<T>(what: &str, a: &Array3<T>, b: &Array3<T>, norm: impl Fn(T) -> f64)
where
    T: Copy + std::ops::Sub<Output = T>,
{
    assert_eq!(a.shape(), b.shape(), "{what}: shapes");
    let largest = b.iter().map(|&v| norm(v)).fold(0.0, f64::max);
    let diff = a
        .iter()
        .zip(b)
        .map(|(&x, &y)| norm(x - y))
        .fold(0.0, f64::max);
    assert!(
        diff <= 1e-12 * largest,
        "{what}: differs by {diff:e} of {largest:e}"
    );
}

/// The current spectrum and history of `p`, on the host.
fn spectra(p: &impl Passes) -> Vec<Array3<Complex64>> {
    let (hat, history) = p.spectra();
    std::iter::once(hat)
        .chain(history.into_iter().flatten())
        .map(|a| match a {
            SavedArray::Complex(c) => c.into_owned(),
            _ => panic!("spectra are complex"),
        })
        .collect()
}

/// The evaluation (hermitian, inverse_inputs, the transforms, pointwise, combine), the area
/// quadratic and the update of one and two levels of history, the mean mode and the step's
/// evaluation, pass by pass.
#[test]
#[ignore = "needs an NVIDIA GPU: run by benches/device_check.sh"]
fn each_pass_matches_the_cpu() {
    let (mut cpu, mut gpu) = engines("sbdf2", false);
    let (c, g) = (cpu.passes_mut(), gpu.passes_mut());
    let (mc, mg) = (c.states().cur.measures(), g.states().cur.measures());
    close("F of the evaluation", mg.energy, mc.energy);
    close("A of the evaluation", mg.area, mc.area);
    close("V of the evaluation", mg.volume, mc.volume);
    let residuals = (g.states().cur.residual(), c.states().cur.residual());
    close("residual of the evaluation", residuals.0, residuals.1);
    close_arrays("φ", g.phi(), c.phi(), f64::abs);
    close_arrays("φ̂", &spectra(g)[0], &spectra(c)[0], |z| z.norm());
    let mut t = 0.0;
    for (step, dt) in [0.5, 0.7, 0.3].into_iter().enumerate() {
        let u = cpu.update(dt);
        assert_eq!(u.levels(), if step == 0 { 1 } else { 2 });
        let (c, g) = (cpu.passes_mut(), gpu.passes_mut());
        let [pc, qc, rc] = c.area_quadratic(&u).expect("cpu");
        let [pg, qg, rg] = g.area_quadratic(&u).expect("GPU area_quadratic");
        close("A_PP", pg, pc);
        close("A_PQ", qg, qc);
        close("A_QQ", rg, rc);
        let sigma = 0.3 - 0.2 * step as f64;
        let area = c.write_update(&u, sigma).expect("cpu");
        close(
            "area of the update",
            g.write_update(&u, sigma).expect("GPU write_update"),
            area,
        );
        let mean = 2.0 * (step as f64) - 3000.0;
        c.set_mean_mode(mean).expect("cpu");
        g.set_mean_mode(mean).expect("GPU set_mean_mode");
        t += dt;
        let change_cpu = c.finish_next(area, t, sigma).expect("cpu").expect("finite");
        let change_gpu = g
            .finish_next(area, t, sigma)
            .expect("GPU finish")
            .expect("finite");
        close("max|φ^{n+1} − φ^n|", change_gpu, change_cpu);
        let (nc, ng) = (c.states().next.measures(), g.states().next.measures());
        close("F of the step", ng.energy, nc.energy);
        close("V of the step", ng.volume, nc.volume);
        c.accept(true).expect("cpu");
        g.accept(true).expect("GPU accept");
        let residuals = (g.states().cur.residual(), c.states().cur.residual());
        close("residual of the step", residuals.0, residuals.1);
        close_arrays("φ after the step", g.phi(), c.phi(), f64::abs);
        for (i, (a, b)) in spectra(g).iter().zip(&spectra(c)).enumerate() {
            close_arrays(&format!("spectrum {i} after step {step}"), a, b, |z| {
                z.norm()
            });
        }
    }
}

/// Whole runs through the shared stepper: SBDF1 fixed steps and SBDF2 adaptive steps with the
/// exact projection (A0 raised by 0.1%), 30 steps each; φ to 1e-10 and σ to 1e-9 (relative),
/// the steps and rejections the same.
#[test]
#[ignore = "needs an NVIDIA GPU: run by benches/device_check.sh"]
fn runs_match_the_cpu() {
    for (scheme, adaptive) in [("sbdf1", false), ("sbdf2", true)] {
        let (mut cpu, mut gpu) = engines(scheme, adaptive);
        let constraint = AreaConstraint {
            method: AreaMethod::Projection,
            alpha: 0.0,
            target: cpu.measures().area * 1.001,
            sigma: 0.0,
        };
        cpu.set_area(constraint);
        gpu.set_area(constraint);
        let (mut t, mut dt_cpu, mut dt_gpu) = (0.0, 0.5, 0.5);
        for step in 0..30 {
            let a = cpu.step(t, dt_cpu).expect("cpu step");
            let b = gpu.step(t, dt_gpu).expect("GPU step");
            assert_eq!(a.rejected, b.rejected, "{scheme} step {step}: rejections");
            close(&format!("{scheme} step {step}: dt"), b.dt, a.dt);
            t += a.dt;
            dt_cpu = cpu.next_dt(a.dt);
            dt_gpu = gpu.next_dt(b.dt);
        }
        let dphi = (cpu.phi() - gpu.phi())
            .mapv(f64::abs)
            .fold(0.0, |m: f64, v| m.max(*v));
        assert!(dphi <= 1e-10, "{scheme}: max|Δφ| = {dphi:e}");
        let ds = (cpu.sigma() - gpu.sigma()).abs() / cpu.sigma().abs();
        assert!(
            ds <= 1e-9,
            "{scheme}: σ {} against {}",
            gpu.sigma(),
            cpu.sigma()
        );
    }
}
