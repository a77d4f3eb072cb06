//! Integration tests of the `vesicle` command line: the invalid-scene corpus in
//! `tests/bad_scenes/` (every file must be refused with exit code 2, a message naming the
//! field, and no output folder), `--set` overrides, tiny runs of the example scenes and their
//! output files, the output-folder rules (an existing folder, one that cannot be written), a
//! grid too large for memory, a blow-up (exit 3 with the last good state written), and the
//! help texts.

use serde_json::Value;
use std::collections::BTreeMap;
use std::ffi::OsStr;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use tempfile::TempDir;

// ---------------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------------

/// The CSV columns every run writes first, in this order.
const CONTRACT_COLUMNS: &[&str] = &[
    "step",
    "t",
    "dt",
    "energy",
    "area",
    "volume",
    "reduced_volume",
    "reduced_energy",
    "sigma",
    "residual",
];

fn crate_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn corpus_dir() -> PathBuf {
    crate_dir().join("tests").join("bad_scenes")
}

fn runs_dir() -> PathBuf {
    crate_dir().join("runs")
}

/// Run the binary with `args` from the crate root.
fn vesicle<I, S>(args: I) -> Output
where
    I: IntoIterator<Item = S>,
    S: AsRef<std::ffi::OsStr>,
{
    Command::new(env!("CARGO_BIN_EXE_vesicle"))
        .args(args)
        .current_dir(crate_dir())
        .output()
        .expect("the vesicle binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Exit code, with a readable panic message if the process was killed by a signal (a crash).
fn code(o: &Output) -> i32 {
    o.status
        .code()
        .unwrap_or_else(|| panic!("killed by a signal; stderr:\n{}", stderr(o)))
}

/// `tests/bad_scenes/expected.json`: file name → substring of the error message.
fn manifest() -> BTreeMap<String, String> {
    let text = fs::read_to_string(corpus_dir().join("expected.json")).expect("manifest");
    serde_json::from_str(&text).expect("manifest is a JSON object of strings")
}

/// An npy v1.0 file: magic, version, header dict padded with spaces to a multiple of 64
/// bytes (ending in a newline), then the raw data.
fn npy_bytes(descr: &str, shape: &[usize], data: &[u8]) -> Vec<u8> {
    npy_bytes_ordered(descr, false, shape, data)
}

/// As [`npy_bytes`], with the `fortran_order` flag given.
fn npy_bytes_ordered(descr: &str, fortran: bool, shape: &[usize], data: &[u8]) -> Vec<u8> {
    let shape_txt = match shape {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(|n| n.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    let mut header = format!(
        "{{'descr': '{descr}', 'fortran_order': {}, 'shape': {shape_txt}, }}",
        if fortran { "True" } else { "False" }
    );
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    out.extend_from_slice(data);
    out
}

fn f64_bytes(values: impl IntoIterator<Item = f64>) -> Vec<u8> {
    values.into_iter().flat_map(f64::to_le_bytes).collect()
}

/// φ = tanh(d/√2) of a centred circle of radius `r` on an `n × n` box (h = ε = 1).
fn circle_phi(n: usize, r: f64) -> Vec<f64> {
    let c = |i: usize| i as f64 + 0.5 - n as f64 / 2.0;
    (0..n * n)
        .map(|k| {
            let (i, j) = (k / n, k % n);
            ((r - c(i).hypot(c(j))) / std::f64::consts::SQRT_2).tanh()
        })
        .collect()
}

/// The `.npy` fixtures the `initial_file_*` corpus scenes refer to (their `n` is `[32, 32]`).
fn write_npy_fixtures(dir: &Path) {
    let good = circle_phi(32, 6.0);
    let write = |name: &str, bytes: Vec<u8>| fs::write(dir.join(name), bytes).unwrap();
    write(
        "fixture_8x8.npy",
        npy_bytes("<f8", &[8, 8], &f64_bytes(circle_phi(8, 2.0))),
    );
    write(
        "fixture_32x32x1.npy",
        npy_bytes("<f8", &[32, 32, 1], &f64_bytes(good.clone())),
    );
    let mut nan = good.clone();
    nan[32 * 16 + 16] = f64::NAN;
    write(
        "fixture_32x32_nan.npy",
        npy_bytes("<f8", &[32, 32], &f64_bytes(nan)),
    );
    let f4: Vec<u8> = good
        .iter()
        .flat_map(|&x| (x as f32).to_le_bytes())
        .collect();
    write("fixture_32x32_f4.npy", npy_bytes("<f4", &[32, 32], &f4));
    write("fixture_not_npy.npy", b"this is not an npy file\n".to_vec());
    // r,z contours for the axisym shape: a unit sphere (R0 = 1), and broken ones
    let contour = |radius: f64, last_r: f64, neg: bool| {
        let mut t = String::from("r,z\n");
        for i in 0..=40 {
            let a = std::f64::consts::PI * i as f64 / 40.0;
            let mut r = radius * a.sin();
            if i == 40 {
                r = last_r;
            }
            if neg && i == 20 {
                r = -0.5;
            }
            t.push_str(&format!("{r:.12e},{:.12e}\n", radius * (1.0 - a.cos())));
        }
        t.into_bytes()
    };
    write("fixture_contour_good.csv", contour(1.0, 0.0, false));
    write("fixture_contour_open.csv", contour(1.0, 0.5, false));
    write("fixture_contour_negative_r.csv", contour(1.0, 0.0, true));
    write("fixture_contour_r0_2.csv", contour(2.0, 0.0, false));
    write(
        "fixture_contour_garbage.csv",
        b"r,z\n0.0,0.0\n0.5,abc\n".to_vec(),
    );
    // wrong dtypes holding the same field
    let i8: Vec<u8> = good
        .iter()
        .flat_map(|&x| ((x * 100.0) as i64).to_le_bytes())
        .collect();
    write("fixture_32x32_i8.npy", npy_bytes("<i8", &[32, 32], &i8));
    let be: Vec<u8> = good.iter().flat_map(|x| x.to_be_bytes()).collect();
    write("fixture_32x32_be.npy", npy_bytes(">f8", &[32, 32], &be));
    // the transposed field in Fortran order: the same array, another memory order
    let fortran: Vec<f64> = (0..32 * 32).map(|k| good[(k % 32) * 32 + k / 32]).collect();
    write(
        "fixture_32x32_fortran.npy",
        npy_bytes_ordered("<f8", true, &[32, 32], &f64_bytes(fortran)),
    );
    let mut inf = good.clone();
    inf[3] = f64::INFINITY;
    write(
        "fixture_32x32_inf.npy",
        npy_bytes("<f8", &[32, 32], &f64_bytes(inf)),
    );
    // the header promises 32 × 32 values; 100 are there
    write(
        "fixture_32x32_truncated.npy",
        npy_bytes("<f8", &[32, 32], &f64_bytes(good[..100].to_vec())),
    );
    let mut extra = good.clone();
    extra.extend([0.0; 8]);
    write(
        "fixture_32x32_extra.npy",
        npy_bytes("<f8", &[32, 32], &f64_bytes(extra)),
    );
    // a valid preamble, then a header dict cut short and padded
    let mut corrupt = npy_bytes("<f8", &[32, 32], &f64_bytes(good.clone()));
    for b in &mut corrupt[30..60] {
        *b = b'#';
    }
    write("fixture_corrupt_header.npy", corrupt);
    write("fixture_empty.npy", Vec::new());
    // a valid header of a grid too large to read: refused on its shape, before any data
    write(
        "fixture_huge_shape.npy",
        npy_bytes("<f8", &[1 << 40, 1 << 40], &[]),
    );
    fs::create_dir_all(dir.join("fixture_dir.npy")).unwrap();
    write(
        "fixture_32x32_good.npy",
        npy_bytes("<f8", &[32, 32], &f64_bytes(good)),
    );
}

/// A temporary copy of the corpus with the `.npy` fixtures beside it.
fn staged_corpus() -> TempDir {
    let dir = TempDir::new().unwrap();
    for entry in fs::read_dir(corpus_dir()).unwrap() {
        let p = entry.unwrap().path();
        fs::copy(&p, dir.path().join(p.file_name().unwrap())).unwrap();
    }
    write_npy_fixtures(dir.path());
    dir
}

/// Check that `vesicle check` and `vesicle run --out` refuse `scene` with exit 2, a message
/// containing `expect`, and no output folder. Returns a description of each failure.
fn rejection_failures(scene: &Path, extra: &[&str], expect: &str, tmp: &Path) -> Vec<String> {
    let name = scene.file_name().unwrap().to_string_lossy().into_owned();
    let mut failures = Vec::new();
    let mut check_args = vec![OsStr::new("check"), scene.as_os_str()];
    check_args.extend(extra.iter().map(OsStr::new));
    let o = vesicle(&check_args);
    if o.status.code() != Some(2) || !stderr(&o).contains(expect) {
        failures.push(format!(
            "check {name} {extra:?}: exit {:?}, expected 2 and {expect:?} in stderr:\n{}",
            o.status.code(),
            stderr(&o).trim()
        ));
    }
    let out = tmp.join(format!("out_{name}"));
    let mut run_args = vec![
        OsStr::new("run"),
        scene.as_os_str(),
        OsStr::new("--out"),
        out.as_os_str(),
    ];
    run_args.extend(extra.iter().map(OsStr::new));
    let o = vesicle(&run_args);
    if o.status.code() != Some(2) || !stderr(&o).contains(expect) {
        failures.push(format!(
            "run {name} {extra:?}: exit {:?}, expected 2 and {expect:?} in stderr:\n{}",
            o.status.code(),
            stderr(&o).trim()
        ));
    }
    if out.exists() {
        failures.push(format!(
            "run {name} {extra:?}: left an output folder behind"
        ));
    }
    failures
}

/// Parse an npy file: (descr, fortran_order, shape, values).
fn read_npy(path: &Path) -> (String, bool, Vec<usize>, Vec<f64>) {
    let bytes = fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(&bytes[..6], b"\x93NUMPY", "npy magic");
    let (len, start) = match bytes[6] {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
        _ => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        ),
    };
    assert_eq!((start + len) % 64, 0, "npy header padded to 64 bytes");
    let header = std::str::from_utf8(&bytes[start..start + len]).unwrap();
    let field = |key: &str| {
        let at = header
            .find(&format!("'{key}':"))
            .unwrap_or_else(|| panic!("no {key} in npy header {header:?}"));
        header[at + key.len() + 3..].trim_start().to_string()
    };
    let descr = field("descr");
    let descr = descr.split('\'').nth(1).unwrap().to_string();
    let fortran = field("fortran_order").starts_with("True");
    let shape_txt = field("shape");
    let shape: Vec<usize> = shape_txt[1..shape_txt.find(')').unwrap()]
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.parse().unwrap())
        .collect();
    let data = &bytes[start + len..];
    assert_eq!(data.len() % 8, 0);
    let values = data
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect();
    (descr, fortran, shape, values)
}

fn read_json(path: &Path) -> Value {
    let text = fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap()
}

/// Names and contents of the entries of `dir`, recursively (for "left untouched" checks).
fn snapshot_dir(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    for entry in fs::read_dir(dir).unwrap() {
        let p = entry.unwrap().path();
        if p.is_dir() {
            out.insert(p.clone(), Vec::new());
            out.extend(snapshot_dir(&p));
        } else {
            out.insert(p.clone(), fs::read(&p).unwrap());
        }
    }
    out
}

/// The step number in "run stopped at step N, t = ..." of a blow-up message.
fn blowup_step(message: &str) -> usize {
    let at = message
        .find("at step ")
        .expect("blow-up message names the step")
        + 8;
    message[at..]
        .split(|c: char| !c.is_ascii_digit())
        .next()
        .unwrap()
        .parse()
        .unwrap()
}

// ---------------------------------------------------------------------------------------------
// The invalid-scene corpus
// ---------------------------------------------------------------------------------------------

#[test]
fn corpus_manifest_matches_the_files() {
    let expected = manifest();
    let mut on_disk: Vec<String> = fs::read_dir(corpus_dir())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n != "expected.json")
        .collect();
    on_disk.sort();
    let listed: Vec<String> = expected.keys().cloned().collect();
    assert_eq!(on_disk, listed, "tests/bad_scenes and expected.json differ");
    for (f, s) in &expected {
        assert!(!s.is_empty(), "{f}: empty expected substring");
    }
}

#[test]
fn corpus_is_rejected_with_exit_2_and_no_output() {
    let corpus = staged_corpus();
    let expected = manifest();
    let mut failures = Vec::new();
    let mut checked = 0;
    for (file, expect) in &expected {
        failures.extend(rejection_failures(
            &corpus.path().join(file),
            &[],
            expect,
            corpus.path(),
        ));
        checked += 1;
    }
    assert!(checked >= 100, "only {checked} corpus cases");
    assert!(
        failures.is_empty(),
        "{} failure(s):\n\n{}",
        failures.len(),
        failures.join("\n\n")
    );
}

/// The corpus's `.npy` fixtures are valid except for the defect each one carries: the good one
/// is accepted, so the others fail for their defect, and the messages say which.
#[test]
fn initial_file_fixtures_fail_for_their_own_defect() {
    let corpus = staged_corpus();
    let scene = corpus.path().join("initial_file_missing.json");
    let set = |f: &str| format!("initial={{\"file\": \"{f}\"}}");
    let ok = vesicle([
        OsStr::new("check"),
        scene.as_os_str(),
        OsStr::new("--set"),
        OsStr::new(&set("fixture_32x32_good.npy")),
    ]);
    assert_eq!(code(&ok), 0, "{}", stderr(&ok));
    for (fixture, words) in [
        ("fixture_8x8.npy", &["[32, 32]", "[8, 8]"][..]),
        ("fixture_32x32x1.npy", &["[32, 32, 1]"][..]),
        ("fixture_32x32_nan.npy", &["non-finite", "NaN"][..]),
        ("fixture_32x32_inf.npy", &["non-finite", "inf"][..]),
        ("fixture_32x32_f4.npy", &["<f4"][..]),
        ("fixture_32x32_i8.npy", &["<i8"][..]),
        ("fixture_32x32_be.npy", &[">f8"][..]),
        ("fixture_32x32_fortran.npy", &["Fortran order"][..]),
        ("fixture_32x32_truncated.npy", &["invalid npy data"][..]),
        ("fixture_32x32_extra.npy", &["invalid npy data"][..]),
        ("fixture_corrupt_header.npy", &["invalid npy header"][..]),
        ("fixture_empty.npy", &["ends before its header"][..]),
        ("fixture_not_npy.npy", &["invalid npy header"][..]),
        (
            "fixture_huge_shape.npy",
            &["[1099511627776, 1099511627776]"][..],
        ),
        ("fixture_dir.npy", &["fixture_dir.npy"][..]),
        ("does_not_exist.npy", &["does_not_exist.npy"][..]),
    ] {
        let o = vesicle([
            OsStr::new("check"),
            scene.as_os_str(),
            OsStr::new("--set"),
            OsStr::new(&set(fixture)),
        ]);
        assert_eq!(code(&o), 2, "{fixture}: {}", stderr(&o));
        assert!(
            stderr(&o).contains("initial.file"),
            "{fixture}: {}",
            stderr(&o)
        );
        for w in words {
            assert!(stderr(&o).contains(w), "{fixture}: {w:?} in {}", stderr(&o));
        }
    }
}

#[test]
fn fd_dt_above_bound_is_accepted_with_allow_unstable() {
    let scene = corpus_dir().join("fd_dt_above_bound.json");
    let o = vesicle([
        OsStr::new("check"),
        scene.as_os_str(),
        OsStr::new("--set"),
        OsStr::new("allow_unstable=true"),
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let tmp = TempDir::new().unwrap();
    let out = tmp.path().join("x");
    let o = vesicle([
        OsStr::new("run"),
        scene.as_os_str(),
        OsStr::new("--out"),
        out.as_os_str(),
        OsStr::new("--set"),
        OsStr::new("allow_unstable=true"),
        OsStr::new("--set"),
        OsStr::new("max_steps=2"),
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    assert!(out.join("summary.json").exists());
    // The bound in the message: 1e-3 against 1/(12·14²) ≈ 4.25e-4.
    let o = vesicle([OsStr::new("check"), scene.as_os_str()]);
    assert_eq!(code(&o), 2);
    assert!(stderr(&o).contains("4.2517e-4"), "{}", stderr(&o));
    assert!(stderr(&o).contains("allow_unstable"), "{}", stderr(&o));
}

// ---------------------------------------------------------------------------------------------
// --set overrides and other command-line input errors
// ---------------------------------------------------------------------------------------------

#[test]
fn bad_overrides_are_rejected_with_exit_2_and_no_output() {
    let tmp = TempDir::new().unwrap();
    let sphere = runs_dir().join("sphere3d.json");
    let ellipse = runs_dir().join("ellipse2d.json");
    let cases: &[(&Path, &[&str], &str)] = &[
        (&sphere, &["--set", "dim=4"], "`dim`"),
        (&sphere, &["--set", "dim=2"], "`n`"),
        (&sphere, &["--set", "area.alpha=-1"], "`area.alpha`"),
        (&sphere, &["--set", "area.alpha=0.01"], "`area.alpha`"),
        (&sphere, &["--set", "nokey=1"], "`nokey`"),
        (&sphere, &["--set", "area.nokey=1"], "`area.nokey`"),
        (
            &sphere,
            &["--set", "c0=0.1", "--set", "c0.inside=1"],
            "`c0`",
        ),
        (&sphere, &["--set", "dt.x=1"], "`dt`"),
        (&sphere, &["--set", "dt"], "--set expects key=value"),
        (&sphere, &["--set", "h=1e999"], "`h`"),
        (&sphere, &["--set", "h=-1"], "`h`"),
        (&sphere, &["--set", "n=[16,16]"], "`n`"),
        (&sphere, &["--set", "initial.radius=-1"], "`initial.radius`"),
        (&sphere, &["--set", "initial.radius=30"], "does not fit"),
        (&sphere, &["--set", "symmetry=[\"x\",\"x\"]"], "`symmetry`"),
        (&sphere, &["--set", "max_steps=0"], "`max_steps`"),
        (
            &sphere,
            &["--set", "method=fd", "--set", "scheme=null"],
            "`dt`",
        ),
        (&sphere, &["--set", "method=fd"], "`scheme`: ignored by"),
        (
            &ellipse,
            &["--set", "adaptive.growth=3"],
            "`adaptive.growth`",
        ),
        (
            &ellipse,
            &["--set", "adaptive.dt_max=0.001"],
            "`adaptive.dt_max`",
        ),
        (&ellipse, &["--set", "method=fd"], "`adaptive`"),
        (
            &ellipse,
            &["--set", "method=fd", "--set", "adaptive=null"],
            "`scheme`: ignored by \"method\": \"fd\"",
        ),
        (
            &ellipse,
            &["--set", "dynamics=relaxational", "--set", "scheme=null"],
            "`adaptive`: ignored by \"dynamics\": \"relaxational\"",
        ),
        (&sphere, &["--set", "lbfgs_memory=3"], "`lbfgs_memory`"),
        // A required key removed is named as the field itself.
        (&sphere, &["--set", "dt=null"], "`dt`: required, missing"),
        (
            &sphere,
            &["--set", "initial=null"],
            "`initial`: required, missing",
        ),
        (
            &sphere,
            &["--set", "initial.radius=null"],
            "`initial.radius`: required, missing",
        ),
    ];
    let mut failures = Vec::new();
    for (scene, extra, expect) in cases {
        failures.extend(rejection_failures(scene, extra, expect, tmp.path()));
        // every case writes to the same out_ path: make sure nothing was left for the next
        assert!(!tmp
            .path()
            .join(format!(
                "out_{}",
                scene.file_name().unwrap().to_string_lossy()
            ))
            .exists());
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn missing_scene_file_is_exit_2() {
    let tmp = TempDir::new().unwrap();
    let out = tmp.path().join("x");
    let o = vesicle([
        OsStr::new("run"),
        OsStr::new("runs/no_such_scene.json"),
        OsStr::new("--out"),
        out.as_os_str(),
    ]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("no_such_scene.json"), "{}", stderr(&o));
    assert!(!out.exists());
    let o = vesicle(["check", "runs/no_such_scene.json"]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
}

// ---------------------------------------------------------------------------------------------
// Valid scenes and their outputs
// ---------------------------------------------------------------------------------------------

/// Run `runs/<name>` tiny and check every output file, and that the resolved scene under
/// `"spec"` reads back as a valid scene. Returns `summary.json`.
fn run_example_tiny(name: &str, overrides: &[&str]) -> Value {
    let scene_path = runs_dir().join(name);
    let scene = read_json(&scene_path);
    let n: Vec<usize> = scene["n"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap() as usize)
        .collect();
    let tmp = TempDir::new().unwrap();
    let out = tmp.path().join("x");
    let mut args = vec![
        OsStr::new("run"),
        scene_path.as_os_str(),
        OsStr::new("--out"),
        out.as_os_str(),
        OsStr::new("--quiet"),
    ];
    for o in overrides {
        args.push(OsStr::new("--set"));
        args.push(OsStr::new(o));
    }
    let started = std::time::Instant::now();
    let o = vesicle(&args);
    let process_seconds = started.elapsed().as_secs_f64();
    assert_eq!(code(&o), 0, "{name}: {}", stderr(&o));
    assert!(
        !out.join("snapshots").exists(),
        "{name}: no snapshots asked for, no snapshots/ folder"
    );

    // timeseries.csv
    let csv = fs::read_to_string(out.join("timeseries.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(
        &header[..CONTRACT_COLUMNS.len()],
        CONTRACT_COLUMNS,
        "{name}"
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert!(rows.len() >= 2, "{name}: initial and final rows");
    for r in &rows {
        assert_eq!(r.len(), header.len(), "{name}: ragged CSV row {r:?}");
    }
    assert_eq!(rows[0][0], "0", "{name}: first row is step 0");

    // summary.json
    let summary = read_json(&out.join("summary.json"));
    for key in ["spec", "final", "steps", "wall_seconds", "stopped"] {
        assert!(
            summary.get(key).is_some(),
            "{name}: summary.json lacks {key}"
        );
    }
    let final_keys: Vec<&str> = summary["final"]
        .as_object()
        .unwrap()
        .keys()
        .map(String::as_str)
        .collect();
    // "final": the last row of the time series, its CSV columns, plus "steps" and "stopped"
    // (docs/src/reference/outputs.md, `summary.json`; "wall_seconds" is a column).
    let mut expected_final = header.clone();
    expected_final.extend(["steps", "stopped"]);
    expected_final.sort_unstable();
    let mut sorted_final = final_keys.clone();
    sorted_final.sort_unstable();
    assert_eq!(
        sorted_final, expected_final,
        "{name}: final keys vs CSV columns + steps, stopped"
    );
    assert_eq!(summary["final"]["stopped"], summary["stopped"], "{name}");
    assert_eq!(summary["final"]["steps"], summary["steps"], "{name}");
    let steps = summary["steps"].as_u64().unwrap();
    assert!(steps >= 1, "{name}");
    assert_eq!(summary["final"]["step"].as_u64(), Some(steps), "{name}");
    assert_eq!(
        rows.last().unwrap()[0],
        steps.to_string(),
        "{name}: last CSV row is the final state"
    );
    // The time loop's wall time: it took some time, less than the whole process took, and it
    // is the last row's (the column never falls).
    let wall = summary["wall_seconds"].as_f64().unwrap();
    assert!(
        wall > 0.0 && wall < process_seconds,
        "{name}: wall_seconds {wall} against {process_seconds} s for the process"
    );
    let column = header.iter().position(|c| *c == "wall_seconds").unwrap();
    let walls: Vec<f64> = rows.iter().map(|r| r[column].parse().unwrap()).collect();
    assert!(walls.windows(2).all(|w| w[0] <= w[1]), "{name}: {walls:?}");
    assert_eq!(
        walls.last(),
        Some(&wall),
        "{name}: the last row's wall time"
    );
    assert!(
        summary["stopped"].is_string() && !summary["stopped"].as_str().unwrap().is_empty(),
        "{name}"
    );
    assert_eq!(summary["spec"]["n"], scene["n"], "{name}");
    assert_eq!(summary["spec"]["dim"], scene["dim"], "{name}");
    let spec = vesicle::problem::config::from_value(summary["spec"].clone())
        .unwrap_or_else(|e| panic!("{name}: the spec does not read back: {e}"));
    spec.validate()
        .unwrap_or_else(|e| panic!("{name}: the spec does not validate: {e}"));

    // phi_final.npy: float64, C order, the FULL box even on a mirror-reduced computation
    let (descr, fortran, shape, values) = read_npy(&out.join("phi_final.npy"));
    assert_eq!(descr, "<f8", "{name}");
    assert!(!fortran, "{name}");
    assert_eq!(shape, n, "{name}: phi_final.npy shape");
    assert_eq!(values.len(), n.iter().product::<usize>(), "{name}");
    assert!(values.iter().all(|v| v.is_finite()), "{name}");
    assert!(values.iter().any(|&v| v > 0.5) && values.iter().any(|&v| v < -0.5));

    // VTI and PNG
    let vti = fs::read(out.join("phi_final.vti")).unwrap();
    let vti_head = String::from_utf8_lossy(&vti[..vti.len().min(400)]);
    assert!(
        vti_head.contains("<VTKFile") && vti_head.contains("ImageData"),
        "{name}"
    );
    let png = fs::read(out.join("shape_final.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "{name}");
    summary
}

#[test]
fn example_ellipse2d_runs_tiny() {
    run_example_tiny("ellipse2d.json", &["max_steps=3", "prepare_steps=2"]);
}

#[test]
fn example_sphere3d_runs_tiny() {
    run_example_tiny("sphere3d.json", &["max_steps=3", "prepare_steps=2"]);
}

#[test]
fn example_prolate3d_runs_tiny() {
    run_example_tiny("prolate3d.json", &["max_steps=3", "prepare_steps=2"]);
}

#[test]
fn example_prolate3d_fd_runs_tiny() {
    // 3 steps of dt = 4e-4
    run_example_tiny(
        "prolate3d_fd.json",
        &["t_end=0.0012", "prepare_steps=2", "output.record_every=1"],
    );
}

/// `--set key=null` removes a key: the spectral prolate becomes its FD reference, and the
/// resolved spec leaves out what FD ignores and shows the automatic `record_every`.
#[test]
fn set_null_turns_the_spectral_prolate_into_its_fd_reference() {
    let summary = run_example_tiny(
        "prolate3d.json",
        &[
            "method=fd",
            "scheme=null",
            "adaptive=null",
            "dt=4e-4",
            "output.record_every=null",
            "max_steps=3",
            "prepare_steps=2",
        ],
    );
    let spec = &summary["spec"];
    assert_eq!(spec["method"], "fd");
    assert_eq!(summary["steps"], 3);
    for key in [
        "scheme",
        "adaptive",
        "laplacian",
        "stabilizer",
        "lbfgs_memory",
    ] {
        assert!(spec.get(key).is_none(), "the fd spec keeps {key}: {spec}");
    }
    assert_eq!(spec["output"]["record_every"], 1, "3 steps: every step");
}

/// A relaxational run's spec leaves out `scheme` and `adaptive` and reads back.
#[test]
fn relaxational_run_spec_reads_back() {
    let summary = run_example_tiny(
        "ellipse2d.json",
        &[
            "dynamics=relaxational",
            "scheme=null",
            "adaptive=null",
            "max_steps=3",
            "prepare_steps=2",
        ],
    );
    let spec = &summary["spec"];
    assert_eq!(spec["dynamics"], "relaxational");
    for key in ["scheme", "adaptive"] {
        assert!(spec.get(key).is_none(), "the relaxational spec keeps {key}");
    }
    assert_eq!(spec["lbfgs_memory"], 5);
}

#[test]
fn initial_field_from_npy_runs_and_round_trips_the_box() {
    let dir = TempDir::new().unwrap();
    write_npy_fixtures(dir.path());
    let scene = dir.path().join("from_file.json");
    fs::write(
        &scene,
        r#"{"dim": 2, "n": [32, 32], "dt": 0.01, "max_steps": 2,
            "initial": {"file": "fixture_32x32_good.npy"}, "symmetry": "auto"}"#,
    )
    .unwrap();
    let out = dir.path().join("x");
    let o = vesicle([
        OsStr::new("run"),
        scene.as_os_str(),
        OsStr::new("--out"),
        out.as_os_str(),
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let (_, _, shape, values) = read_npy(&out.join("phi_final.npy"));
    assert_eq!(shape, vec![32, 32]);
    assert!(values.iter().all(|v| v.is_finite()));
    let summary = read_json(&out.join("summary.json"));
    // the centred circle is even about both box planes: auto symmetry computes a quarter
    assert_eq!(summary["computed_shape"], serde_json::json!([16, 16]));
}

#[test]
fn check_prints_the_resolved_scene() {
    let o = vesicle(["check", "runs/prolate3d.json"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let resolved: Value = serde_json::from_str(&stdout(&o)).expect("check prints JSON");
    assert_eq!(resolved["area"]["method"], "projection");
    assert_eq!(resolved["dim"], 3);
    assert_eq!(resolved["n"], serde_json::json!([48, 48, 48]));
    assert_eq!(resolved["symmetry"], serde_json::json!(["x", "y", "z"]));
    assert!(resolved["threads"].as_u64().unwrap() >= 1);
    for key in [
        "method",
        "scheme",
        "dynamics",
        "stabilizer",
        "output",
        "adaptive",
    ] {
        assert!(resolved.get(key).is_some(), "resolved scene lacks {key}");
    }
    let o = vesicle(["check", "runs/prolate3d_fd.json"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let resolved: Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(resolved["area"]["method"], "lagrangian");
    assert_eq!(resolved["area"]["alpha"], 0.001);
}

// ---------------------------------------------------------------------------------------------
// Output folder rules
// ---------------------------------------------------------------------------------------------

#[test]
fn existing_output_folder_needs_force() {
    let tmp = TempDir::new().unwrap();
    let out = tmp.path().join("x");
    fs::create_dir_all(out.join("sub")).unwrap();
    fs::write(out.join("keep.txt"), "precious").unwrap();
    fs::write(out.join("sub").join("summary.json"), "{}").unwrap();
    let before = snapshot_dir(&out);
    let run = |extra: &[&str]| {
        let mut args = vec![
            OsStr::new("run"),
            OsStr::new("runs/sphere3d.json"),
            OsStr::new("--out"),
            out.as_os_str(),
            OsStr::new("--set"),
            OsStr::new("max_steps=2"),
            OsStr::new("--set"),
            OsStr::new("prepare_steps=1"),
        ];
        args.extend(extra.iter().map(OsStr::new));
        vesicle(&args)
    };
    let o = run(&[]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("--force"), "{}", stderr(&o));
    assert_eq!(snapshot_dir(&out), before, "folder touched without --force");

    // an invalid scene with --force leaves the folder alone too
    let o = run(&["--force", "--set", "dt=-1"]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert_eq!(
        snapshot_dir(&out),
        before,
        "folder touched by a refused scene"
    );

    let o = run(&["--force"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    assert!(
        !out.join("keep.txt").exists(),
        "--force replaces the folder"
    );
    assert!(!out.join("sub").exists(), "--force replaces the folder");
    for f in [
        "timeseries.csv",
        "summary.json",
        "phi_final.npy",
        "phi_final.vti",
        "shape_final.png",
    ] {
        assert!(out.join(f).exists(), "{f} after --force");
    }
}

/// An output folder that cannot be made is a usage error: exit 2 naming `--out`, before any
/// computation (the scene would run for minutes), and nothing is left anywhere.
#[test]
fn unwritable_output_folder_is_exit_2_before_computing() {
    let tmp = TempDir::new().unwrap();
    let file = tmp.path().join("file.txt");
    fs::write(&file, "not a folder").unwrap();
    let readonly = tmp.path().join("readonly");
    fs::create_dir(&readonly).unwrap();
    let mut cases: Vec<(PathBuf, Vec<&str>, &str)> = vec![
        (file.join("x"), vec![], "is not a folder"),
        (file.join("a").join("b"), vec![], "is not a folder"),
        (file.clone(), vec!["--force"], "is not a folder"),
    ];
    if Path::new("/proc/self").exists() {
        cases.push((PathBuf::from("/proc/forbidden/x"), vec![], "not writable"));
    }
    // a read-only folder (root writes anyway: then the case says nothing)
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        fs::set_permissions(&readonly, fs::Permissions::from_mode(0o555)).unwrap();
        if fs::create_dir(readonly.join("probe")).is_err() {
            cases.push((readonly.join("x"), vec![], "not writable"));
        } else {
            fs::remove_dir(readonly.join("probe")).unwrap();
        }
    }
    let before = snapshot_dir(tmp.path());
    // prolate3d runs up to 40 000 steps after 20 preparation steps: a command that computed
    // before checking its folder would write nothing either, but would take minutes (the
    // suite's length shows it; no wall-clock assertion here).
    for (out, extra, why) in &cases {
        for command in [&["run"][..], &["compare"][..], &["study", "stationary"][..]] {
            let mut args: Vec<&OsStr> = command.iter().map(OsStr::new).collect();
            args.extend([
                OsStr::new("runs/prolate3d.json"),
                OsStr::new("--out"),
                out.as_os_str(),
            ]);
            args.extend(extra.iter().map(OsStr::new));
            let o = vesicle(&args);
            let what = format!("{command:?} --out {} {extra:?}", out.display());
            assert_eq!(code(&o), 2, "{what}: {}", stderr(&o));
            assert!(stderr(&o).contains("`--out`"), "{what}: {}", stderr(&o));
            assert!(
                stderr(&o).contains(why),
                "{what}: {why:?} in {}",
                stderr(&o)
            );
        }
    }
    assert_eq!(snapshot_dir(tmp.path()), before, "something was written");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        fs::set_permissions(&readonly, fs::Permissions::from_mode(0o755)).unwrap();
    }
}

/// A grid whose estimated peak memory exceeds the machine's is refused up front: exit 2 naming
/// `n`, with the estimate in bytes and f64 per point and the memory available, no output
/// folder, and no allocation attempted (it returns at once).
#[test]
fn grid_too_large_for_memory_is_refused_up_front() {
    if fs::read_to_string("/proc/meminfo").is_err() {
        eprintln!("no /proc/meminfo: the memory check is skipped, and so is this test");
        return;
    }
    let tmp = TempDir::new().unwrap();
    for n in [
        "n=[4096,4096,4096]",
        // the point count overflows 64-bit integers
        "n=[4294967296,4294967296,4294967296]",
    ] {
        for extra in [
            &[][..],
            &["--set", "method=fd", "--set", "scheme=null"][..],
            &["--set", "dynamics=relaxational", "--set", "scheme=null"][..],
        ] {
            let out = tmp.path().join("x");
            let mut args = vec![
                OsStr::new("run"),
                OsStr::new("runs/sphere3d.json"),
                OsStr::new("--out"),
                out.as_os_str(),
                OsStr::new("--set"),
                OsStr::new(n),
            ];
            args.extend(extra.iter().map(OsStr::new));
            let o = vesicle(&args);
            let err = stderr(&o);
            assert_eq!(code(&o), 2, "{n} {extra:?}: {err}");
            for w in ["`n`", "bytes", "f64 per computed point", "available"] {
                assert!(err.contains(w), "{n} {extra:?}: {w:?} in {err}");
            }
            // Refused by the estimate, not by a failed allocation: the message names the
            // estimate (an attempted allocation of this size would abort, not exit 2).
            assert!(!out.exists(), "{n}: output folder created");
        }
    }
    let o = vesicle(["check", "runs/sphere3d.json", "--set", "n=[4096,4096,4096]"]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains(" TB"), "{}", stderr(&o));
}

/// Hostile but valid: the largest `max_steps` is accepted (another rule stops the run), and
/// a scene path that is a folder is refused as input.
#[test]
fn huge_max_steps_runs_and_a_folder_as_scene_is_exit_2() {
    let tmp = TempDir::new().unwrap();
    let out = tmp.path().join("x");
    let o = vesicle([
        OsStr::new("run"),
        OsStr::new("runs/ellipse2d.json"),
        OsStr::new("--out"),
        out.as_os_str(),
        OsStr::new("--quiet"),
        OsStr::new("--set"),
        OsStr::new("max_steps=18446744073709551615"),
        OsStr::new("--set"),
        OsStr::new("t_end=0.05"),
        OsStr::new("--set"),
        OsStr::new("stop_residual=null"),
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    assert!(out.join("summary.json").exists());
    let o = vesicle([OsStr::new("check"), tmp.path().as_os_str()]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("(scene file)"), "{}", stderr(&o));
}

/// The rates study's `mirror` (the quarter box about x and y) holds only the circle's even
/// modes (cos nθ is odd about x = 0 for odd n): the study file's circle groups hold n = 3, so it
/// is refused with exit 2 naming `circle.mirror`, before anything runs or is written. (A study
/// file, not a scene: `tests/bad_scenes/` holds scenes for `check` and `run`.)
#[test]
fn a_mirrored_circle_in_the_rates_study_is_exit_2() {
    rates_study_is_refused(
        |v| v["circle"]["mirror"] = Value::Bool(true),
        "`circle.mirror`",
    );
}

/// The rates study takes unequal viscosities on the circle and the flat membrane only: the
/// quasi-sphere's box factor is known at equal viscosities, so a sphere group with a
/// `viscosity_ratio` other than 1 is refused with exit 2 naming it, before anything is written.
#[test]
fn a_sphere_with_unequal_viscosities_in_the_rates_study_is_exit_2() {
    rates_study_is_refused(
        |v| v["sphere"]["groups"][0]["viscosity_ratio"] = serde_json::json!([1, 5]),
        "sphere.groups.viscosity_ratio",
    );
}

/// The rates study shows its progress: a line on stderr as each case ends, with its ratio and
/// an ETA (`runs/studies/rates_free.json --quick`: the circle's n = 2 at two sizes in two boxes,
/// four cases).
#[test]
fn the_rates_study_reports_each_case_with_an_eta() {
    let tmp = TempDir::new().unwrap();
    let out = tmp.path().join("o");
    let file = runs_dir().join("studies").join("rates_free.json");
    let o = vesicle([
        OsStr::new("study"),
        OsStr::new("rates"),
        file.as_os_str(),
        OsStr::new("--quick"),
        OsStr::new("--out"),
        out.as_os_str(),
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let lines: Vec<String> = stderr(&o)
        .lines()
        .filter(|l| l.starts_with("rates ["))
        .map(String::from)
        .collect();
    assert_eq!(lines.len(), 4, "{lines:?}");
    assert!(
        lines[3].starts_with("rates [4/4] circle 2 drop"),
        "{lines:?}"
    );
    assert!(lines
        .iter()
        .all(|l| l.contains("ratio") && l.contains("ETA")));
}

/// A list of boxes is taken to L → ∞ through its (R/L)³, smallest box first: a list out of order
/// (or with a box twice) is refused with exit 2 naming `sphere.box`, before anything is written.
#[test]
fn boxes_out_of_order_in_the_rates_study_are_exit_2() {
    rates_study_is_refused(
        |v| v["sphere"]["box"] = serde_json::json!([10, 8]),
        "sphere.box",
    );
}

/// Each mobility of a list is a family of its own, smallest first: a list out of order, or a
/// mobility that is not positive, is refused with exit 2 naming `mobility`.
#[test]
fn mobilities_out_of_order_or_not_positive_in_the_rates_study_are_exit_2() {
    rates_study_is_refused(
        |v| v["mobility"] = serde_json::json!([0.16, 0.04]),
        "mobility",
    );
    rates_study_is_refused(|v| v["mobility"] = serde_json::json!([0.0]), "mobility");
}

/// `runs/studies/rates.json` changed by `edit` is refused with exit 2, a message holding `key`,
/// and no output folder.
fn rates_study_is_refused(edit: impl FnOnce(&mut Value), key: &str) {
    let tmp = TempDir::new().unwrap();
    let text = fs::read_to_string(runs_dir().join("studies").join("rates.json")).unwrap();
    let mut v: Value = serde_json::from_str(&text).unwrap();
    edit(&mut v);
    let bad = tmp.path().join("rates_refused.json");
    fs::write(&bad, v.to_string()).unwrap();
    let out = tmp.path().join("o");
    let o = vesicle([
        OsStr::new("study"),
        OsStr::new("rates"),
        bad.as_os_str(),
        OsStr::new("--out"),
        out.as_os_str(),
    ]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains(key), "{}", stderr(&o));
    assert!(!out.exists());
}

// ---------------------------------------------------------------------------------------------
// Blow-up
// ---------------------------------------------------------------------------------------------

/// FD, dim 3, h = ε = 1: bound 1/(12·14²) = 4.2517e-4; dt is 3× that.
const BLOWUP_SCENE: &str = r#"{
  "description": "FD at three times its stability bound: must blow up",
  "dim": 3, "n": [16, 16, 16], "method": "fd", "dt": 1.2755e-3,
  "allow_unstable": true, "max_steps": 3000,
  "initial": {"shape": "sphere", "radius": 4.0}
}"#;

/// Run the blow-up scene with `extra` arguments; returns (tempdir, out, output).
fn run_blowup(extra: &[&str]) -> (TempDir, PathBuf, Output) {
    let tmp = TempDir::new().unwrap();
    let scene = tmp.path().join("blowup.json");
    fs::write(&scene, BLOWUP_SCENE).unwrap();
    let out = tmp.path().join("x");
    let mut args = vec![
        OsStr::new("run"),
        scene.as_os_str(),
        OsStr::new("--out"),
        out.as_os_str(),
    ];
    args.extend(extra.iter().map(OsStr::new));
    let o = vesicle(&args);
    (tmp, out, o)
}

fn assert_blowup_outputs(out: &Path, o: &Output) -> usize {
    assert_eq!(code(o), 3, "{}", stderr(o));
    let err = stderr(o);
    assert!(err.contains("at step ") && err.contains("t = "), "{err}");
    assert!(err.contains("diverged") || err.contains("blew up"), "{err}");
    let step = blowup_step(&err);
    let summary = read_json(&out.join("summary.json"));
    let stopped = summary["stopped"].as_str().unwrap();
    assert!(stopped.starts_with("blew up"), "stopped = {stopped:?}");
    let (descr, _, shape, values) = read_npy(&out.join("phi_final.npy"));
    assert_eq!(descr, "<f8");
    assert_eq!(shape, vec![16, 16, 16]);
    assert!(
        values.iter().all(|v| v.is_finite()),
        "phi_final.npy is the last good state"
    );
    step
}

#[test]
fn blowup_exits_3_and_keeps_the_last_good_state() {
    let (_tmp, out, o) = run_blowup(&[]);
    let step = assert_blowup_outputs(&out, &o);
    assert!(step > 1 && step < 3000, "blew up at step {step}");
    let summary = read_json(&out.join("summary.json"));
    assert_eq!(summary["steps"].as_u64(), Some(step as u64 - 1));
    assert!(out.join("timeseries.csv").exists());
}

#[test]
fn blowup_summary_describes_the_last_good_state() {
    let (_tmp, out, o) = run_blowup(&["--set", "output.record_every=5"]);
    let step = assert_blowup_outputs(&out, &o);
    let summary = read_json(&out.join("summary.json"));
    // phi_final.npy holds the state after step − 1; the summary must describe that state
    assert_eq!(summary["steps"].as_u64(), Some(step as u64 - 1));
    assert_eq!(summary["final"]["step"].as_u64(), Some(step as u64 - 1));
}

#[test]
fn blowup_during_preparation_writes_the_outputs() {
    let (_tmp, out, o) = run_blowup(&["--set", "prepare_steps=100"]);
    assert_eq!(code(&o), 3, "{}", stderr(&o));
    assert!(stderr(&o).contains("preparation"), "{}", stderr(&o));
    assert!(
        out.join("summary.json").exists(),
        "exit 3 promises the last good state and the summary"
    );
    assert_blowup_outputs(&out, &o);
}

// ---------------------------------------------------------------------------------------------
// Help
// ---------------------------------------------------------------------------------------------

#[test]
fn help_texts_have_examples() {
    for args in [
        &["--help"][..],
        &["run", "--help"][..],
        &["check", "--help"][..],
        &["compare", "--help"][..],
    ] {
        let o = vesicle(args);
        assert_eq!(code(&o), 0, "{args:?}: {}", stderr(&o));
        let text = stdout(&o);
        let sub = if args.len() == 2 { args[0] } else { "run" };
        let example = format!("vesicle {sub} ");
        assert!(
            text.lines().any(|l| l.trim_start().starts_with(&example)),
            "{args:?}: no example line starting with {example:?}:\n{text}"
        );
    }
    let o = vesicle(["--help"]);
    for sub in ["run", "check", "compare"] {
        assert!(stdout(&o).contains(sub), "--help lists {sub}");
    }
}

// ---------------------------------------------------------------------------------------------
// The lattice pinning note
// ---------------------------------------------------------------------------------------------

/// `check` prints the pinning bound of the scene's h/ε (a note, not a refusal: exit 0). At
/// h = ε (`runs/prolate3d.json`) it is the h = ε row of the table measured by `study pinning`
/// (`vesicle::problem::pinning::TABLE`, read here, not copied) and recommends h = ε/2; at
/// h = ε/2 (the same scene on 96³ points) it gives the ε/2 row and recommends nothing; an FD
/// scene, whose own spatial error is far larger, gets no pinning note.
#[test]
fn check_prints_the_pinning_bound_of_the_scenes_spacing() {
    use vesicle::problem::pinning::{bound, TABLE};
    let at_eps = TABLE
        .iter()
        .find(|r| r.h_over_eps == 1.0)
        .expect("h = eps row");
    let o = vesicle([
        OsStr::new("check"),
        runs_dir().join("prolate3d.json").as_os_str(),
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let line = stderr(&o)
        .lines()
        .find(|l| l.contains("lattice pinning"))
        .unwrap_or_else(|| panic!("no pinning note in:\n{}", stderr(&o)))
        .to_string();
    assert!(line.contains(&format!("{:.1e}", at_eps.e)), "{line}");
    assert!(
        line.contains("recommended") && line.contains("study pinning"),
        "{line}"
    );
    let o = vesicle([
        OsStr::new("check"),
        runs_dir().join("prolate3d.json").as_os_str(),
        OsStr::new("--set"),
        OsStr::new("h=0.5"),
        OsStr::new("--set"),
        OsStr::new("n=[96,96,96]"),
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let err = stderr(&o);
    let line = err.lines().find(|l| l.contains("lattice pinning")).unwrap();
    assert!(
        line.contains(&format!("{:.1e}", bound(0.5).value())),
        "{line}"
    );
    assert!(!line.contains("recommended"), "{line}");
    let o = vesicle([
        OsStr::new("check"),
        runs_dir().join("prolate3d_fd.json").as_os_str(),
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    assert!(!stderr(&o).contains("lattice pinning"), "{}", stderr(&o));
}
