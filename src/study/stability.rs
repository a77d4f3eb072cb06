//! `vesicle study stability`: where each time stepper fails (validation ladder rung 7).
//!
//! For each stepper (FD explicit Euler; spectral SBDF1 without stabiliser; spectral SBDF1 and
//! SBDF2 with the scene's stabiliser) and each Δt of a geometric sweep, take `steps` fixed steps
//! from the scene's prepared field and classify the run: `stable` (F_eff never rose beyond
//! round-off), `energy rise` (it rose: the scheme is not dissipative at that Δt) or `blew up`.
//! The table gives each stepper's largest stable Δt beside the FD bound of DESIGN.md §2 and the
//! spectral frozen-coefficient bound; `stability.csv` has every run, `stability.png` charts
//! log10 max|φ| after the run against log10 Δt.

use crate::config::{AdaptiveSpec, AreaMethod, Method, Scene, Scheme, Stabilizer, StabilizerSpec};
use crate::error::Result;
use crate::fd;
use crate::output;
use crate::record::Record;
use crate::run;
use crate::setup;
use crate::simulation::{Flow, Now, Probe, Simulation, StopRules};
use crate::spectral;
use std::fmt::Write as _;
use std::path::Path;

/// Relative rise of F_eff that counts as a rise (beyond the round-off of the sums).
const RISE_TOL: f64 = 1e-10;

/// How one fixed-Δt run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// F_eff never rose.
    Stable,
    /// F_eff rose on some step.
    EnergyRise,
    /// The state diverged.
    BlewUp,
}

impl Outcome {
    fn as_str(self) -> &'static str {
        match self {
            Outcome::Stable => "stable",
            Outcome::EnergyRise => "energy rise",
            Outcome::BlewUp => "blew up",
        }
    }
}

/// One run of the sweep.
#[derive(Clone, Debug)]
pub struct Sample {
    /// Stepper name.
    pub stepper: &'static str,
    /// Time step.
    pub dt: f64,
    /// How it ended.
    pub outcome: Outcome,
    /// max|φ| at the end (or when it blew up).
    pub max_phi: f64,
}

/// The steppers compared: name and how to set up the scene.
fn steppers(scene: &Scene) -> Vec<(&'static str, Scene)> {
    let base = |method, scheme, stabilizer: StabilizerSpec| {
        let mut s = scene.clone();
        s.method = method;
        s.scheme = scheme;
        s.stabilizer = stabilizer;
        s.adaptive = AdaptiveSpec::Flag(false);
        s.allow_unstable = true;
        s.area.method = Some(AreaMethod::None);
        s.area.alpha = None;
        s
    };
    let none = StabilizerSpec {
        s2: Some(0.0),
        s4: Some(0.0),
    };
    vec![
        (
            "fd explicit Euler",
            base(Method::Fd, Scheme::Sbdf1, StabilizerSpec::default()),
        ),
        (
            "spectral SBDF1, S = 0",
            base(Method::Spectral, Scheme::Sbdf1, none),
        ),
        (
            "spectral SBDF1, S",
            base(Method::Spectral, Scheme::Sbdf1, scene.stabilizer.clone()),
        ),
        (
            "spectral SBDF2, S",
            base(Method::Spectral, Scheme::Sbdf2, scene.stabilizer.clone()),
        ),
    ]
}

/// Sweep Δt over `per_decade` values per decade in [dt_lo, dt_hi] for every stepper.
///
/// # Errors
/// `Error::Config` for an invalid scene or an existing `out` without `force`.
pub fn stability(
    scene: &Scene,
    out: &Path,
    force: bool,
    steps: usize,
    dt_lo: f64,
    dt_hi: f64,
) -> Result<Vec<Sample>> {
    run::check_out_dir(out, force)?;
    let problem = setup::build(scene)?;
    let per_decade = 4.0;
    let count = ((dt_hi / dt_lo).log10() * per_decade).ceil() as i32;
    let dts: Vec<f64> = (0..=count)
        .map(|i| dt_lo * 10f64.powf(i as f64 / per_decade))
        .collect();
    let mut samples = Vec::new();
    for (name, s) in steppers(scene) {
        for &dt in &dts {
            let mut s = s.clone();
            s.dt = dt;
            samples.push(one_run(name, &s, &problem, steps)?);
        }
    }
    run::make_out_dir(out, force)?;
    let fd_bound = fd::stability_bound(&problem.grid, scene.eps, 0.0);
    let none = Stabilizer { s2: 0.0, s4: 0.0 };
    let sp_bound = spectral::stability_bound(&problem.grid, scene.eps, &none, scene.laplacian);
    let text = table(&samples, &dts, fd_bound, sp_bound, steps);
    println!("{text}");
    super::write_text(out, "stability.txt", &text)?;
    let mut csv = String::from("stepper,dt,outcome,max_abs_phi\n");
    for x in &samples {
        let _ = writeln!(
            csv,
            "\"{}\",{},{},{}",
            x.stepper,
            x.dt,
            x.outcome.as_str(),
            x.max_phi
        );
    }
    super::write_text(out, "stability.csv", &csv)?;
    chart(out, &samples, fd_bound)?;
    Ok(samples)
}

