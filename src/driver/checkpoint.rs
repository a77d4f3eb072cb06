//! Checkpoints: everything needed to continue a run exactly (the resolved scene, the clock, the
//! observers' schedule timers and the engine's saved state), in one file written atomically.
//!
//! Layout of `checkpoint.bin`:
//!
//! ```text
//! MAGIC                    b"VESICLE-CHECKPOINT\n"
//! header length            u64, little endian
//! header                   JSON: {"version", "scene", "scalars": [names], "arrays": [{name, kind, shape}]}
//! payload                  the scalars, then each array: f64, little endian (complex as re, im
//!                          pairs), or f32 for the kind "single" (the L-BFGS pairs, as re, im)
//! checksum                 CRC-32 of header and payload, u32, little endian
//! ```
//!
//! A checkpoint is written to a temporary file in the same folder, flushed to disk and renamed
//! over the old one, so a crash at any moment leaves the previous checkpoint or the new one,
//! whole. Reading checks the magic, every length against the file, the checksum and the program
//! version before anything is used: a truncated, corrupted or foreign file is refused with a
//! message, never half-loaded.

use crate::driver::schedule::{self, Timer};
use crate::driver::simulation::{Clock, Simulation};
use crate::engines::{Saved, SavedArray};
use crate::error::{Error, Result};
use ndarray::Array3;
use num_complex::Complex64;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

/// First bytes of every checkpoint.
pub const MAGIC: &[u8] = b"VESICLE-CHECKPOINT\n";
/// The checkpoint's file name in a run folder.
pub const FILE_NAME: &str = "checkpoint.bin";

/// A run's state at the end of an accepted step: the engine's arrays borrowed from it when the
/// checkpoint is written, owned when it is read.
#[derive(Clone, Debug, PartialEq)]
pub struct Checkpoint<'a> {
    /// The program version that wrote it.
    pub version: String,
    /// The resolved scene (`summary.json`'s `"spec"`).
    pub scene: Value,
    /// The simulation clock.
    pub clock: Clock,
    /// The observers' timers (scalars `schedule.<name>.<field>`; none in a checkpoint that
    /// has no such scalars).
    pub timers: Vec<Timer>,
    /// The engine's state.
    pub engine: Saved<'a>,
}

#[derive(Serialize, Deserialize)]
struct Header {
    version: String,
    scene: Value,
    scalars: Vec<String>,
    arrays: Vec<ArrayHeader>,
}

#[derive(Serialize, Deserialize)]
struct ArrayHeader {
    name: String,
    kind: String,
    shape: [usize; 3],
}

/// The clock's fields in the scalar list.
const CLOCK: [&str; 7] = [
    "clock.step",
    "clock.t",
    "clock.dt",
    "clock.last_dt",
    "clock.last_rate",
    "clock.rejected",
    "clock.wall_seconds",
];

fn clock_values(c: &Clock) -> [f64; 7] {
    [
        c.step as f64,
        c.t,
        c.dt,
        c.last_dt,
        c.last_rate,
        c.rejected as f64,
        c.wall_seconds,
    ]
}

impl<'a> Checkpoint<'a> {
    /// The checkpoint of `simulation`'s current state, of a run of the resolved scene
    /// `scene` (`summary.json`'s `"spec"`), by this program version; it borrows the engine's
    /// arrays.
    pub fn of(simulation: &'a Simulation, scene: Value) -> Self {
        Checkpoint {
            version: env!("CARGO_PKG_VERSION").to_string(),
            scene,
            clock: simulation.clock,
            timers: simulation.timers.clone(),
            engine: simulation.engine().save(),
        }
    }
}

