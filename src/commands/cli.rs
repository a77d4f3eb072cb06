//! Command-line interface: `vesicle run | resume | check | compare | study | axisym | render |
//! measure`.
//!
//! Exit codes: 0 success, 2 invalid input (the message names the field: a scene key, `n` for a
//! grid whose estimated peak memory exceeds the memory available, `--out` for an output folder
//! that exists or cannot be written; all checked before any computation, nothing written), 3 a
//! run that blew up or broke a constraint (its last good state and summary are written), 1
//! anything else.

use crate::commands::run::{self, RunOptions};
use crate::commands::study::harness::Study as _;
use crate::error::Error;
use crate::problem::config::{self, Scene};
use clap::{Parser, Subcommand};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

const RUN_EXAMPLE: &str = "Examples:
  vesicle run runs/ellipse2d.json --out out/ellipse2d
  vesicle run runs/prolate3d_fd.json --out out/p --set t_end=1 --set output.record_every=100
  vesicle run runs/sphere3d.json --out out/s --set area.method=lagrangian --set area.alpha=0.002";

/// Phase-field simulation of lipid vesicle shapes (Campelo & Hernández-Machado model).
#[derive(Parser, Debug)]
#[command(name = "vesicle", version, after_help = RUN_EXAMPLE)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// Scene file and overrides shared by the subcommands.
#[derive(clap::Args, Debug)]
struct SceneArgs {
    /// Scene (run) file, JSON.
    scene: PathBuf,
    /// Override a scene field: `key=value`, dotted keys for nested fields (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
}

/// Where a command writes.
#[derive(clap::Args, Debug)]
struct OutArgs {
    /// Output folder (default: out/<scene name>[-<command>]); never overwritten without --force.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Replace an existing output folder.
    #[arg(long)]
    force: bool,
}

