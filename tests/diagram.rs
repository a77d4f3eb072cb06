//! Tests of `vesicle diagram`: a quick diagram (three points, small grids) end to end, the same
//! CSV files from one process and from a sweep of `--case` runs merged, the refusals (bad
//! diagram files, a missing case at merge, a case run twice), and the file it writes.

use std::fs;
use std::path::Path;
use std::process::{Command, Output};
use tempfile::TempDir;

fn vesicle(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vesicle"))
        .args(args)
        .output()
        .expect("run vesicle")
}

/// `vesicle diagram FILE --out OUT EXTRA…`.
fn diagram(file: &str, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["diagram", file, "--out", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    vesicle(&args)
}

fn text(out: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// Three points (one per branch), each at R0 = 8, 9 and 10 ε: a few seconds in all.
const QUICK: &str = r#"{
  "description": "quick diagram for the tests",
  "branches": {"prolate": [0.8], "oblate": [0.8], "stomatocyte": [0.6]},
  "r0": [8, 9, 10],
  "thumbnails": [0.6]
}"#;

fn write_quick(dir: &Path) -> String {
    let path = dir.join("quick.json");
    fs::write(&path, QUICK).unwrap();
    path.to_string_lossy().into_owned()
}

/// `cases.csv` without its last column (the wall time, which differs from run to run).
fn cases_without_wall(dir: &Path) -> String {
    fs::read_to_string(dir.join("cases.csv"))
        .unwrap()
        .lines()
        .map(|l| l.rsplit_once(',').unwrap().0.to_string() + "\n")
        .collect()
}

/// One process, and nine `--case` runs merged, write the same diagram: every case runs on one
/// thread whatever the sweep, so the numbers agree to the last digit. The CSV has the
/// columns `branch,v,e` first; every relaxation is stationary; and at R0 = 10ε the raw
/// energies are within 8% of the reference (the phase-field error at ε/R0 = 0.1 is a few
/// percent, DESIGN.md §7), which a wrong branch or a broken measure would not be.
#[test]
fn quick_diagram_single_process_and_merged_sweep_agree() {
    let tmp = TempDir::new().unwrap();
    let file = write_quick(tmp.path());
    let single = tmp.path().join("single");
    let out = diagram(&file, &single, &[]);
    assert!(out.status.success(), "{}", text(&out));
    let table = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(table.contains("transition prolate/oblate"), "{table}");

    let listed = vesicle(&["diagram", &file, "--list"]);
    assert!(listed.status.success());
    assert!(String::from_utf8_lossy(&listed.stdout).contains("9 cases"));

    let swept = tmp.path().join("swept");
    for k in 0..9 {
        let out = diagram(&file, &swept, &["--case", &k.to_string()]);
        assert!(out.status.success(), "case {k}: {}", text(&out));
    }
    let merged = diagram(&file, &swept, &["--merge"]);
    assert!(merged.status.success(), "{}", text(&merged));

    for name in ["diagram.csv", "transitions.csv", "reference.csv"] {
        let a = fs::read_to_string(single.join(name)).unwrap();
        let b = fs::read_to_string(swept.join(name)).unwrap();
        assert_eq!(
            a, b,
            "{name} differs between the single run and the merged sweep"
        );
    }
    assert_eq!(cases_without_wall(&single), cases_without_wall(&swept));

    let csv = fs::read_to_string(single.join("diagram.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    assert_eq!(&header[..3], &["branch", "v", "e"]);
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    assert_eq!(csv.lines().count(), 4, "three points");
    for row in csv.lines().skip(1) {
        let f: Vec<&str> = row.split(',').collect();
        let err: f64 = f[col("error_finest")].parse().unwrap();
        assert!(err.abs() < 0.08, "{row}: raw error {err}");
    }
    let cases = fs::read_to_string(single.join("cases.csv")).unwrap();
    assert_eq!(cases.lines().count(), 10);
    assert!(
        cases.lines().skip(1).all(|l| l.contains(",stationary,")),
        "{cases}"
    );
    for picture in ["diagram.png", "thumbnails.png"] {
        assert!(
            fs::metadata(single.join(picture)).unwrap().len() > 1000,
            "{picture}"
        );
    }
    // Each case folder holds a scene `vesicle run` accepts as it is.
    let case0 = fs::read_dir(single.join("cases"))
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    let check = vesicle(&["check", case0.join("scene.json").to_str().unwrap()]);
    assert!(check.status.success(), "{}", text(&check));

    // Merging again, or redoing a case, needs --force; nothing is overwritten silently.
    let again = diagram(&file, &swept, &["--merge"]);
    assert_eq!(again.status.code(), Some(2), "{}", text(&again));
    assert!(text(&again).contains("--merge"));
    let redo = diagram(&file, &swept, &["--case", "3"]);
    assert_eq!(redo.status.code(), Some(2));
    assert!(text(&redo).contains("--case"));
    let rerun = diagram(&file, &single, &[]);
    assert_eq!(rerun.status.code(), Some(2));
    assert!(text(&rerun).contains("--out"));
}

/// A merge with cases missing names them and writes nothing; a case number out of range is
/// refused.
#[test]
fn merge_needs_every_case() {
    let tmp = TempDir::new().unwrap();
    let file = write_quick(tmp.path());
    let dir = tmp.path().join("partial");
    let out = diagram(&file, &dir, &["--case", "0"]);
    assert!(out.status.success(), "{}", text(&out));
    let merged = diagram(&file, &dir, &["--merge"]);
    assert_eq!(merged.status.code(), Some(2));
    let msg = text(&merged);
    assert!(
        msg.contains("8 of 9 cases have no result") && msg.contains("1, 2"),
        "{msg}"
    );
    assert!(!dir.join("diagram.csv").exists());
    let out = diagram(&file, &dir, &["--case", "9"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out).contains("--case"));
}

/// Bad diagram files are refused with exit 2 and a message naming the key, before anything
/// runs or is written.
#[test]
fn bad_diagram_files_name_the_key() {
    let tmp = TempDir::new().unwrap();
    let cases = [
        (
            r#"{"branches": {"prolate": [0.8]}, "r0": [8, 10, 12], "speed": 2}"#,
            "speed",
        ),
        (r#"{"branches": {"prolate": [0.8]}, "r0": [10]}"#, "r0"),
        (
            r#"{"branches": {"discocyte": [0.8]}, "r0": [8, 10, 12]}"#,
            "branches.discocyte",
        ),
        (
            r#"{"branches": {"stomatocyte": [0.7]}, "r0": [8, 10, 12]}"#,
            "branches.stomatocyte",
        ),
        (
            r#"{"branches": {"prolate": [0.8]}, "r0": [8, 10, 2]}"#,
            "r0",
        ),
        (
            r#"{"branches": {"prolate": [0.8]}, "r0": [8, 10, 12], "stop_residual": 0}"#,
            "stop_residual",
        ),
        (
            r#"{"branches": {"prolate": "0.8"}, "r0": [8, 10, 12]}"#,
            "branches.prolate",
        ),
        (
            r#"{"branches": {"prolate": [0.8]}, "r0": [8, 10, 12]"#,
            "(file)",
        ),
    ];
    for (k, (json, field)) in cases.iter().enumerate() {
        let path = tmp.path().join(format!("bad{k}.json"));
        fs::write(&path, json).unwrap();
        let out_dir = tmp.path().join(format!("out{k}"));
        let out = vesicle(&[
            "diagram",
            path.to_str().unwrap(),
            "--out",
            out_dir.to_str().unwrap(),
        ]);
        assert_eq!(out.status.code(), Some(2), "{json}: {}", text(&out));
        assert!(
            text(&out).contains(&format!("`{field}`")),
            "{json}: {}",
            text(&out)
        );
        assert!(!out_dir.exists(), "{json}: wrote {}", out_dir.display());
    }
}

/// The committed diagram file is valid and lists its cases.
#[test]
fn committed_diagram_file_lists_its_cases() {
    let file = concat!(env!("CARGO_MANIFEST_DIR"), "/runs/diagram.json");
    let out = vesicle(&["diagram", file, "--list"]);
    assert!(out.status.success(), "{}", text(&out));
    assert!(String::from_utf8_lossy(&out.stdout).contains("84 cases"));
}
