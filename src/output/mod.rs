//! Writers for simulation output: raw arrays (`.npy`), ParaView volumes (`.vti`), slice
//! pictures of the phase field and time-series charts (`.png`), and the pictures of
//! `vesicle render`: `.ply` files ([`ply`]) and shaded views ([`shade`]) of the φ = 0 surface
//! (the mesh of [`crate::analysis::surface`]) and animated GIFs ([`animation`]).
//!
//! Every writer receives a FULL-box field (already unfolded from any mirror reduction) in the
//! internal layout of [`crate::problem::grid`]: a standard-layout `Array3<f64>` of shape `[n0, n1, n2]`,
//! with a 2D scene stored as `[1, nx, ny]`, together with the scene dimension.

pub mod animation;
pub mod chart;
pub mod folder;
pub mod image;
pub mod lock;
pub mod npy;
pub mod ply;
pub mod shade;
pub mod vti;

/// The error of the writers (defined with the crate's errors: the `.npy` reader shares it).
pub use crate::error::OutputError;

use ndarray::Array3;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;
use std::sync::OnceLock;

/// Font family name under which the embedded DejaVu Sans is registered with plotters.
pub(crate) const FONT_FAMILY: &str = "dejavu-sans";

/// DejaVu Sans (Bitstream Vera licence, see `src/output/assets/DejaVuSans-LICENSE.txt`).
const FONT_BYTES: &[u8] = include_bytes!("assets/DejaVuSans.ttf");

/// Register the embedded font with plotters once; later calls return the first outcome.
pub(crate) fn ensure_font(path: &Path) -> Result<(), OutputError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(FONT_FAMILY, plotters::style::FontStyle::Normal, FONT_BYTES)
            .is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(OutputError::format(
            path,
            "embedded font could not be loaded",
        ))
    }
}

/// Check that `field` is a valid full-box field of a `dim`-dimensional scene.
pub(crate) fn check_field(path: &Path, field: &Array3<f64>, dim: usize) -> Result<(), OutputError> {
    match dim {
        2 if field.shape()[0] != 1 => Err(OutputError::format(
            path,
            format!(
                "a 2D field must have shape [1, nx, ny], got {:?}",
                field.shape()
            ),
        )),
        2 | 3 if field.is_empty() => Err(OutputError::format(path, "the field is empty")),
        2 | 3 => Ok(()),
        _ => Err(OutputError::format(
            path,
            format!("scene dimension must be 2 or 3, got {dim}"),
        )),
    }
}

/// Create `path` for buffered writing.
pub(crate) fn create_file(path: &Path) -> Result<BufWriter<File>, OutputError> {
    File::create(path)
        .map(BufWriter::new)
        .map_err(|e| OutputError::io(path, e))
}

/// Encode an 8-bit RGB buffer of `width x height` pixels (row-major) as a PNG file.
pub(crate) fn write_rgb_png(
    path: &Path,
    width: u32,
    height: u32,
    rgb: &[u8],
) -> Result<(), OutputError> {
    let mut file = create_file(path)?;
    let mut encoder = png::Encoder::new(&mut file, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Best);
    encoder.set_adaptive_filter(png::AdaptiveFilterType::Adaptive);
    let png_err = |e: png::EncodingError| match e {
        png::EncodingError::IoError(io) => OutputError::io(path, io),
        other => OutputError::format(path, other),
    };
    let mut writer = encoder.write_header().map_err(png_err)?;
    writer.write_image_data(rgb).map_err(png_err)?;
    writer.finish().map_err(png_err)?;
    file.flush().map_err(|e| OutputError::io(path, e))
}

/// An 8-bit RGB picture, row-major, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// `3 × width × height` bytes: R, G, B of each pixel.
    pub rgb: Vec<u8>,
}

impl RgbImage {
    /// A `width × height` picture of one colour.
    pub fn filled(width: usize, height: usize, colour: [u8; 3]) -> Self {
        RgbImage {
            width,
            height,
            rgb: colour.repeat(width * height),
        }
    }

    /// The colour of pixel `(x, y)`.
    pub fn pixel(&self, x: usize, y: usize) -> [u8; 3] {
        let k = 3 * (y * self.width + x);
        [self.rgb[k], self.rgb[k + 1], self.rgb[k + 2]]
    }

    /// Write the picture as a PNG file.
    pub fn write_png(&self, path: &Path) -> Result<(), OutputError> {
        write_rgb_png(path, self.width as u32, self.height as u32, &self.rgb)
    }