impl OutArgs {
    /// The folder: `--out`, or `out/<scene stem><suffix>`.
    fn folder(&self, scene: &Path, suffix: &str) -> PathBuf {
        self.out.clone().unwrap_or_else(|| {
            let stem = scene
                .file_stem()
                .map_or("run".into(), |s| s.to_string_lossy().to_string());
            PathBuf::from("out").join(format!("{stem}{suffix}"))
        })
    }
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run a scene: writes timeseries.csv, summary.json, phi_final.npy/.vti and PNG images.
    #[command(after_help = RUN_EXAMPLE)]
    Run {
        #[command(flatten)]
        scene: SceneArgs,
        #[command(flatten)]
        output: OutArgs,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Continue a run from its checkpoint (`DIR/checkpoint.bin`, written on `output.checkpoints`
    /// (by default every 10 minutes) and at the end, also when `max_wall_minutes` stopped it),
    /// bit for bit as if it had not stopped. Extend it with `--set max_steps=M` (counting from
    /// the start), `--set t_end=T`, `--set stop_residual=R` or `--set max_wall_minutes=W`.
    #[command(
        after_help = "Examples:\n  vesicle resume out/prolate3d --set stop_residual=1e-8\n  vesicle resume out/prolate3d_fd --set t_end=240"
    )]
    Resume {
        /// The run folder.
        dir: PathBuf,
        /// Change a stop rule (`max_steps`, `t_end`, `stop_residual`, `max_wall_minutes`),
        /// `threads` or an `output.*` key: `key=value` (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Validate a scene and print it with every default resolved, and its stability bound.
    #[command(after_help = "Example:\n  vesicle check runs/prolate3d.json --set method=fd")]
    Check {
        #[command(flatten)]
        scene: SceneArgs,
    },
    /// Studies that compare methods in one run and print ratios (tables, CSV, charts).
    #[command(
        subcommand,
        after_help = "Examples:\n  vesicle study stationary runs/prolate3d.json --out out/stationary\n  vesicle study stability runs/studies/stability.json --out out/stability"
    )]
    Study(Study),
    /// Shape diagram from the axisymmetric (sharp-interface) reference solver: prolate, oblate
    /// and stomatocyte branches, e against v, and the transition volumes; with --c0 LIST the
    /// (v, c0) diagram of the spontaneous-curvature model with the pear branch.
    #[command(
        after_help = "Examples:\n  vesicle axisym --out out/axisym --v-min 0.5 --v-max 0.99 --dv 0.01\n  vesicle axisym --out out/axisym_c0 --c0=-1,0,1 --dv 0.01"
    )]
    Axisym(crate::commands::axisym::AxisymArgs),
    /// Shape diagram from the phase-field model: every branch and reduced volume of FILE at
    /// several ε/R0, relaxed by L-BFGS on its reduced box, extrapolated to ε/R0 → 0 and
    /// compared with the axisymmetric reference (CSV, chart, thumbnails, transitions).
    #[command(
        after_help = "Examples:\n  vesicle diagram runs/diagram.json --out out/diagram\n  vesicle diagram runs/diagram.json --list\n  vesicle diagram runs/diagram.json --out out/diagram --case 7\n  vesicle diagram runs/diagram.json --out out/diagram --merge"
    )]
    Diagram(crate::commands::diagram::DiagramArgs),
    /// Pictures of a finished run: DIR/frames/frame_<step>.png from its snapshots and final
    /// state (3D: shaded φ = 0 surface, plus surface_<step>.ply), and DIR/movie.gif.
    #[command(
        after_help = "Example:\n  vesicle run runs/sphere3d.json --out out/s --set output.snapshot_every=20\n  vesicle render out/s --gif --cut y"
    )]
    Render {
        /// Run folder (with summary.json and snapshots/phi_<step>.npy).
        dir: PathBuf,
        /// Also assemble DIR/movie.gif.
        #[arg(long)]
        gif: bool,
        /// Cut away the near half of a 3D shape across the mid-plane normal to this axis.
        #[arg(long, value_parser = ["x", "y", "z"])]
        cut: Option<String>,
        /// Use every K-th snapshot (the final state always).
        #[arg(long, value_name = "K", default_value_t = 1)]
        every: usize,
        /// GIF frame delay in hundredths of a second.
        #[arg(long, value_name = "CS", default_value_t = 20)]
        delay: u16,
        /// Replace an existing DIR/frames.
        #[arg(long)]
        force: bool,
    },
    /// Radius profile of a finished 3D run along an axis, for every snapshot and the final
    /// state: neck radius (budding), dominant wavelength against the tube radius (pearling),
    /// skewness (pears). Writes DIR/measure.csv and DIR/neck.png and prints a short table.
    #[command(
        after_help = "Example:\n  vesicle run runs/budding3d.json --out out/budding3d\n  vesicle measure out/budding3d --axis z"
    )]
    Measure {
        /// Run folder (with summary.json, timeseries.csv and snapshots/phi_<step>.npy).
        dir: PathBuf,
        /// Axis of the profile: slices are normal to it.
        #[arg(long, default_value = "z")]
        axis: String,
        /// Replace an existing DIR/measure.csv and DIR/neck.png.
        #[arg(long)]
        force: bool,
    },
    /// Run the finite-difference reference and the spectral engine on the same initial field;
    /// print and write a table of both at common times.
    #[command(after_help = "Example:\n  vesicle compare runs/compare2d.json --out out/compare")]
    Compare {
        #[command(flatten)]
        scene: SceneArgs,
        #[command(flatten)]
        output: OutArgs,
    },
}

/// A study file and how to run it.
#[derive(clap::Args, Debug)]
struct StudyArgs {
    /// Study file, JSON (runs/studies/*.json).
    file: PathBuf,
    /// The quick variant (the file's "quick" block; under a minute).
    #[arg(long)]
    quick: bool,
    #[command(flatten)]
    output: OutArgs,
}