impl Checkpoint<'_> {
    /// The checkpoint's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut bytes = Vec::new();
        self.write_to(&mut bytes, || ())
            .expect("writing to memory does not fail");
        bytes
    }

    /// Write the checkpoint to `out` (layout in the module documentation), the body staged and
    /// hashed in chunks of [`CHUNK`] bytes, `after_chunk` called after each: no copy of the
    /// engine's arrays is held beside them.
    ///
    /// # Errors
    /// What `out` returns.
    fn write_to(&self, out: &mut impl Write, after_chunk: fn()) -> std::io::Result<()> {
        let mut names: Vec<String> = CLOCK.iter().map(|s| s.to_string()).collect();
        let mut values: Vec<f64> = clock_values(&self.clock).to_vec();
        for timer in &self.timers {
            for (field, v) in schedule::SAVED.iter().zip(timer.saved()) {
                names.push(format!("schedule.{}.{field}", timer.name));
                values.push(v);
            }
        }
        for (n, v) in &self.engine.scalars {
            names.push(format!("engine.{n}"));
            values.push(*v);
        }
        let arrays = self
            .engine
            .arrays
            .iter()
            .map(|(name, a)| {
                let (kind, shape) = match a {
                    SavedArray::Real(a) => ("real", a.dim().into()),
                    SavedArray::Complex(a) => ("complex", a.dim().into()),
                    SavedArray::Single(shape, _) => ("single", *shape),
                };
                ArrayHeader {
                    name: name.clone(),
                    kind: kind.to_string(),
                    shape,
                }
            })
            .collect();
        let header = serde_json::to_vec(&Header {
            version: self.version.clone(),
            scene: self.scene.clone(),
            scalars: names,
            arrays,
        })
        .expect("serialisable header");
        out.write_all(MAGIC)?;
        out.write_all(&(header.len() as u64).to_le_bytes())?;
        let mut body = Body {
            out,
            staged: Vec::with_capacity(CHUNK + 16),
            crc: crc32fast::Hasher::new(),
            after_chunk,
        };
        body.put(&header)?;
        for v in values {
            body.put(&v.to_le_bytes())?;
        }
        for (_, a) in &self.engine.arrays {
            match a {
                SavedArray::Real(a) => a.iter().try_for_each(|v| body.put(&v.to_le_bytes()))?,
                SavedArray::Complex(a) => a.iter().try_for_each(|v| {
                    body.put(&v.re.to_le_bytes())?;
                    body.put(&v.im.to_le_bytes())
                })?,
                SavedArray::Single(_, reals) => {
                    reals.iter().try_for_each(|&v| body.put(&v.to_le_bytes()))?
                }
            }
        }
        body.finish()
    }

    /// Parse a checkpoint from `bytes` (from `source`, named in messages).
    ///
    /// # Errors
    /// `Error::Config` on field `checkpoint` when the bytes are not a whole checkpoint of this
    /// program version.
    pub fn from_bytes(bytes: &[u8], source: &Path) -> Result<Checkpoint<'static>> {
        let bad = |reason: String| {
            Error::config(
                "checkpoint",
                format!("{}: {reason}; it cannot be resumed", source.display()),
            )
        };
        let rest = bytes
            .strip_prefix(MAGIC)
            .ok_or_else(|| bad("not a vesicle checkpoint (wrong magic bytes)".into()))?;
        if rest.len() < 12 {
            return Err(bad("truncated (no header)".into()));
        }
        let (len, rest) = rest.split_at(8);
        let header_len = u64::from_le_bytes(len.try_into().expect("8 bytes"));
        let (body, crc) = rest.split_at(rest.len() - 4);
        if header_len > body.len() as u64 {
            return Err(bad(format!(
                "truncated: the header says {header_len} bytes, {} remain",
                body.len()
            )));
        }
        let stored = u32::from_le_bytes(crc.try_into().expect("4 bytes"));
        if crc32fast::hash(body) != stored {
            return Err(bad(
                "corrupted: the checksum does not match (truncated or overwritten)".into(),
            ));
        }
        let (header, payload) = body.split_at(header_len as usize);
        let header: Header =
            serde_json::from_slice(header).map_err(|e| bad(format!("unreadable header ({e})")))?;
        let version = env!("CARGO_PKG_VERSION");
        if header.version != version {
            return Err(bad(format!(
                "written by vesicle {}, this is vesicle {version}",
                header.version
            )));
        }
        let mut values = Payload(payload);
        let mut scalars = Vec::with_capacity(header.scalars.len());
        for name in &header.scalars {
            let v = values
                .f64()
                .ok_or_else(|| bad("truncated payload".into()))?;
            scalars.push((name.clone(), v));
        }
        let clock_value = |name: &str| {
            scalars
                .iter()
                .find(|(n, _)| n == name)
                .map(|(_, v)| *v)
                .ok_or_else(|| bad(format!("the header lacks `{name}`")))
        };
        let count = |v: f64, name: &str| {
            if v >= 0.0 && v.fract() == 0.0 && v < 2f64.powi(53) {
                Ok(v as usize)
            } else {
                Err(bad(format!("`{name}` = {v} is not a count")))
            }
        };
        let clock = Clock {
            step: count(clock_value(CLOCK[0])?, CLOCK[0])?,
            t: clock_value(CLOCK[1])?,
            dt: clock_value(CLOCK[2])?,
            last_dt: clock_value(CLOCK[3])?,
            last_rate: clock_value(CLOCK[4])?,
            rejected: count(clock_value(CLOCK[5])?, CLOCK[5])?,
            wall_seconds: clock_value(CLOCK[6])?,
        };
        let mut timers = Vec::new();
        for (n, _) in &scalars {
            let Some(name) = n
                .strip_prefix("schedule.")
                .and_then(|r| r.strip_suffix(schedule::SAVED[0]))
                .and_then(|r| r.strip_suffix('.'))
            else {
                continue;
            };
            let mut v = [0.0; 6];
            for (slot, field) in v.iter_mut().zip(schedule::SAVED) {
                *slot = clock_value(&format!("schedule.{name}.{field}"))?;
            }
            timers.push(
                Timer::from_saved(name, v)
                    .ok_or_else(|| bad(format!("the schedule `{name}` is not a schedule's")))?,
            );
        }
        let mut engine = Saved::default();
        for (n, v) in &scalars {
            if let Some(name) = n.strip_prefix("engine.") {
                engine.scalars.push((name.to_string(), *v));
            }
        }
        for a in &header.arrays {
            let [n0, n1, n2] = a.shape;
            // Bytes a value: a real f64, a complex pair of f64, a single pair of f32.
            let per = match a.kind.as_str() {
                "real" | "single" => 8,
                "complex" => 16,
                other => return Err(bad(format!("array `{}` of unknown kind {other}", a.name))),
            };
            let len = n0
                .checked_mul(n1)
                .and_then(|x| x.checked_mul(n2))
                .filter(|&x| x.checked_mul(per).is_some_and(|m| m <= values.remaining()))
                .ok_or_else(|| bad(format!("array `{}` is larger than the file", a.name)))?;
            let shape = (n0, n1, n2);
            let array = match a.kind.as_str() {
                "real" => {
                    let data: Vec<f64> = (0..len).filter_map(|_| values.f64()).collect();
                    let a = Array3::from_shape_vec(shape, data).expect("checked size");
                    SavedArray::Real(a.into())
                }
                "complex" => {
                    let data: Vec<Complex64> = (0..len)
                        .filter_map(|_| Some(Complex64::new(values.f64()?, values.f64()?)))
                        .collect();
                    let a = Array3::from_shape_vec(shape, data).expect("checked size");
                    SavedArray::Complex(a.into())
                }
                _ => {
                    let data: Vec<f32> = (0..2 * len).filter_map(|_| values.f32()).collect();
                    SavedArray::Single(a.shape, data.into())
                }
            };
            engine.arrays.push((a.name.clone(), array));
        }
        if values.remaining() != 0 {
            return Err(bad(format!(
                "{} bytes after the last array",
                values.remaining()
            )));
        }
        Ok(Checkpoint {
            version: header.version,
            scene: header.scene,
            clock,
            timers,
            engine,
        })
    }

    /// Write atomically to `dir/checkpoint.bin`: a temporary file, flushed to disk, renamed.
    ///
    /// # Errors
    /// `Error::Io` on failure (the previous checkpoint is then untouched).
    pub fn write(&self, dir: &Path) -> Result<()> {
        let path = dir.join(FILE_NAME);
        let tmp = dir.join(format!("{FILE_NAME}.tmp"));
        let io = |p: &PathBuf| {
            let p = p.clone();
            move |source| Error::Io { path: p, source }
        };
        let mut file = File::create(&tmp).map_err(io(&tmp))?;
        self.write_to(&mut file, pause_for_tests)
            .map_err(io(&tmp))?;
        file.sync_all().map_err(io(&tmp))?;
        drop(file);
        std::fs::rename(&tmp, &path).map_err(io(&path))?;
        if let Ok(d) = File::open(dir) {
            let _ = d.sync_all();
        }
        Ok(())
    }

    /// Read `dir/checkpoint.bin`.
    ///
    /// # Errors
    /// `Error::Config` on field `checkpoint` if it is missing or not a whole checkpoint of this
    /// version.
    pub fn read(dir: &Path) -> Result<Checkpoint<'static>> {
        let path = dir.join(FILE_NAME);
        let bytes = std::fs::read(&path).map_err(|e| {
            Error::config("checkpoint", format!("cannot read {}: {e}", path.display()))
        })?;
        Self::from_bytes(&bytes, &path)
    }
}

