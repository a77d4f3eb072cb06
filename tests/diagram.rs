//! Tests of `vesicle diagram`: a quick diagram (three points, small grids) end to end, the same
//! CSV files from one process and from a sweep of `--case` runs merged, a quick diagram at two
//! reduced spontaneous curvatures against the axisymmetric reference, the refusals (bad
//! diagram files, too thin a shape, ε|c0| too large, a missing case at merge, a case run
//! twice), and the files it writes.

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

/// Three points (one per branch), each at R0 = 8, 9 and 10 ε: a few seconds in all. The
/// stomatocyte's mouth is 0.248 R0 wide, 2ε at R0 = 8ε: below the default `min_width` of 5ε,
/// so the file lowers it.
const QUICK: &str = r#"{
  "description": "quick diagram for the tests",
  "branches": {"prolate": [0.8], "oblate": [0.8], "stomatocyte": [0.6]},
  "r0": [8, 9, 10],
  "thumbnails": [0.6],
  "min_width": 1.5
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
/// energies are within 8% of the reference (the phase-field error of e grows with ε/R0: under
/// 0.7% at ε/R0 = 0.025, docs/src/science/shape-diagram.md, a few percent at 0.1), which a wrong
/// branch or a broken measure would not be.
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
        // The pear only with ADE or the bilayer couple.
        (
            r#"{"branches": {"pear": [0.8]}, "r0": [8, 10, 12]}"#,
            "branches.pear",
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
        // ε|c0| = 2/16 at the coarsest resolution: above 0.1.
        (
            r#"{"c0": [0, 2], "branches": {"prolate": [0.8]}, "r0": [16, 20, 24]}"#,
            "c0",
        ),
        (
            r#"{"c0": [0, 1], "branches": {"prolate": [0.8]}, "r0": [10, 12, 14],
                "branches_by_c0": {"2": {"prolate": [0.8]}}}"#,
            "branches_by_c0.2",
        ),
        (
            r#"{"c0": [1], "r0": [10, 12, 14],
                "branches_by_c0": {"1": {"prolate": [0.8], "discocyte": [0.8]}}}"#,
            "branches_by_c0.1.discocyte",
        ),
        (
            r#"{"c0": [1], "branches": {"prolate": [0.8]}, "r0": [10, 12, 14], "c0_list": [1]}"#,
            "c0_list",
        ),
        // Too thin at the coarsest R0 = 24ε: the oblate's centre at v = 0.55 (0.11 R0 = 2.6ε)
        // and the stomatocyte's mouth at c0 R0 = −1, v = 0.75 (0.092 R0 = 2.2ε).
        (
            r#"{"branches": {"oblate": [0.55, 0.8]}, "r0": [24, 32, 40]}"#,
            "branches.oblate",
        ),
        (
            r#"{"c0": [-1], "branches_by_c0": {"-1": {"stomatocyte": [0.75]}},
                "r0": [24, 32, 40]}"#,
            "branches_by_c0.-1.stomatocyte",
        ),
        // branches_by_da: only in an ADE or bilayer-couple diagram, keyed by its slice values.
        (
            r#"{"branches": {"prolate": [0.8]}, "r0": [8, 10, 12],
                "branches_by_da": {"1.2": {"prolate": [0.75]}}}"#,
            "branches_by_da.1.2",
        ),
        (
            r#"{"bilayer_couple": {"da": [1.2]}, "r0": [14, 16, 18],
                "branches_by_da": {"1.3": {"prolate": [0.75]}}}"#,
            "branches_by_da.1.3",
        ),
        (
            r#"{"bilayer_couple": {"da": [1.2]}, "r0": [14, 16, 18],
                "branches_by_da": {"1.2": {"discocyte": [0.75]}}}"#,
            "branches_by_da.1.2.discocyte",
        ),
        // A slice with no branches (none in `branches`, none under its Δa).
        (
            r#"{"bilayer_couple": {"da": [1.2, 1.3]}, "r0": [14, 16, 18],
                "branches_by_da": {"1.2": {"prolate": [0.75]}}}"#,
            "branches",
        ),
        // No stomatocyte branch at c0 R0 = 1: its continuation is the oblate.
        (
            r#"{"c0": [1], "branches": {"stomatocyte": [0.6]}, "r0": [10, 12, 14]}"#,
            "branches.stomatocyte",
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

/// The committed diagram files are valid and list their cases.
#[test]
fn committed_diagram_files_list_their_cases() {
    for (file, cases) in [
        ("diagram.json", 84),
        ("diagram_c0.json", 165),
        ("diagram_fine.json", 81),
        ("diagram_c0_fine.json", 165),
        ("diagram_bc.json", 36),
    ] {
        let path = format!("{}/runs/{file}", env!("CARGO_MANIFEST_DIR"));
        let out = vesicle(&["diagram", &path, "--list"]);
        assert!(out.status.success(), "{file}: {}", text(&out));
        let listed = String::from_utf8_lossy(&out.stdout);
        assert!(
            listed.contains(&format!("{cases} cases")),
            "{file}: {listed}"
        );
    }
}

/// Two prolates at c0 R0 = 1 (and one at c0 = 0), each at R0 = 12, 14 and 16 ε: a few seconds.
const QUICK_C0: &str = r#"{
  "description": "quick diagram at spontaneous curvature for the tests",
  "c0": [0, 1],
  "branches": {"prolate": [0.75, 0.9]},
  "branches_by_c0": {"0": {"prolate": [0.75]}},
  "r0": [12, 14, 16]
}"#;