impl StudyArgs {
    /// Run the study `name` of the file ([`crate::commands::studies::run`]: in one pool of its
    /// threads), into [`Self::folder`].
    ///
    /// # Errors
    /// A missing or unreadable study file, or the study's own errors.
    fn run(&self, name: &str) -> Result<(), Error> {
        let out = self.folder();
        let args = crate::commands::studies::Args {
            file: &self.file,
            quick: self.quick,
            set: &[],
            out: &out,
            force: self.output.force,
        };
        crate::commands::studies::run(name, &args)?;
        Ok(())
    }

    /// The output folder: `--out`, or `out/<file stem>[-quick]`.
    fn folder(&self) -> PathBuf {
        self.output
            .folder(&self.file, if self.quick { "-quick" } else { "" })
    }
}

#[derive(Subcommand, Debug)]
enum Study {
    /// Observed orders in Δt (SBDF1, SBDF2; prepared and raw starts), in h (FD h², spectral
    /// exponential) and in ε/R0 (prolate, oblate, sphere control, with extrapolated limits),
    /// each from a least-squares fit.
    #[command(
        after_help = "Examples:\n  vesicle study convergence runs/studies/convergence.json --out out/convergence\n  vesicle study convergence runs/studies/convergence.json --quick"
    )]
    Convergence(StudyArgs),
    /// What each engine and `stop_residual` buy on the way to a stationary state. On a scene
    /// file: L-BFGS (the reference; run three times, the run of median wall time tabulated),
    /// conserved SBDF1 and SBDF2 with adaptive steps, each run to residual 1e-8, and FD at its
    /// bound (extrapolated); on a study file (`"study": "stationary"`) the routes it lists.
    /// Steps, wall time and energy error at every tolerance, the fastest route to each error
    /// level, and the Pareto chart of energy error against wall time.
    #[command(
        after_help = "Examples:\n  vesicle study stationary runs/prolate3d.json --out out/stationary\n  vesicle study stationary runs/studies/stationary.json --quick"
    )]
    Stationary {
        #[command(flatten)]
        scene: SceneArgs,
        /// The quick variant of a study file (its "quick" block).
        #[arg(long)]
        quick: bool,
        #[command(flatten)]
        output: OutArgs,
    },
    /// Speed against accuracy on a transient (the 3D prolate): the error in φ at a fixed time
    /// against wall time for FD and spectral SBDF1/SBDF2; the Pareto chart and the spectral/FD
    /// wall-time ratio at each error level (the stationary side is `study stationary`).
    #[command(
        after_help = "Example:\n  vesicle study precision runs/studies/precision.json --out out/precision [--quick]"
    )]
    Precision(StudyArgs),
    /// The stability map: fixed Δt against h for FD, SBDF1 and SBDF2 (S = 0 and default S),
    /// adaptive runs at several tolerances, the Lagrangian α against Δt; every run classified.
    #[command(
        after_help = "Example:\n  vesicle study stability runs/studies/stability.json --out out/stability [--quick]"
    )]
    Stability(StudyArgs),
    /// Quasi-static budding: from the axisymmetric prolate at v, c0 R0 stepped up with an
    /// L-BFGS relaxation at each step (a small up-down asymmetry seeded first); neck radius,
    /// skewness and pieces against c0 R0, beside the sharp pear branch at the same v.
    #[command(
        after_help = "Example:\n  vesicle study budding runs/studies/budding.json --out out/budding [--quick]"
    )]
    Budding(StudyArgs),
    /// The budding onset: the c0 R0 (or, with a path in da, the bilayer couple's Δa) where the
    /// prolate at v leaves up-down symmetry (a coarse path of L-BFGS relaxations, each after a
    /// small seeded asymmetry, then bisection; or the sign of the symmetric state's lowest
    /// up-down odd eigenvalue), at several R0, extrapolated in eps/R0 beside the sharp
    /// prolate's loss of up-down stability at the same v.
    #[command(
        after_help = "Examples:\n  vesicle study onset runs/studies/onset.json --out out/onset [--quick]\n  vesicle study onset runs/studies/onset_bc.json --out out/onset_bc"
    )]
    Onset(StudyArgs),
    /// Budding on heating (ADE): from the axisymmetric ADE prolate at v, Δa0 stepped up and
    /// down with an L-BFGS relaxation at each step (a small up-down asymmetry seeded first), at
    /// one or more R0; w, Δa, neck and skewness against Δa0 beside the sharp ADE prolate and
    /// pear branches at the same v.
    #[command(
        after_help = "Example:\n  vesicle study heating runs/studies/heating.json --out out/heating [--quick]"
    )]
    Heating(StudyArgs),
    /// Lattice pinning of stationary energies: e and v of shapes started from the sharp
    /// reference and relaxed by L-BFGS, over R0 steps of a fraction of ε and sub-cell shifts of
    /// the centre, at several h/ε; the residual of a smooth fit in (ε/R0)² and the spread over
    /// the shifts, per shape and h/ε, and the bound the program prints.
    #[command(
        after_help = "Example:\n  vesicle study pinning runs/studies/pinning.json --out out/pinning [--quick]"
    )]
    Pinning(StudyArgs),
    /// Speed against accuracy for stationary shapes: e's error against the sharp axisymmetric
    /// reference and the wall time per (h/ε, ε/R0) and route (L-BFGS at one R0, extrapolation in
    /// ε/R0 over two or three R0, adaptive SBDF2), with the Pareto front.
    #[command(
        after_help = "Example:\n  vesicle study resolution runs/studies/resolution.json --out out/resolution [--quick]"
    )]
    Resolution(StudyArgs),
    /// The ADE multiplier's stability map: fixed Δt against α for SBDF1 and SBDF2 with λ
    /// implicit (solved with σ) and lagged, on a 3D scene with an `ade` block; every run
    /// classified, the largest stable Δt per scheme, multiplier and α.
    #[command(
        after_help = "Example:\n  vesicle study ade runs/studies/stability_ade.json --out runs/results/stability_ade [--quick]"
    )]
    Ade(StudyArgs),
    /// The Stokes dynamics' relaxation rates: a seeded mode of a quasi-circle, a quasi-sphere
    /// or a flat membrane at fixed tension, its fitted decay rate over the sharp rate times the
    /// periodic box's factor, extrapolated in ε/R.
    #[command(
        after_help = "Example:\n  vesicle study rates runs/studies/rates.json --out runs/results/rates [--quick]"
    )]
    Rates(StudyArgs),
    /// 2D vesicles tank-treading in a steady shear (Couette flow between walls or Kolmogorov
    /// flow) with their area held: the inclination, deformation and tank-treading rate against
    /// the reduced area, the departure from the linear theory extrapolated in ε/R0.
    #[command(
        after_help = "Example:\n  vesicle study shear runs/studies/shear.json --out runs/results/shear [--quick]"
    )]
    Shear(StudyArgs),
    /// Non-axisymmetric ADE shapes (triaxial, starfish): a seeded scene relaxed by L-BFGS per
    /// h/ε and Δa0, its w, Δa, e and semi-axes against the axisymmetric starts relaxed in the
    /// same box (interpolated to its v) and the sharp axisymmetric branches at its v.
    #[command(
        after_help = "Example:\n  vesicle study nonaxisymmetric runs/studies/nonaxisymmetric.json --out runs/results/nonaxisymmetric [--quick]"
    )]
    Nonaxisymmetric(StudyArgs),
}