fn one_run(
    name: &'static str,
    s: &Scene,
    problem: &setup::Problem,
    steps: usize,
) -> Result<Sample> {
    let (mut sim, _) = Simulation::of_scene(&setup_free(s), problem)?;
    let mut outcome = Outcome::Stable;
    // F_eff before each step, at the σ of that state.
    let f_eff = |r: &Record, sigma: f64| r.energy + sigma * r.area;
    let mut before = sim.record();
    let mut watch = Probe(|now: &Now| {
        let after = &now.record;
        let (f0, f1) = (f_eff(&before, before.sigma), f_eff(after, before.sigma));
        if f1 > f0 + RISE_TOL * f0.abs() {
            outcome = Outcome::EnergyRise;
        }
        before = *after;
        Ok(Flow::Continue)
    });
    let blew_up = sim
        .run(&StopRules::steps(steps), &mut [&mut watch])
        .is_err();
    let max_phi = if blew_up {
        outcome = Outcome::BlewUp;
        f64::INFINITY
    } else {
        sim.engine()
            .phi()
            .iter()
            .fold(0.0f64, |m, p| m.max(p.abs()))
    };
    Ok(Sample {
        stepper: name,
        dt: s.dt,
        outcome,
        max_phi,
    })
}

/// The scene without preparation steps (the sweep starts every run from the same field).
fn setup_free(s: &Scene) -> Scene {
    let mut s = s.clone();
    s.prepare_steps = 0;
    s
}

fn table(samples: &[Sample], dts: &[f64], fd_bound: f64, sp_bound: f64, steps: usize) -> String {
    let mut s = format!(
        "{steps} fixed steps per run, dt from {:.2e} to {:.2e}\nFD bound (DESIGN.md §2): {fd_bound:.4e}; spectral S = 0 frozen-coefficient bound: {sp_bound:.4e}\n{:<24} {:>16} {:>16}\n",
        dts[0], dts[dts.len() - 1], "stepper", "largest stable", "first failure"
    );
    let mut names: Vec<&str> = samples.iter().map(|x| x.stepper).collect();
    names.dedup();
    for name in names {
        let runs: Vec<&Sample> = samples.iter().filter(|x| x.stepper == name).collect();
        let first_fail = runs.iter().find(|x| x.outcome != Outcome::Stable);
        let stable = runs
            .iter()
            .take_while(|x| x.outcome == Outcome::Stable)
            .last()
            .map_or("none".to_string(), |x| format!("{:.3e}", x.dt));
        let fail = first_fail.map_or("none".to_string(), |x| {
            format!("{:.3e} ({})", x.dt, x.outcome.as_str())
        });
        let _ = writeln!(s, "{name:<24} {stable:>16} {fail:>16}");
    }
    s
}

fn chart(out: &Path, samples: &[Sample], fd_bound: f64) -> Result<()> {
    let mut names: Vec<&str> = samples.iter().map(|x| x.stepper).collect();
    names.dedup();
    let mut series: Vec<(&str, Vec<(f64, f64)>)> = names
        .iter()
        .map(|&n| {
            let pts = samples
                .iter()
                .filter(|x| x.stepper == n)
                .map(|x| (x.dt.log10(), x.max_phi.clamp(1e-3, 1e3)))
                .collect();
            (n, pts)
        })
        .collect();
    series.push((
        "FD bound",
        vec![(fd_bound.log10(), 1.0), (fd_bound.log10(), 100.0)],
    ));
    output::chart::write_timeseries_png(
        &out.join("stability.png"),
        &series,
        "log10 dt",
        "max |phi| after the run",
        true,
    )?;
    Ok(())
}
