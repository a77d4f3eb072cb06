//! The GPU engine's passes in plain Rust on the CPU's transforms (tests only): the engine's
//! logic, run on this backend, must give the CPU spectral engine's results.

use super::backend::{tables, Backend, UpdateArgs};
use super::engine::DeviceEngine;
use crate::engines::spectral::transform::Transform;
use crate::engines::spectral::SpectralEngine;
use crate::engines::{AreaConstraint, Engine};
use crate::problem::config::{self, AreaMethod, Laplacian};
use crate::problem::grid::Grid;
use ndarray::{Array3, Zip};
use num_complex::Complex64;
use std::cell::RefCell;

/// A CPU stand-in for the GPU (see the module documentation).
pub struct HostDevice {
    transform: RefCell<Transform>,
    tables: [Vec<f64>; 6],
    shape: [usize; 3],
    spectral: [usize; 3],
}

impl HostDevice {
    pub fn new(grid: &Grid, laplacian: Laplacian) -> Self {
        let transform = Transform::new(grid.shape, grid.kinds, 1);
        let spectral = transform.spectral_shape();
        HostDevice {
            transform: RefCell::new(transform),
            tables: tables(grid, laplacian),
            shape: grid.shape,
            spectral,
        }
    }

    /// |k|² and w at mode (i0, i1, i2).
    fn at(&self, (i0, i1, i2): (usize, usize, usize)) -> (f64, f64) {
        let t = &self.tables;
        (
            t[0][i0] + t[1][i1] + t[2][i2],
            t[3][i0] * t[4][i1] * t[5][i2],
        )
    }

    /// |k|², w, P̂ and Q̂ of the update `u` at mode `ix` (`update_at` of `kernels.cu`).
    fn update_at(
        &self,
        ix: (usize, usize, usize),
        cur: (&Array3<Complex64>, &Array3<Complex64>),
        prev: Option<(&Array3<Complex64>, &Array3<Complex64>)>,
        u: &UpdateArgs,
    ) -> (f64, f64, Complex64, Complex64) {
        let (k, w) = self.at(ix);
        let zero = Complex64::new(0.0, 0.0);
        let (x0, n0) = prev.map_or((zero, zero), |(h, n)| (h[ix], n[ix]));
        let (p, q) = u.apply(k, prev.is_some(), [cur.0[ix], cur.1[ix], x0, n0]);
        (k, w, p, q)
    }
}

impl Backend for HostDevice {
    type Spectrum = Array3<Complex64>;
    type Field = Array3<f64>;

    fn spectral_shape(&self) -> [usize; 3] {
        self.spectral
    }

    fn points(&self) -> usize {
        self.shape.iter().product()
    }

    fn spectrum(&self) -> Result<Self::Spectrum, String> {
        Ok(Array3::zeros(self.spectral))
    }

    fn field(&self) -> Result<Self::Field, String> {
        Ok(Array3::zeros(self.shape))
    }

    fn upload_field(&self, from: &[f64], to: &mut Self::Field) -> Result<(), String> {
        to.as_slice_mut().expect("layout").copy_from_slice(from);
        Ok(())
    }

    fn download_field(&self, from: &Self::Field) -> Result<Vec<f64>, String> {
        Ok(from.iter().cloned().collect())
    }

    fn upload_spectrum(&self, from: &Array3<Complex64>) -> Result<Self::Spectrum, String> {
        Ok(from.clone())
    }

    fn download_spectrum(&self, from: &Self::Spectrum) -> Result<Array3<Complex64>, String> {
        Ok(from.clone())
    }

    fn copy_spectrum(&self, from: &Self::Spectrum, to: &mut Self::Spectrum) -> Result<(), String> {
        to.assign(from);
        Ok(())
    }

    fn hermitian(&self, a: &mut Self::Spectrum) -> Result<(), String> {
        let [n0, n1, _] = self.shape;
        let n2 = self.shape[2];
        let planes: &[usize] = if n2.is_multiple_of(2) {
            &[0, n2 / 2]
        } else {
            &[0]
        };
        for &i2 in planes {
            for i0 in 0..n0 {
                for i1 in 0..n1 {
                    let (p0, p1) = ((n0 - i0) % n0, (n1 - i1) % n1);
                    if (i0 * n1 + i1) > (p0 * n1 + p1) {
                        continue;
                    }
                    let (x, y) = (a[(i0, i1, i2)], a[(p0, p1, i2)]);
                    let v = Complex64::new((x.re + y.re) * 0.5, (x.im - y.im) * 0.5);
                    a[(i0, i1, i2)] = v;
                    a[(p0, p1, i2)] = v.conj();
                }
            }
        }
        Ok(())
    }