    /// Draw the line `text` in the embedded font, `size` pixels high (smaller, or shortened,
    /// where it would not fit the width: [`fit_line`]), in `colour`, centred on the picture's
    /// middle column at row `y`; `name` names the picture in error messages.
    pub(crate) fn draw_heading(
        &mut self,
        name: &Path,
        text: &str,
        size: u32,
        colour: [u8; 3],
        y: usize,
    ) -> Result<(), OutputError> {
        use plotters::prelude::*;
        use plotters::style::text_anchor::{HPos, Pos, VPos};
        let (text, size) = fit_line(name, text, size, self.width)?;
        let (w, h) = (self.width as u32, self.height as u32);
        let root = BitMapBackend::with_buffer(&mut self.rgb, (w, h)).into_drawing_area();
        let rgb = RGBColor(colour[0], colour[1], colour[2]);
        let style = TextStyle::from((FONT_FAMILY, size).into_font())
            .color(&rgb)
            .pos(Pos::new(HPos::Center, VPos::Center));
        let text_err = |e| OutputError::format(name, format!("cannot draw text: {e}"));
        root.draw_text(&text, &style, ((self.width / 2) as i32, y as i32))
            .map_err(text_err)?;
        root.present().map_err(text_err)
    }
}

/// Pixels kept free of text at each side of a line fitted to a picture's width.
const TEXT_MARGIN: usize = 8;

/// The line `text` fitted to a picture `width` pixels wide (less [`TEXT_MARGIN`] at each side)
/// in the embedded font: at font size `size` where it fits, else at the largest size down to
/// three quarters of `size` that fits, else at that size cut at its end with an ellipsis.
/// Returns the text and the size to draw it at; `name` names the picture in error messages.
///
/// # Errors
/// `OutputError::Format` if the font cannot be loaded or measure the text.
pub(crate) fn fit_line(
    name: &Path,
    text: &str,
    size: u32,
    width: usize,
) -> Result<(String, u32), OutputError> {
    use plotters::style::IntoFont;
    ensure_font(name)?;
    let room = width.saturating_sub(2 * TEXT_MARGIN);
    let fits = |t: &str, s: u32| {
        (FONT_FAMILY, f64::from(s))
            .into_font()
            .box_size(t)
            .map(|(w, _)| w as usize <= room)
            .map_err(|e| OutputError::format(name, format!("cannot measure text: {e}")))
    };
    let smallest = (3 * size / 4).max(1);
    for s in (smallest..=size).rev() {
        if fits(text, s)? {
            return Ok((text.to_string(), s));
        }
    }
    let mut chars: Vec<char> = text.chars().collect();
    while chars.pop().is_some() {
        let shortened = format!("{}…", chars.iter().collect::<String>().trim_end());
        if fits(&shortened, smallest)? {
            return Ok((shortened, smallest));
        }
    }
    Ok((String::new(), smallest))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A line that fits keeps its text and size; a longer one is drawn smaller; one too long
    /// even at three quarters of the size is cut with an ellipsis; every result fits.
    #[test]
    fn lines_are_fitted_to_the_width() {
        let name = Path::new("test");
        let width = |t: &str, s: u32| {
            use plotters::style::IntoFont;
            (FONT_FAMILY, f64::from(s))
                .into_font()
                .box_size(t)
                .unwrap()
                .0 as usize
        };
        ensure_font(name).unwrap();
        let short = "step 100";
        assert_eq!(
            fit_line(name, short, 20, 640).unwrap(),
            (short.to_string(), 20)
        );
        let long = "deflation3d   step 180000   A = 5244.77329   V = 25132.09399   v = 0.7037";
        assert!(
            width(long, 20) > 640 - 2 * TEXT_MARGIN,
            "wider than the picture"
        );
        let (text, size) = fit_line(name, long, 20, 640).unwrap();
        assert_eq!(text, long);
        assert!((15..20).contains(&size), "size {size}");
        assert!(width(&text, size) <= 640 - 2 * TEXT_MARGIN);
        let twice = long.repeat(2);
        let (text, size) = fit_line(name, &twice, 20, 640).unwrap();
        assert_eq!(size, 15);
        assert!(text.ends_with('…') && twice.starts_with(text.trim_end_matches('…')));
        assert!(width(&text, size) <= 640 - 2 * TEXT_MARGIN);
        assert_eq!(fit_line(name, long, 20, 10).unwrap(), (String::new(), 15));
    }
}
