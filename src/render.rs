//! `vesicle render DIR`: pictures of a finished run from its snapshots.
//!
//! Reads `DIR/summary.json` (for `dim`, `n`, `h` and the final step), the snapshots
//! `DIR/snapshots/phi_<step>.npy` and `DIR/phi_final.npy`, and writes into `DIR/frames/` one
//! picture per state, `frame_<step>.png`: for a 3D run a shaded view of the φ = 0 surface
//! ([`output::shade`], fitted to the simulation box so that frames compare) and the surface
//! itself, `surface_<step>.ply`; for a 2D run the φ picture with its φ = 0 contour
//! ([`output::image::slices_image`]). With `gif`, the frames also go into `DIR/movie.gif`.

use crate::error::{Error, Result};
use crate::output::animation::GifWriter;
use crate::output::shade::{Bounds, View};
use crate::output::{self, RgbImage};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// What `vesicle render` draws and writes.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// Also write `DIR/movie.gif`.
    pub gif: bool,
    /// Cut away the viewer's half of a 3D shape across the plane through the box centre
    /// normal to this axis (0, 1, 2 for x, y, z).
    pub cut: Option<usize>,
    /// Use every `every`-th snapshot (the first one and the final state always).
    pub every: usize,
    /// Replace an existing `DIR/frames/`.
    pub force: bool,
    /// GIF frame delay in hundredths of a second.
    pub delay_cs: u16,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            gif: false,
            cut: None,
            every: 1,
            force: false,
            delay_cs: 20,
        }
    }
}

/// What was written.
#[derive(Clone, Debug, PartialEq)]
pub struct Rendered {
    /// The frame pictures, in step order.
    pub frames: Vec<PathBuf>,
    /// The animation, if asked for.
    pub gif: Option<PathBuf>,
}

/// The axis index of `x`, `y` or `z`.
///
/// # Errors
/// `Error::Config` on `--cut` for any other name.
pub fn axis_index(name: &str) -> Result<usize> {
    ["x", "y", "z"]
        .iter()
        .position(|a| a.eq_ignore_ascii_case(name))
        .ok_or_else(|| Error::config("--cut", format!("expected x, y or z, got `{name}`")))
}

/// The run's geometry as saved in `summary.json`.
struct RunInfo {
    dim: usize,
    n: Vec<usize>,
    h: f64,
    final_step: Option<usize>,
}

/// One state to draw: its step and `.npy` file.
struct State {
    step: usize,
    path: PathBuf,
}

/// Render the run in `dir` (see the module docs).
///
/// # Errors
/// `Error::Config` (exit code 2) if `dir` or its `summary.json` is missing or unreadable,
/// there are no snapshots, `every` is 0, or `DIR/frames` exists without `force`;
/// `Error::Io`/`Error::Output` if reading or writing fails.
pub fn render(dir: &Path, opts: &RenderOptions) -> Result<Rendered> {
    if !dir.is_dir() {
        return Err(Error::config(
            "DIR",
            format!("{} is not a run folder (it does not exist)", dir.display()),
        ));
    }
    if opts.every == 0 {
        return Err(Error::config("--every", "must be at least 1"));
    }
    let info = run_info(dir)?;
    let states = states(dir, &info, opts.every)?;
    let frames_dir = dir.join("frames");
    make_frames_dir(&frames_dir, opts.force)?;
    let name = dir
        .file_name()
        .map_or_else(String::new, |s| s.to_string_lossy().to_string());
    let view = View {
        cut: opts.cut,
        ..View::default()
    };
    let mut gif: Option<GifWriter> = None;
    let mut written = Vec::new();
    for state in &states {
        let image = frame(&frames_dir, state, &info, &view, &name)?;
        let png = frames_dir.join(format!("frame_{:08}.png", state.step));
        image.write_png(&png)?;
        written.push(png);
        if opts.gif {
            let writer = match gif.as_mut() {
                Some(w) => w,
                None => gif.insert(GifWriter::create(
                    &dir.join("movie.gif"),
                    image.width,
                    image.height,
                    opts.delay_cs,
                )?),
            };
            writer.add(&image)?;
        }
    }
    let gif = match gif {
        Some(w) => {
            w.finish()?;
            Some(dir.join("movie.gif"))
        }
        None => None,
    };
    Ok(Rendered {
        frames: written,
        gif,
    })
}