/// Bytes of a checkpoint's body staged before they are written.
const CHUNK: usize = 1 << 20;

/// A checkpoint's body on its way to `out`: staged in chunks of [`CHUNK`] bytes and hashed
/// (CRC-32) chunk by chunk.
struct Body<'a, W: Write> {
    out: &'a mut W,
    staged: Vec<u8>,
    crc: crc32fast::Hasher,
    after_chunk: fn(),
}

impl<W: Write> Body<'_, W> {
    fn put(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.staged.extend_from_slice(bytes);
        if self.staged.len() >= CHUNK {
            self.pass_on()?;
        }
        Ok(())
    }

    /// Hash and write the staged bytes.
    fn pass_on(&mut self) -> std::io::Result<()> {
        self.crc.update(&self.staged);
        self.out.write_all(&self.staged)?;
        self.staged.clear();
        (self.after_chunk)();
        Ok(())
    }

    /// The last staged bytes, then the checksum of the whole body.
    fn finish(mut self) -> std::io::Result<()> {
        if !self.staged.is_empty() {
            self.pass_on()?;
        }
        self.out.write_all(&self.crc.finalize().to_le_bytes())
    }
}

/// With `VESICLE_TEST_SLOW_CHECKPOINT=<ms>` in the environment, sleep that long after each MiB
/// written, so a test can kill the process in the middle of a checkpoint write.
fn pause_for_tests() {
    if let Some(ms) = std::env::var("VESICLE_TEST_SLOW_CHECKPOINT")
        .ok()
        .and_then(|v| v.parse::<u64>().ok())
    {
        std::thread::sleep(std::time::Duration::from_millis(ms));
    }
}