/// A diagram at c0 R0 = 1 against the axisymmetric reference at the same c0 R0 (the scene's
/// c0 = c0R0 / r0, e = ∮(2H − c0)² dA / 16π on both sides). Each c0 gets its folder
/// `c0_<c0>/` with the files of a one-c0 diagram; the top folder spans them.
///
/// Measured (residual 1e-6): raw errors at R0 = 16ε of +0.64% (v = 0.75) and +2.09% (v = 0.9),
/// extrapolated −0.06% and +0.73%. Asserted: raw |error| < 3% (the c0 = 0 diagram's raw error
/// at R0 = 24ε is up to 0.66% and falls as (ε/R0)^2.7, so about 2% is expected at 16ε),
/// extrapolated |error| < 1.5% and below the raw one. A wrong c0 would fail by far more: e
/// at v = 0.75 is 1.50 at c0 R0 = 0, 0.572 at 1 and 0.295 at 1.5 (a factor √2 in c0).
#[test]
fn quick_diagram_at_spontaneous_curvature_matches_the_reference() {
    let tmp = TempDir::new().unwrap();
    let file = tmp.path().join("quick_c0.json");
    fs::write(&file, QUICK_C0).unwrap();
    let file = file.to_string_lossy().into_owned();
    let dir = tmp.path().join("out");
    let out = diagram(&file, &dir, &["--jobs", "2"]);
    assert!(out.status.success(), "{}", text(&out));

    let csv = fs::read_to_string(dir.join("c0_1.00/diagram.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    assert_eq!(csv.lines().count(), 3, "two points at c0 R0 = 1: {csv}");
    for row in csv.lines().skip(1) {
        let f: Vec<&str> = row.split(',').collect();
        let raw: f64 = f[col("error_finest")].parse().unwrap();
        let ext: f64 = f[col("error")].parse().unwrap();
        assert!(raw.abs() < 0.03, "{row}: raw error {raw}");
        assert!(
            ext.abs() < 0.015 && ext.abs() < raw.abs(),
            "{row}: extrapolated {ext}"
        );
    }
    // The top folder: every point with its c0, the phase chart, the whole table.
    let all = fs::read_to_string(dir.join("diagram.csv")).unwrap();
    assert!(all.starts_with("c0,branch,v,e,"), "{all}");
    assert_eq!(
        all.lines().filter(|l| l.starts_with("1,prolate,")).count(),
        2
    );
    assert_eq!(
        all.lines().filter(|l| l.starts_with("0,prolate,")).count(),
        1
    );
    for picture in [
        "phase.png",
        "errors.png",
        "c0_0.00/diagram.png",
        "c0_1.00/errors.png",
    ] {
        assert!(
            fs::metadata(dir.join(picture)).unwrap().len() > 1000,
            "{picture}"
        );
    }
    let table = fs::read_to_string(dir.join("table.txt")).unwrap();
    assert!(
        table.contains("=== c0 R0 = 1 ===") && table.contains("against R0"),
        "{table}"
    );

    // A c0 ≠ 0 case keeps its c0 in its folder name; c0 = 0 cases keep their old names.
    let names: Vec<String> = fs::read_dir(dir.join("cases"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(
        names.contains(&"000_prolate_v0.7500_r12".to_string()),
        "{names:?}"
    );
    assert!(
        names.contains(&"003_prolate_v0.7500_c1.00_r12".to_string()),
        "{names:?}"
    );
    let scene =
        fs::read_to_string(dir.join("cases/003_prolate_v0.7500_c1.00_r12/scene.json")).unwrap();
    assert!(
        scene.contains(r#""c0": 0.08333333333333333"#),
        "c0 = 1/12: {scene}"
    );
}

/// Run the one-point diagram `spec` (as `name.json`) into a fresh folder and check its point's
/// raw error (at the finest R0) is below 3%; the folder and the directory that holds it.
fn one_point_diagram(name: &str, spec: &str) -> (TempDir, std::path::PathBuf) {
    let tmp = TempDir::new().unwrap();
    let file = tmp.path().join(format!("{name}.json"));
    fs::write(&file, spec).unwrap();
    let file = file.to_string_lossy().into_owned();
    let dir = tmp.path().join("out");
    let out = diagram(&file, &dir, &["--jobs", "2"]);
    assert!(out.status.success(), "{}", text(&out));
    let csv = fs::read_to_string(dir.join("diagram.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let row: Vec<&str> = csv.lines().nth(1).expect("one point").split(',').collect();
    let raw: f64 = row[col("error_finest")].parse().unwrap();
    assert!(raw.abs() < 0.03, "{csv}");
    (tmp, dir)
}

/// An ADE diagram: one slice, α = 1.4 and Δa0 = 1.3, the prolate at v = 0.85 at R0 = 12, 14
/// and 16ε (h = ε).
const QUICK_ADE: &str = r#"{
  "description": "quick ADE diagram for the tests",
  "ade": {"alpha": 1.4, "da0": [1.3]},
  "branches": {"prolate": [0.85]},
  "r0": [12, 14, 16]
}"#;

/// The ADE diagram end to end: each case's scene holds the `ade` block, the phase field's w
/// is compared with the sharp ADE reference's w at its own v (the ADE functional solved on the
/// axisymmetric contour), and its Δa with the reference's Δa. At R0 = 16ε and h = ε the raw
/// errors are the phase field's ε/R0 and lattice errors (measured −1.22% in w, +1.60% in Δa),
/// so both must be below 3%. (One point at h = ε fits no orders in ε/R0: its extrapolation is
/// not checked here.) Without the term the phase field would miss by far more: with α → 0
/// this prolate relaxes to w = e = 1.268 and Δa = 1.050, against the reference's w ≈ 1.50 and
/// Δa ≈ 1.095 (15% and 4% off).
#[test]
fn quick_ade_diagram_matches_the_ade_reference() {
    let (_tmp, dir) = one_point_diagram("quick_ade", QUICK_ADE);
    let table = fs::read_to_string(dir.join("table.txt")).unwrap();
    let da_row = table
        .lines()
        .skip_while(|l| !l.contains("Δa_ref"))
        .nth(1)
        .unwrap_or_else(|| panic!("a Δa table: {table}"));
    let fields: Vec<&str> = da_row.split_whitespace().collect();
    let (da, da_ref): (f64, f64) = (fields[3].parse().unwrap(), fields[4].parse().unwrap());
    assert!((da / da_ref - 1.0).abs() < 0.03, "{da_row}");
    let names: Vec<String> = fs::read_dir(dir.join("cases"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    let case = names
        .iter()
        .find(|n| n.ends_with("_a1.30_r16"))
        .unwrap_or_else(|| panic!("{names:?}"));
    let scene = fs::read_to_string(dir.join("cases").join(case).join("scene.json")).unwrap();
    assert!(
        scene.contains(r#""ade""#) && scene.contains(r#""da0": 1.3"#),
        "{scene}"
    );
}

/// A bilayer-couple diagram: one slice, Δa = 1.2, the prolate at v = 0.75 at R0 = 14, 16 and
/// 18ε (h = ε; at R0 = 12ε the shape leaves the branch).
const QUICK_BC: &str = r#"{
  "description": "quick bilayer-couple diagram for the tests",
  "bilayer_couple": {"da": [1.2]},
  "branches": {"prolate": [0.75]},
  "r0": [14, 16, 18]
}"#;

/// The bilayer-couple diagram end to end: each case runs L-BFGS (`"relaxational"`) with the
/// couple as its second constraint, which holds Δa = 1.2 (the case's Δa within 1e-10; the
/// retraction holds M to 1e-12 of M0, so a Δa off by more means the constraint was lost or the
/// case ran a dynamics that does not hold it), and its e is compared with the sharp BC
/// shape's at its own v: raw error below 3% at R0 = 18ε, h = ε (measured −1.82%, as the
/// conserved flow gave: both reach the same stationary state). The φ = 0 surface's own Δa,
/// which the couple does not hold, is within 3% of 1.2 too (measured 1.18847, −0.96%: the
/// profile's and the lattice's error at h = ε); a Δa measured with a wrong factor or R0 would
/// be far off.
#[test]
fn quick_bilayer_couple_diagram_holds_da_against_the_bc_reference() {
    let (_tmp, dir) = one_point_diagram("quick_bc", QUICK_BC);
    let csv = fs::read_to_string(dir.join("diagram.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let row: Vec<&str> = csv.lines().nth(1).unwrap().split(',').collect();
    let col = |name: &str| {
        let i = header.iter().position(|h| *h == name).unwrap();
        row[i].parse::<f64>().unwrap()
    };
    assert_eq!(col("da_reference_finest"), 1.2, "{csv}");
    assert!((col("da_surface_finest") / 1.2 - 1.0).abs() < 0.03, "{csv}");
    for entry in fs::read_dir(dir.join("cases")).unwrap() {
        let case = entry.unwrap().path();
        let result: serde_json::Value =
            serde_json::from_str(&fs::read_to_string(case.join("result.json")).unwrap()).unwrap();
        let da = result["da"].as_f64().unwrap();
        assert!((da - 1.2).abs() < 1e-10, "{}: Δa = {da}", case.display());
        let scene = fs::read_to_string(case.join("scene.json")).unwrap();
        assert!(
            scene.contains(r#""bilayer_couple""#) && scene.contains(r#""relaxational""#),
            "{scene}"
        );
    }
}

/// A bilayer-couple pear: Δa = 1.25, v0 = 0.78 (a neck of 0.21 R0), at R0 = 14 and 16ε.
const QUICK_BC_PEAR: &str = r#"{
  "description": "quick bilayer-couple pear for the tests",
  "bilayer_couple": {"da": [1.25]},
  "branches": {"pear": [0.78]},
  "r0": [14, 16]
}"#;

/// The pear in a bilayer-couple diagram: its case runs on the box mirrored in x and y only
/// (the pear is not up–down symmetric), holds Δa, stays a pear (volume skewness along the
/// axis −0.102; a shape that relaxed to the up–down symmetric prolate reads 0) and relaxes to
/// e within 4.5% of the sharp BC pear's at the case's own v (measured −3.55% at R0 = 16ε,
/// h = ε; −4.82% at 14ε and −2.63% at 18ε: the error falls with ε/R0).
#[test]
fn a_bilayer_couple_pear_case_relaxes_to_the_sharp_pear() {
    let tmp = TempDir::new().unwrap();
    let file = tmp.path().join("pear.json");
    fs::write(&file, QUICK_BC_PEAR).unwrap();
    let dir = tmp.path().join("out");
    let out = diagram(file.to_str().unwrap(), &dir, &["--case", "1"]);
    assert!(out.status.success(), "{}", text(&out));
    let case = fs::read_dir(dir.join("cases"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.join("result.json").exists())
        .expect("the case's folder");
    let result: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(case.join("result.json")).unwrap()).unwrap();
    assert_eq!(result["stopped"], "stationary", "{result}");
    assert!(
        (result["da"].as_f64().unwrap() - 1.25).abs() < 1e-10,
        "{result}"
    );
    let scene: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(case.join("scene.json")).unwrap()).unwrap();
    assert_eq!(scene["symmetry"], serde_json::json!(["x", "y"]));
    let skewness = result["skewness"].as_f64().unwrap();
    assert!(skewness < -0.05, "skewness {skewness}");
    let v = result["v"].as_f64().unwrap();
    let sharp = vesicle::analysis::axisym::bc_solution(
        vesicle::analysis::axisym::Branch::Pear,
        v,
        1.25,
        &Default::default(),
    )
    .unwrap();
    let error = result["e"].as_f64().unwrap() / sharp.e - 1.0;
    assert!(
        error.abs() < 0.045,
        "e {} against the sharp pear's {} at v = {v}",
        result["e"],
        sharp.e
    );
}
