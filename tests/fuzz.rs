//! Fuzzing of the readers of outside input: the scene loader, the `.npy` reader and the
//! checkpoint reader. For arbitrary bytes, arbitrary JSON built from the real key names, and
//! valid headers followed by arbitrary data, none may panic: every failure is an `Err` with a
//! message. A scene that passes validation on a small grid also goes through the memory
//! estimate, the problem set-up and the stability check, which must not panic either.

use proptest::prelude::*;
use serde_json::{Map, Value};
use std::io::Write;
use vesicle::error::Error;
use vesicle::problem::config::{self, Initial};

/// Every key the scene format knows, at any level.
const KEYS: &[&str] = &[
    "description",
    "dim",
    "n",
    "h",
    "eps",
    "method",
    "scheme",
    "dt",
    "adaptive",
    "t_end",
    "max_steps",
    "stop_residual",
    "max_wall_minutes",
    "initial",
    "prepare_steps",
    "c0",
    "area",
    "symmetry",
    "allow_unstable",
    "threads",
    "dynamics",
    "laplacian",
    "lbfgs_memory",
    "stabilizer",
    "output",
    // nested
    "shape",
    "radius",
    "center",
    "axes",
    "axis",
    "kind",
    "reduced_volume",
    "r0",
    "inner_radius",
    "offset",
    "length",
    "of",
    "base",
    "minus",
    "file",
    "inside",
    "outside",
    "width",
    "ramp_time",
    "angle",
    "pole",
    "half_width",
    "alpha",
    "target",
    "dt_min",
    "dt_max",
    "growth",
    "shrink",
    "energy_alpha",
    "s2",
    "s4",
    "record_every",
    "snapshot_every",
    "vti",
    "png",
    "checkpoint_every",
    "checkpoint_minutes",
    "records",
    "snapshots",
    "checkpoints",
    "every_steps",
    "every_time",
    "every_minutes",
    "bogus",
];

/// String values the format gives meaning to, and a few it does not.
const WORDS: &[&str] = &[
    "sphere",
    "ellipsoid",
    "spheroid",
    "cup",
    "capsule",
    "star",
    "union",
    "difference",
    "prolate",
    "oblate",
    "ball",
    "cap",
    "band",
    "+",
    "-",
    "x",
    "y",
    "z",
    "auto",
    "spectral",
    "fd",
    "sbdf1",
    "sbdf2",
    "conserved",
    "relaxational",
    "projection",
    "lagrangian",
    "none",
    "",
    "é\u{0}",
    "does_not_exist.npy",
];

fn key() -> impl Strategy<Value = String> {
    prop::sample::select(KEYS).prop_map(str::to_string)
}

/// Numbers that probe the edges: zero, negative, tiny, huge, non-integral, integer limits.
fn number() -> impl Strategy<Value = Value> {
    prop_oneof![
        (-3i64..40).prop_map(Value::from),
        prop::sample::select(vec![
            0.0,
            -0.0,
            -1.0,
            0.5,
            1.0,
            2.0,
            3.0,
            4.0,
            6.0,
            8.0,
            16.0,
            1e-300,
            1e300,
            -1e300,
            f64::MAX,
            f64::MIN_POSITIVE,
            0.85,
            1.5,
        ])
        .prop_map(Value::from),
        prop::sample::select(vec![u64::MAX, 1 << 40, 1 << 32, 4096]).prop_map(Value::from),
        Just(Value::from(i64::MIN)),
        any::<f64>()
            .prop_filter("finite", |x| x.is_finite())
            .prop_map(Value::from),
    ]
}

fn leaf() -> impl Strategy<Value = Value> {
    prop_oneof![
        Just(Value::Null),
        any::<bool>().prop_map(Value::from),
        number(),
        number(),
        prop::sample::select(WORDS).prop_map(Value::from),
    ]
}

/// Random nested JSON: objects keyed by the real key names, arrays, leaves.
fn json_value() -> impl Strategy<Value = Value> {
    leaf().prop_recursive(4, 48, 6, |inner| {
        prop_oneof![
            prop::collection::vec(inner.clone(), 0..4).prop_map(Value::Array),
            prop::collection::vec((key(), inner), 0..6)
                .prop_map(|kv| Value::Object(kv.into_iter().collect::<Map<_, _>>())),
        ]
    })
}

/// A valid small scene, the base that mutations start from.
fn base_scene() -> Value {
    serde_json::json!({
        "dim": 2, "n": [16, 16], "dt": 0.01, "max_steps": 3,
        "initial": {"shape": "sphere", "radius": 3.0}
    })
}