/// Draw one state (writing its `.ply` surface for a 3D run) and return the picture.
fn frame(
    frames_dir: &Path,
    state: &State,
    info: &RunInfo,
    view: &View,
    name: &str,
) -> Result<RgbImage> {
    let field = output::npy::read_npy(&state.path, &info.n)?;
    if info.dim == 2 {
        let ls = crate::levelset::measure(&field, 2, info.h);
        let title = format!(
            "{name}   step {}   L = {:.4}   v = {:.4}",
            state.step, ls.area, ls.reduced_volume
        );
        return Ok(output::image::slices_image(&state.path, &field, 2, &title)?);
    }
    let mesh = output::surface::extract(&field, info.h);
    output::ply::write_ply(
        &frames_dir.join(format!("surface_{:08}.ply", state.step)),
        &mesh,
        &format!("vesicle phi = 0 surface, {name}, step {}", state.step),
    )?;
    let (area, volume) = (mesh.area(), mesh.enclosed_volume());
    let reduced = 6.0 * std::f64::consts::PI.sqrt() * volume / area.powf(1.5);
    let title = format!(
        "{name}   step {}   A = {area:.5}   V = {volume:.5}   v = {reduced:.4}",
        state.step
    );
    let bounds = Bounds::of_grid([info.n[0], info.n[1], info.n[2]], info.h);
    Ok(output::shade::render(&mesh, &bounds, view, &title)?)
}

/// `dim`, `n`, `h` and the final step from `DIR/summary.json` (`"spec"` and `"steps"`).
fn run_info(dir: &Path) -> Result<RunInfo> {
    let path = dir.join("summary.json");
    let text = std::fs::read_to_string(&path).map_err(|e| {
        Error::config(
            "DIR",
            format!(
                "cannot read {}: {e} (is this a run folder?)",
                path.display()
            ),
        )
    })?;
    let bad = |what: &str| Error::config("DIR", format!("{}: no valid {what}", path.display()));
    let v: Value = serde_json::from_str(&text).map_err(|_| bad("JSON"))?;
    let spec = &v["spec"];
    let dim = spec["dim"]
        .as_u64()
        .filter(|d| *d == 2 || *d == 3)
        .ok_or_else(|| bad("spec.dim (2 or 3)"))? as usize;
    let n: Vec<usize> = spec["n"]
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|x| x.as_u64().map(|x| x as usize))
                .collect()
        })
        .filter(|n: &Vec<usize>| n.len() == dim && n.iter().all(|&m| m > 0))
        .ok_or_else(|| bad("spec.n"))?;
    let h = spec["h"]
        .as_f64()
        .filter(|h| *h > 0.0)
        .ok_or_else(|| bad("spec.h"))?;
    let final_step = v["steps"].as_u64().map(|s| s as usize);
    Ok(RunInfo {
        dim,
        n,
        h,
        final_step,
    })
}

/// The states to draw in step order: every `every`-th snapshot from the first, then the
/// final state unless a snapshot already has its step.
fn states(dir: &Path, info: &RunInfo, every: usize) -> Result<Vec<State>> {
    let snap_dir = dir.join("snapshots");
    let none = || {
        Error::config(
            "DIR",
            format!(
                "no snapshots {}/phi_<step>.npy: run with --set output.snapshot_every=K",
                snap_dir.display()
            ),
        )
    };
    let entries = std::fs::read_dir(&snap_dir).map_err(|_| none())?;
    let mut snaps: Vec<State> = entries
        .filter_map(|e| e.ok())
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().to_string();
            let step = name
                .strip_prefix("phi_")?
                .strip_suffix(".npy")?
                .parse()
                .ok()?;
            Some(State {
                step,
                path: e.path(),
            })
        })
        .collect();
    if snaps.is_empty() {
        return Err(none());
    }
    snaps.sort_by_key(|s| s.step);
    let mut chosen: Vec<State> = snaps.into_iter().step_by(every).collect();
    let final_path = dir.join("phi_final.npy");
    if let Some(step) = info.final_step.filter(|_| final_path.is_file()) {
        if chosen.iter().all(|s| s.step != step) {
            chosen.push(State {
                step,
                path: final_path,
            });
            chosen.sort_by_key(|s| s.step);
        }
    }
    Ok(chosen)
}

/// Create `frames`, refusing an existing one unless `force` (then it is replaced).
fn make_frames_dir(frames: &Path, force: bool) -> Result<()> {
    let io = |source| Error::Io {
        path: frames.to_path_buf(),
        source,
    };
    if frames.exists() {
        if !force {
            return Err(Error::config(
                "--force",
                format!(
                    "{} already exists; pictures are never overwritten silently (pass --force to replace them)",
                    frames.display()
                ),
            ));
        }
        std::fs::remove_dir_all(frames).map_err(io)?;
    }
    std::fs::create_dir_all(frames).map_err(io)
}