    fn inverse_inputs(
        &self,
        hat: &Self::Spectrum,
        copy: &mut Self::Spectrum,
        lap: &mut Self::Spectrum,
        ap: f64,
    ) -> Result<f64, String> {
        let mut area = 0.0;
        for ((ix, h), (c, l)) in hat.indexed_iter().zip(copy.iter_mut().zip(lap.iter_mut())) {
            let (k, w) = self.at(ix);
            *c = *h;
            *l = -(*h * k);
            area += ap * k * w * h.norm_sqr();
        }
        Ok(area)
    }

    fn inverse(&self, input: &mut Self::Spectrum, out: &mut Self::Field) -> Result<(), String> {
        self.transform.borrow_mut().inverse(input, out);
        let n = self.points() as f64;
        out.mapv_inplace(|v| v * n);
        Ok(())
    }

    fn forward(&self, input: &Self::Field, out: &mut Self::Spectrum) -> Result<(), String> {
        let mut scratch = input.clone();
        self.transform.borrow_mut().forward(&mut scratch, out);
        Ok(())
    }

    fn pointwise(
        &self,
        phi: &mut Self::Field,
        lap: &mut Self::Field,
        fphi: &mut Self::Field,
        old: Option<&Self::Field>,
        e2: f64,
        ec0: f64,
    ) -> Result<[f64; 4], String> {
        let inv_n = 1.0 / self.points() as f64;
        let mut s = [0.0; 4];
        Zip::indexed(&mut *phi)
            .and(&mut *lap)
            .and(&mut *fphi)
            .for_each(|ix, p, l, fp| {
                let v = *p * inv_n;
                let lv = *l * inv_n;
                let f = (v + ec0) * (v * v - 1.0);
                let df = 3.0 * v * v - 1.0 + 2.0 * ec0 * v;
                let big = f - e2 * lv;
                *p = v;
                *l = f;
                *fp = df * big;
                s[0] += big * big;
                s[1] += v;
                s[2] = s[2].max(v.abs());
                if let Some(o) = old {
                    s[3] = s[3].max((v - o[ix]).abs());
                }
            });
        Ok(s)
    }

    fn combine(
        &self,
        hat: &Self::Spectrum,
        nl: &mut Self::Spectrum,
        g: &Self::Spectrum,
        e2: f64,
        tension: f64,
        residual: bool,
    ) -> Result<f64, String> {
        let mut res = 0.0;
        for ((ix, n), (gv, h)) in nl.indexed_iter_mut().zip(g.iter().zip(hat.iter())) {
            let (k, w) = self.at(ix);
            let mu = *n * 2.0 + gv * (2.0 * e2 * k) + h * (2.0 * e2 * e2 * k * k + tension * k);
            *n = *n * (-2.0 * k) + gv * (-2.0 * e2 * k * k);
            if residual && k > 0.0 {
                res += w * mu.norm_sqr();
            }
        }
        Ok(res)
    }

    fn area_quadratic(
        &self,
        cur: (&Self::Spectrum, &Self::Spectrum),
        prev: Option<(&Self::Spectrum, &Self::Spectrum)>,
        u: UpdateArgs,
        ap: f64,
    ) -> Result<[f64; 3], String> {
        let mut s = [0.0; 3];
        for ix in ndarray::indices(cur.0.dim()) {
            let (k, w, p, q) = self.update_at(ix, cur, prev, &u);
            let a = ap * k * w;
            s[0] += a * p.norm_sqr();
            s[1] += a * (p.re * q.re + p.im * q.im);
            s[2] += a * q.norm_sqr();
        }
        Ok(s)
    }

    fn write_update(
        &self,
        cur: (&Self::Spectrum, &Self::Spectrum),
        prev: Option<(&Self::Spectrum, &Self::Spectrum)>,
        u: UpdateArgs,
        ap: f64,
        sigma: f64,
        out: &mut Self::Spectrum,
        copy: &mut Self::Spectrum,
        lap: &mut Self::Spectrum,
    ) -> Result<f64, String> {
        let mut area = 0.0;
        for (ix, o) in out.indexed_iter_mut() {
            let (k, w, p, q) = self.update_at(ix, cur, prev, &u);
            let x = p + q * sigma;
            *o = x;
            copy[ix] = x;
            lap[ix] = -(x * k);
            area += ap * k * w * x.norm_sqr();
        }
        Ok(area)
    }
}