/// The payload's bytes, read front to back as little-endian numbers.
struct Payload<'a>(&'a [u8]);

impl Payload<'_> {
    /// Bytes left.
    fn remaining(&self) -> usize {
        self.0.len()
    }

    fn take<const N: usize>(&mut self) -> Option<[u8; N]> {
        let (v, rest) = self.0.split_first_chunk::<N>()?;
        self.0 = rest;
        Some(*v)
    }

    fn f64(&mut self) -> Option<f64> {
        self.take().map(f64::from_le_bytes)
    }

    fn f32(&mut self) -> Option<f32> {
        self.take().map(f32::from_le_bytes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Checkpoint<'static> {
        let saved = Saved::default()
            .scalar("sigma", -0.07)
            .scalar("dt_next", f64::NAN)
            .array(
                "phi",
                SavedArray::Real(
                    Array3::from_shape_fn((1, 3, 4), |(_, i, j)| i as f64 - j as f64).into(),
                ),
            )
            .array(
                "hat",
                SavedArray::Complex(
                    Array3::from_shape_fn((2, 2, 2), |(a, b, c)| {
                        Complex64::new(a as f64, b as f64 * 0.5 - c as f64)
                    })
                    .into(),
                ),
            )
            .array(
                "pair",
                SavedArray::Single(
                    [1, 2, 2],
                    vec![0.5, -1.25, 3e-8, 7.0, -0.0, 1e30, 2.5, -4.0].into(),
                ),
            );
        let mut clock = Clock::new(0.5);
        clock.step = 12;
        clock.t = 3.25;
        let snapshots = crate::problem::config::Schedule::time(0.75);
        Checkpoint {
            version: env!("CARGO_PKG_VERSION").into(),
            scene: serde_json::json!({"dim": 2}),
            timers: vec![Timer::new("snapshots", snapshots, &clock)],
            clock,
            engine: saved,
        }
    }

    /// Bytes → checkpoint → bytes is the identity (NaN scalars included, bit for bit), and the
    /// arrays (real, complex, single) come back equal.
    #[test]
    fn round_trip_is_bit_exact() {
        let c = sample();
        let bytes = c.to_bytes();
        let back = Checkpoint::from_bytes(&bytes, Path::new("x")).unwrap();
        assert_eq!(back.to_bytes(), bytes);
        assert_eq!(back.clock.step, 12);
        assert_eq!(back.timers, c.timers);
        assert_eq!(back.timers[0].next_time(), Some(4.0));
        assert!(back.engine.get("dt_next").unwrap().is_nan());
        assert_eq!(back.engine.arrays, c.engine.arrays);
    }

    /// Every truncation and every single flipped byte is refused with an error, never a panic.
    #[test]
    fn truncated_or_corrupted_is_refused() {
        let bytes = sample().to_bytes();
        for cut in 0..bytes.len() {
            assert!(Checkpoint::from_bytes(&bytes[..cut], Path::new("x")).is_err());
        }
        for i in 0..bytes.len() {
            let mut b = bytes.clone();
            b[i] ^= 0x5a;
            assert!(
                Checkpoint::from_bytes(&b, Path::new("x")).is_err(),
                "byte {i}"
            );
        }
    }

    /// A checkpoint larger than the write buffer (three chunks and a part: staged, hashed and
    /// written chunk by chunk) reads back bit for bit, its checksum whole; a single-precision
    /// spectrum (the L-BFGS pairs) is stored as f32 and comes back as the same values, which
    /// `Saved::take_single` moves out (once); and a pair written as a complex array (the format
    /// before the f32 kind) is rounded back to the same f32 values.
    #[test]
    fn a_checkpoint_of_several_chunks_round_trips() {
        let shape = [32, 64, 65];
        let n: usize = shape.iter().product();
        let reals: Vec<f32> = (0..2 * n).map(|i| (i as f32 * 0.37).sin() / 3.0).collect();
        let widened = Array3::from_shape_fn((32, 64, 65), |(a, b, d)| {
            let at = 2 * ((a * 64 + b) * 65 + d);
            Complex64::new(f64::from(reals[at]), f64::from(reals[at + 1]))
        });
        let mut c = sample();
        c.engine = c
            .engine
            .array("s_0", SavedArray::Single(shape, reals.clone().into()))
            .array("s_1", SavedArray::Complex(widened.into()))
            .array(
                "big",
                SavedArray::Complex(
                    Array3::from_shape_fn((32, 64, 65), |(a, b, d)| {
                        Complex64::new((a * b) as f64 / 7.0, d as f64 - 0.1)
                    })
                    .into(),
                ),
            );
        let bytes = c.to_bytes();
        assert!(bytes.len() > 3 * CHUNK, "{} bytes", bytes.len());
        let mut back = Checkpoint::from_bytes(&bytes, Path::new("x")).unwrap();
        assert_eq!(back.to_bytes(), bytes);
        assert_eq!(back.engine.arrays[3..], c.engine.arrays[3..]);
        assert_eq!(back.engine.take_single("s_0", &shape).unwrap(), reals);
        assert_eq!(back.engine.take_single("s_1", &shape).unwrap(), reals);
        assert!(back.engine.take_single("s_0", &shape).is_err());
    }

    /// A checkpoint of another version is refused, naming both versions.
    #[test]
    fn other_version_is_refused() {
        let mut c = sample();
        c.version = "0.0.0-other".into();
        let e = Checkpoint::from_bytes(&c.to_bytes(), Path::new("x")).unwrap_err();
        assert!(e.to_string().contains("0.0.0-other"), "{e}");
    }

    /// A checkpoint is written from the engine's own arrays: every array `save` returns but
    /// the small L-BFGS Gram borrows the engine's memory, so writing a checkpoint adds no copy
    /// of the state (1 f64 per point for φ̂, 2 for SBDF2's previous step, 1 per L-BFGS pair) to
    /// the run's peak. A `save` that cloned would own its arrays and fail here.
    #[test]
    fn saving_borrows_the_engines_arrays() {
        use serde_json::json;
        use std::borrow::Cow;
        for (extra, arrays) in [
            (json!({"method": "fd", "dt": 1e-4}), 1),
            (json!({"scheme": "sbdf1"}), 1),
            (json!({"scheme": "sbdf2"}), 3),
            (
                json!({"dynamics": "relaxational", "lbfgs_memory": 3}),
                2 + 2 * 3,
            ),
        ] {
            let mut v = json!({"dim": 3, "n": [16, 16, 16], "dt": 0.5, "max_steps": 4,
                "initial": {"shape": "ellipsoid", "axes": [5.0, 3.5, 3.5]}});
            v.as_object_mut()
                .unwrap()
                .extend(extra.as_object().unwrap().clone());
            let scene = crate::problem::config::from_value(v).expect("scene");
            let problem = crate::problem::setup::build(&scene).expect("problem");
            let mut engine = crate::driver::simulation::build_engine(&scene, &problem).unwrap();
            for i in 0..4 {
                engine.step(i as f64 * scene.dt, scene.dt).expect("step");
            }
            let saved = engine.save();
            assert_eq!(saved.arrays.len(), arrays, "{extra}");
            for (name, a) in &saved.arrays {
                let borrowed = match a {
                    SavedArray::Real(a) => a.is_view(),
                    SavedArray::Complex(a) => a.is_view(),
                    SavedArray::Single(_, v) => matches!(v, Cow::Borrowed(_)),
                };
                assert_eq!(borrowed, name != "gram", "{extra}: `{name}`");
            }
        }
    }
}