/// Set `value` at the dotted `path` of `scene`, creating objects on the way (replacing
/// non-objects).
fn set_path(scene: &mut Value, path: &[String], value: Value) {
    let mut node = scene;
    for (i, k) in path.iter().enumerate() {
        if !node.is_object() {
            *node = Value::Object(Map::new());
        }
        let obj = node.as_object_mut().unwrap();
        if i + 1 == path.len() {
            obj.insert(k.clone(), value);
            return;
        }
        node = obj.entry(k.clone()).or_insert(Value::Object(Map::new()));
    }
}

/// An error must carry a message (and a field, for scene errors).
fn assert_message(e: &Error) {
    assert!(!e.to_string().trim().is_empty(), "empty message: {e:?}");
    if let Error::Config { field, reason } = e {
        assert!(!field.is_empty() && !reason.is_empty(), "{e:?}");
    }
}

/// Everything a command does with a scene before it allocates the run: validation, the memory
/// estimate, and (on small grids without a file) the problem set-up and the stability check.
fn exercise(value: Value) {
    let scene = match config::from_value(value) {
        Ok(s) => s,
        Err(e) => return assert_message(&e),
    };
    if let Err(e) = scene.validate() {
        return assert_message(&e);
    }
    let est = vesicle::problem::memory::estimate(&scene);
    assert!(est.bytes > 0.0, "{est:?}");
    let _ = scene.resolved_value();
    let _ = scene.record_every();
    let points: f64 = scene.n.iter().map(|&m| m as f64).product();
    if points <= 64.0 * 64.0 && !matches!(scene.initial, Initial::File { .. }) {
        match vesicle::problem::setup::build(&scene) {
            Ok(problem) => {
                if let Err(e) = vesicle::driver::simulation::check_stability(&scene, &problem.grid)
                {
                    assert_message(&e);
                }
            }
            Err(e) => assert_message(&e),
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 800, ..ProptestConfig::default() })]

    /// Arbitrary bytes: JSON parsing, then the scene reader.
    #[test]
    fn scene_from_arbitrary_bytes(bytes in prop::collection::vec(any::<u8>(), 0..256)) {
        if let Ok(v) = serde_json::from_slice::<Value>(&bytes) {
            exercise(v);
        }
    }

    /// Arbitrary bytes through `config::load` (file reading, the non-finite number rescue).
    #[test]
    fn load_from_arbitrary_bytes(
        bytes in prop::collection::vec(any::<u8>(), 0..256),
        text_like in prop::collection::vec(
            prop::sample::select(&[
                "{", "}", "[", "]", ",", ":", " ", "\n", "\r\n", "\"dim\"", "\"n\"", "\"h\"",
                "\"initial\"", "\"radius\"", "2", "32", "1e999", "-1e999", "0.5", "null", "é",
            ][..]),
            0..40,
        ),
    ) {
        let dir = tempfile::TempDir::new().unwrap();
        for (i, content) in [bytes, text_like.concat().into_bytes()].into_iter().enumerate() {
            let path = dir.path().join(format!("scene{i}.json"));
            std::fs::write(&path, &content).unwrap();
            match config::load(&path, &[]) {
                Ok(scene) => exercise(serde_json::to_value(&scene).unwrap()),
                Err(e) => assert_message(&e),
            }
        }
    }

    /// Arbitrary JSON made of the real key names.
    #[test]
    fn scene_from_random_json(v in json_value()) {
        exercise(v);
    }

    /// A valid scene with one to four random keys set anywhere (deeper into validation).
    #[test]
    fn scene_from_mutated_valid_scene(
        edits in prop::collection::vec(
            (prop::collection::vec(key(), 1..4), json_value()), 1..5),
    ) {
        let mut v = base_scene();
        for (path, value) in edits {
            set_path(&mut v, &path, value);
        }
        exercise(v);
    }
}

// ---------------------------------------------------------------------------------------------
// .npy
// ---------------------------------------------------------------------------------------------

/// An npy v1.0 header dict (padded to 64 bytes) for `descr`, `fortran`, `shape`.
fn npy_header(descr: &str, fortran: bool, shape: &[u64], version: u8) -> Vec<u8> {
    let dims: Vec<String> = shape.iter().map(u64::to_string).collect();
    let shape_txt = match dims.len() {
        1 => format!("({},)", dims[0]),
        _ => format!("({})", dims.join(", ")),
    };
    let fortran = if fortran { "True" } else { "False" };
    let mut dict =
        format!("{{'descr': '{descr}', 'fortran_order': {fortran}, 'shape': {shape_txt}, }}");
    let pre = if version == 1 { 10 } else { 12 };
    while (pre + dict.len() + 1) % 64 != 0 {
        dict.push(' ');
    }
    dict.push('\n');
    let mut out = b"\x93NUMPY".to_vec();
    out.extend([version, 0]);
    if version == 1 {
        out.extend((dict.len() as u16).to_le_bytes());
    } else {
        out.extend((dict.len() as u32).to_le_bytes());
    }
    out.extend(dict.into_bytes());
    out
}

