//! Animated GIF files (`GIF89a`, looping forever) from a sequence of RGB pictures of one
//! size. Each frame gets its own 256-colour palette (NeuQuant quantisation). Frames are
//! encoded as they come ([`GifWriter`]), so a long sequence is never held in memory.

use super::{create_file, OutputError, RgbImage};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Quantiser speed of the `gif` crate, 1 (best) to 30 (fastest).
const QUANTISER_SPEED: i32 = 10;

/// An animated GIF being written, frame by frame.
pub struct GifWriter {
    path: PathBuf,
    encoder: ::gif::Encoder<BufWriter<File>>,
    size: (usize, usize),
    delay_cs: u16,
    frames: usize,
}

impl GifWriter {
    /// Create `path` for frames of `width × height` pixels, each shown for `delay_cs`
    /// hundredths of a second.
    ///
    /// # Errors
    /// `OutputError::Format` if a side is 0 or exceeds 65 535 pixels; `OutputError::Io` if
    /// the file cannot be created.
    pub fn create(
        path: &Path,
        width: usize,
        height: usize,
        delay_cs: u16,
    ) -> Result<Self, OutputError> {
        let side = |n: usize| {
            u16::try_from(n)
                .ok()
                .filter(|&s| s > 0)
                .ok_or_else(|| OutputError::format(path, format!("{n} pixels is no GIF side")))
        };
        let (w, h) = (side(width)?, side(height)?);
        let file = create_file(path)?;
        let mut encoder = ::gif::Encoder::new(file, w, h, &[]).map_err(|e| gif_error(path, e))?;
        encoder
            .set_repeat(::gif::Repeat::Infinite)
            .map_err(|e| gif_error(path, e))?;
        Ok(GifWriter {
            path: path.to_path_buf(),
            encoder,
            size: (width, height),
            delay_cs,
            frames: 0,
        })
    }

    /// Append one frame.
    ///
    /// # Errors
    /// `OutputError::Format` if its size differs from the writer's; `OutputError::Io` if
    /// writing fails.
    pub fn add(&mut self, image: &RgbImage) -> Result<(), OutputError> {
        if (image.width, image.height) != self.size {
            return Err(OutputError::format(
                &self.path,
                format!(
                    "frame {} is {}x{}, the animation is {}x{}: all frames need one size",
                    self.frames, image.width, image.height, self.size.0, self.size.1
                ),
            ));
        }
        let mut frame = ::gif::Frame::from_rgb_speed(
            self.size.0 as u16,
            self.size.1 as u16,
            &image.rgb,
            QUANTISER_SPEED,
        );
        frame.delay = self.delay_cs;
        self.encoder
            .write_frame(&frame)
            .map_err(|e| gif_error(&self.path, e))?;
        self.frames += 1;
        Ok(())
    }

    /// Write the trailer and flush the file; returns the number of frames written.
    pub fn finish(self) -> Result<usize, OutputError> {
        let mut file = self
            .encoder
            .into_inner()
            .map_err(|e| gif_error(&self.path, e))?;
        file.flush().map_err(|e| OutputError::io(&self.path, e))?;
        Ok(self.frames)
    }
}

/// Write `frames` to `path` as an animated GIF showing each frame for `delay_cs` hundredths
/// of a second.
///
/// # Errors
/// `OutputError::Format` if there are no frames or they differ in size (see
/// [`GifWriter`]); `OutputError::Io` if writing fails.
pub fn write_gif(path: &Path, frames: &[RgbImage], delay_cs: u16) -> Result<(), OutputError> {
    let first = frames
        .first()
        .ok_or_else(|| OutputError::format(path, "no frames to write"))?;
    let mut writer = GifWriter::create(path, first.width, first.height, delay_cs)?;
    for f in frames {
        writer.add(f)?;
    }
    writer.finish().map(|_| ())
}

/// Map an encoder error, keeping I/O errors as such.
fn gif_error(path: &Path, e: ::gif::EncodingError) -> OutputError {
    match e {
        ::gif::EncodingError::Io(io) => OutputError::io(path, io),
        other => OutputError::format(path, other),
    }
}