/// The GPU engine's logic on [`HostDevice`] against the CPU spectral engine, on a 32 × 24 × 28
/// periodic box holding an ellipsoid, through the preparation's A0: SBDF1 fixed steps with the
/// projection, SBDF2 adaptive steps with the projection and the Lagrangian update, 30 steps
/// each. They differ only at round-off (another order of the sums), so φ must agree to 1e-11
/// and σ to 1e-9 (relative): a wrong factor, table, buffer or order of the passes misses by
/// far more.
#[test]
fn the_engine_on_the_host_matches_the_cpu_spectral_engine() {
    let cases = [
        ("sbdf1", false, "projection"),
        ("sbdf2", true, "projection"),
        ("sbdf2", true, "lagrangian"),
    ];
    for (scheme, adaptive, area) in cases {
        let mut scene = serde_json::json!({"dim": 3, "n": [32, 24, 28], "h": 1.0, "eps": 1.0,
            "method": "spectral", "scheme": scheme, "dt": 0.5, "adaptive": adaptive,
            "max_steps": 30, "c0": 0.02, "area": {"method": area},
            "initial": {"shape": "ellipsoid", "axes": [10.0, 7.0, 8.0]}});
        if area == "lagrangian" {
            scene["area"]["alpha"] = serde_json::json!(0.001);
        }
        let scene = config::from_value(scene).expect("scene");
        let pb = crate::problem::setup::build(&scene).expect("problem");
        let mut cpu = SpectralEngine::new(&scene, pb.grid.clone(), pb.c0.clone(), pb.phi.clone())
            .expect("cpu engine");
        let dev = HostDevice::new(&pb.grid, scene.laplacian);
        let mut host =
            DeviceEngine::on(dev, &scene, pb.grid.clone(), pb.c0.clone(), pb.phi.clone())
                .expect("host engine");
        let a0 = cpu.measures().area;
        assert!(
            (host.measures().area - a0).abs() <= 1e-12 * a0,
            "{scheme}: initial area"
        );
        let method = if area == "projection" {
            AreaMethod::Projection
        } else {
            AreaMethod::Lagrangian
        };
        let constraint = AreaConstraint {
            method,
            alpha: 0.001,
            target: a0 * 1.001,
        };
        cpu.set_area(constraint);
        host.set_area(constraint);
        let (mut t, mut dt_cpu, mut dt_host) = (0.0, 0.5, 0.5);
        for step in 0..30 {
            let a = cpu.step(t, dt_cpu).expect("cpu step");
            let b = host.step(t, dt_host).expect("host step");
            assert_eq!(
                a.rejected, b.rejected,
                "{scheme} {area} step {step}: rejections"
            );
            assert!(
                (a.dt - b.dt).abs() <= 1e-12 * a.dt,
                "{scheme} step {step}: dt"
            );
            t += a.dt;
            dt_cpu = cpu.next_dt(a.dt);
            dt_host = host.next_dt(b.dt);
        }
        let dphi = (cpu.phi() - host.phi())
            .mapv(f64::abs)
            .fold(0.0, |m: f64, v| m.max(*v));
        assert!(dphi <= 1e-11, "{scheme} {area}: max|Δφ| = {dphi:e}");
        let ds = (cpu.sigma() - host.sigma()).abs() / cpu.sigma().abs().max(1e-300);
        assert!(
            ds <= 1e-9,
            "{scheme} {area}: σ {} against {}",
            cpu.sigma(),
            host.sigma()
        );
        let dr = (cpu.residual() - host.residual()).abs() / cpu.residual();
        assert!(dr <= 1e-9, "{scheme} {area}: residual");
        // The host engine's checkpoint restores into the CPU engine.
        let mut again = SpectralEngine::new(&scene, pb.grid.clone(), pb.c0.clone(), pb.phi.clone())
            .expect("cpu engine");
        again.set_area(constraint);
        again.restore(&mut host.save(), t).expect("restore");
        let back = (again.phi() - host.phi())
            .mapv(f64::abs)
            .fold(0.0, |m: f64, v| m.max(*v));
        assert!(
            back <= 1e-12,
            "{scheme} {area}: the host's checkpoint on the CPU, {back:e}"
        );
    }
}