/// Read `bytes` as an npy file of each expected shape: an array of that shape or an error
/// with a message, never a panic.
fn read_all_ways(bytes: &[u8]) {
    let mut file = tempfile::NamedTempFile::new().unwrap();
    file.write_all(bytes).unwrap();
    file.flush().unwrap();
    for expected in [&[4usize, 4][..], &[2, 3, 4], &[1, 1], &[3]] {
        match vesicle::npy::read_npy(file.path(), expected) {
            Ok(a) => {
                let want: usize = expected.iter().product();
                assert_eq!(a.len(), want);
                assert!(expected.len() == 2 || expected.len() == 3);
            }
            Err(e) => assert!(!e.to_string().trim().is_empty()),
        }
    }
}

fn descr() -> impl Strategy<Value = String> {
    prop_oneof![
        prop::sample::select(vec![
            "<f8", ">f8", "=f8", "|f8", "<f4", "<i8", "<u1", "|b1", "<c16", "O", "<U3", "V8",
            "<f8'", "", "f8", "<f16",
        ])
        .prop_map(str::to_string),
        "[<>=|]?[a-zA-Z][0-9]{0,3}",
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 600, ..ProptestConfig::default() })]

    /// Arbitrary bytes, with and without the npy magic in front.
    #[test]
    fn npy_from_arbitrary_bytes(
        magic in any::<bool>(),
        version in 0u8..4,
        tail in prop::collection::vec(any::<u8>(), 0..300),
    ) {
        let mut bytes = Vec::new();
        if magic {
            bytes.extend(b"\x93NUMPY");
            bytes.extend([version, 0]);
        }
        bytes.extend(tail);
        read_all_ways(&bytes);
    }

    /// Valid headers (any dtype, order, shape, including huge) followed by arbitrary data.
    #[test]
    fn npy_valid_header_arbitrary_data(
        descr in descr(),
        fortran in any::<bool>(),
        shape in prop::collection::vec(
            prop_oneof![0u64..6, Just(u64::MAX), Just(1 << 40), Just(1 << 62)], 0..4),
        version in 1u8..3,
        data in prop::collection::vec(any::<u8>(), 0..400),
    ) {
        let mut bytes = npy_header(&descr, fortran, &shape, version);
        bytes.extend(data);
        read_all_ways(&bytes);
    }

    /// A valid file of the expected shape with a few bytes changed anywhere.
    #[test]
    fn npy_flipped_bytes(
        flips in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..6),
        cut in prop::option::of(any::<prop::sample::Index>()),
    ) {
        let mut bytes = npy_header("<f8", false, &[4, 4], 1);
        bytes.extend((0..16).flat_map(|i| (i as f64 * 0.1 - 0.8).to_le_bytes()));
        for (at, b) in flips {
            let i = at.index(bytes.len());
            bytes[i] = b;
        }
        if let Some(c) = cut {
            bytes.truncate(c.index(bytes.len()));
        }
        read_all_ways(&bytes);
    }
}

/// The unflipped file reads back exactly (so the flips above start from a valid file).
#[test]
fn npy_valid_file_reads() {
    let mut bytes = npy_header("<f8", false, &[4, 4], 1);
    bytes.extend((0..16).flat_map(|i| (i as f64).to_le_bytes()));
    let mut file = tempfile::NamedTempFile::new().unwrap();
    file.write_all(&bytes).unwrap();
    let a = vesicle::npy::read_npy(file.path(), &[4, 4]).unwrap();
    assert_eq!(a[[0, 3, 2]], 14.0);
    let mut bytes = npy_header("<f8", false, &[4, 4], 2);
    bytes.extend((0..16).flat_map(|i| (i as f64).to_le_bytes()));
    std::fs::write(file.path(), &bytes).unwrap();
    let a = vesicle::npy::read_npy(file.path(), &[4, 4]).unwrap();
    assert_eq!(a[[0, 1, 1]], 5.0);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(600))]

    /// The checkpoint reader on arbitrary bytes, with and without the magic prefix and a
    /// plausible header length: an error with a message, never a panic.
    #[test]
    fn checkpoint_reader_never_panics(
        bytes in prop::collection::vec(any::<u8>(), 0..400),
        with_magic in any::<bool>(),
        header_len in 0u64..512,
    ) {
        let mut data = Vec::new();
        if with_magic {
            data.extend_from_slice(vesicle::driver::checkpoint::MAGIC);
            data.extend_from_slice(&header_len.to_le_bytes());
        }
        data.extend_from_slice(&bytes);
        let r = vesicle::driver::checkpoint::Checkpoint::from_bytes(&data, std::path::Path::new("x"));
        prop_assert!(r.is_err(), "arbitrary bytes were accepted as a checkpoint");
        prop_assert!(!r.unwrap_err().to_string().is_empty());
    }
}
