//! `vesicle render DIR`: pictures of a finished run from its snapshots.
//!
//! Reads `DIR/summary.json` (for `dim`, `n`, `h` and the final step), the snapshots
//! `DIR/snapshots/phi_<step>.npy` and `DIR/phi_final.npy`, and writes into `DIR/frames/` one
//! picture per state, `frame_<step>.png`: for a 3D run a shaded view of the φ = 0 surface
//! ([`output::shade`], fitted to the simulation box so that frames compare) and the surface
//! itself, `surface_<step>.ply`; for a 2D run the φ picture with its φ = 0 contour
//! ([`output::image::slices_image`]). With `gif`, the frames also go into `DIR/movie.gif`.

use crate::commands::run_folder::{self, RunInfo, State};
use crate::error::{Error, Result};
use crate::output::animation::GifWriter;
use crate::output::shade::{Bounds, View};
use crate::output::{self, RgbImage};
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

/// Render the run in `dir` (see the module docs).
///
/// # Errors
/// `Error::Config` (exit code 2) if `dir` or its `summary.json` is missing or unreadable,
/// there are no snapshots, `every` is 0, or `DIR/frames` exists without `force`;
/// `Error::Io`/`Error::Output` if reading or writing fails.
pub fn render(dir: &Path, opts: &RenderOptions) -> Result<Rendered> {
    run_folder::check_dir(dir)?;
    if opts.every == 0 {
        return Err(Error::config("--every", "must be at least 1"));
    }
    let info = run_folder::run_info(dir)?;
    let states = run_folder::states(dir, &info, opts.every)?;
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
    let field = crate::npy::read_npy(&state.path, &info.n)?;
    if info.dim == 2 {
        let ls = crate::analysis::levelset::measure(&field, 2, info.h);
        let title = format!(
            "{name}   step {}   L = {:.4}   v = {:.4}",
            state.step, ls.area, ls.reduced_volume
        );
        return Ok(output::image::slices_image(&state.path, &field, 2, &title)?);
    }
    let mesh = crate::analysis::surface::extract(&field, info.h);
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