/// Parse the command line, run it, and return the process exit code.
pub fn main() -> i32 {
    let cli = Cli::parse();
    match dispatch(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e}");
            exit_code(&e)
        }
    }
}

/// Run the command line `args` (the program name first) in this process, as [`main`] does
/// but returning the error instead of printing it: print what the command prints and return
/// its exit code (0, or 128 + the signal that ended a run). `--help` and `--version` print and
/// return 0.
///
/// # Errors
/// `Error::Config` on field `(command line)` with clap's message for arguments that do not
/// parse; otherwise the command's error.
pub fn run_args<I, T>(args: I) -> Result<i32, Error>
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    match Cli::try_parse_from(args) {
        Ok(cli) => dispatch(cli),
        Err(e) if e.exit_code() == 0 => {
            let _ = e.print();
            Ok(0)
        }
        Err(e) => {
            let text = e.render().to_string();
            let reason = text.strip_prefix("error: ").unwrap_or(&text).trim_end();
            Err(Error::config("(command line)", reason))
        }
    }
}

/// Exit code of an error: 2 invalid input, 3 blow-up or broken constraint, 4 device failure, 1
/// otherwise.
pub fn exit_code(e: &Error) -> i32 {
    match e {
        Error::Config { .. } => 2,
        Error::Blowup { .. } => 3,
        Error::Device { .. } => 4,
        Error::Io { .. } | Error::Output(_) | Error::Study(_) => 1,
    }
}

fn load(args: &SceneArgs) -> Result<Scene, Error> {
    super::load_scene(&args.scene, &args.set)
}

/// Run `f` in a pool of the scene's [`Scene::threads`].
fn with_threads<T: Send>(scene: &Scene, f: impl FnOnce() -> T + Send) -> T {
    crate::cpu::in_pool(scene.threads(), f)
}

/// Print the one-line result of a run; its exit code (128 + the signal that interrupted it).
fn report(outcome: &run::Outcome, out: &Path) -> i32 {
    let l = &outcome.last;
    eprintln!(
        "done ({}): step {} t {:.6e} e {:.6} v {:.6} sigma {:.4e} residual {:.3e} in {:.2} s -> {}",
        outcome.stopped.as_str(),
        l.step,
        l.t,
        l.reduced_energy,
        l.reduced_volume,
        l.sigma,
        l.residual,
        outcome.wall_seconds,
        out.display()
    );
    outcome.signal.map_or(0, |s| 128 + s)
}

/// Run the command; its exit code (0, or 130/143 for a run ended by SIGINT/SIGTERM).
fn dispatch(cli: Cli) -> Result<i32, Error> {
    match cli.command {
        Command::Run {
            scene: args,
            output,
            quiet,
        } => {
            let scene = load(&args)?;
            let out = output.folder(&args.scene, "");
            let opts = RunOptions {
                out: out.clone(),
                force: output.force,
                progress: !quiet && std::io::stderr().is_terminal(),
            };
            let outcome = with_threads(&scene, || run::run(&scene, &opts))?;
            Ok(report(&outcome, &out))
        }
        Command::Resume { dir, set, quiet } => {
            let checkpoint = crate::driver::checkpoint::Checkpoint::read(&dir)?;
            let scene = run::resumed_scene(checkpoint.scene.clone(), &set)?;
            let progress = !quiet && std::io::stderr().is_terminal();
            let outcome = with_threads(&scene, || run::resume(&dir, checkpoint, &scene, progress))?;
            Ok(report(&outcome, &dir))
        }
        Command::Check { scene: args } => {
            let scene = load(&args)?;
            // The hardware, probed as the run would when it builds the engine.
            if scene.device == config::Device::Gpu {
                crate::engines::gpu::usable().map_err(|why| Error::config("device", why))?;
            }
            let problem = crate::problem::setup::build(&scene)?;
            crate::driver::simulation::check_stability(&scene, &problem.grid)?;
            let resolved = with_threads(&scene, || {
                run::resolved_scene(
                    &scene,
                    scene.area.target.unwrap_or(f64::NAN),
                    &problem.mirror,
                )
            });
            println!(
                "{}",
                serde_json::to_string_pretty(&resolved.resolved_value()).expect("serialisable")
            );
            eprintln!("{}", run::describe(&scene, &problem, "check"));
            Ok(0)
        }
        Command::Study(Study::Stationary {
            scene: args,
            quick,
            output,
        }) => {
            let suffix = if quick {
                "-stationary-quick"
            } else {
                "-stationary"
            };
            let out = output.folder(&args.scene, suffix);
            let study = crate::commands::studies::Args {
                file: &args.scene,
                quick,
                set: &args.set,
                out: &out,
                force: output.force,
            };
            crate::commands::studies::run("stationary", &study)?;
            Ok(0)
        }
        Command::Study(Study::Precision(args)) => {
            args.run(crate::commands::study::precision::Precision::NAME)?;
            Ok(0)
        }
        Command::Study(Study::Stability(args)) => {
            args.run(crate::commands::study::stability::Stability::NAME)?;
            Ok(0)
        }
        Command::Study(Study::Ade(args)) => {
            args.run(crate::commands::study::stability::AdeStability::NAME)?;
            Ok(0)
        }
        Command::Study(Study::Rates(args)) => {
            args.run(crate::commands::study::rates::RatesStudy::NAME)?;
            Ok(0)
        }
        Command::Study(Study::Shear(args)) => {
            args.run(crate::commands::study::shear::ShearStudy::NAME)?;
            Ok(0)
        }
        Command::Study(Study::Nonaxisymmetric(args)) => {
            args.run(crate::commands::study::nonaxisymmetric::Nonaxisymmetric::NAME)?;
            Ok(0)
        }
        Command::Study(Study::Budding(args)) => {
            args.run(crate::commands::study::budding::Budding::NAME)?;
            Ok(0)
        }
        Command::Study(Study::Onset(args)) => {
            args.run(crate::commands::study::onset::OnsetStudy::NAME)?;
            Ok(0)
        }
        Command::Study(Study::Heating(args)) => {
            args.run(crate::commands::study::heating::Heating::NAME)?;
            Ok(0)
        }
        Command::Study(Study::Pinning(args)) => {
            args.run(crate::commands::study::pinning::PinningStudy::NAME)?;
            Ok(0)
        }
        Command::Study(Study::Resolution(args)) => {
            args.run(crate::commands::study::resolution::ResolutionStudy::NAME)?;
            Ok(0)
        }
        Command::Study(Study::Convergence(args)) => {
            args.run(crate::commands::study::convergence::Convergence::NAME)?;
            Ok(0)
        }
        Command::Axisym(args) => {
            crate::commands::axisym::run(&args)?;
            Ok(0)
        }
        Command::Diagram(args) => {
            // Cases run on pools of one thread each (their scenes set `threads` to 1); the
            // rest (the sharp starts, the merge) on one pool of `--jobs` workers.
            crate::cpu::in_pool(args.jobs(), || crate::commands::diagram::run(&args))?;
            Ok(0)
        }
        Command::Render {
            dir,
            gif,
            cut,
            every,
            delay,
            force,
        } => {
            let opts = crate::commands::render::RenderOptions {
                gif,
                cut: cut
                    .as_deref()
                    .map(crate::commands::render::axis_index)
                    .transpose()?,
                every,
                force,
                delay_cs: delay,
            };
            let done = crate::commands::render::render(&dir, &opts)?;
            let gif = done.gif.map(|g| format!(" and {}", g.display()));
            eprintln!(
                "{} frames -> {}{}",
                done.frames.len(),
                dir.join("frames").display(),
                gif.unwrap_or_default()
            );
            Ok(0)
        }
        Command::Measure { dir, axis, force } => {
            let opts = crate::commands::measure::MeasureOptions { axis, force };
            let done = crate::commands::measure::measure(&dir, &opts)?;
            print!("{}", crate::commands::measure::table(&done.rows, 12));
            eprintln!(
                "{} states -> {} and {}",
                done.rows.len(),
                done.csv.display(),
                done.chart.display()
            );
            Ok(0)
        }
        Command::Compare {
            scene: args,
            output,
        } => {
            let scene = load(&args)?;
            let out = output.folder(&args.scene, "-compare");
            with_threads(&scene, || {
                crate::commands::compare::compare(&scene, &out, output.force)
            })?;
            Ok(0)
        }
    }
}
