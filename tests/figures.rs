//! The manual's figures (`docs/src/figures/`) are copies of pictures under `runs/results/`,
//! listed in `runs/regenerate_charts.sh`'s `FIGURES` as `name.png=path/under/results.png`.
//! A result regenerated without its copy leaves the manual showing an older run (the budding
//! charts did, from 2026-12-05 to 12-06): every listed copy must equal its source byte for byte,
//! and every figure the manual holds must be listed.

use std::collections::BTreeSet;
use std::fs;
use std::path::PathBuf;

fn crate_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The `FIGURES` entries of the script: (the manual's name, the source under runs/results/).
fn listed_figures() -> Vec<(String, String)> {
    let script = fs::read_to_string(crate_dir().join("runs/regenerate_charts.sh")).expect("script");
    let start = script.find("\nFIGURES=(").expect("a FIGURES list");
    let body = &script[start..];
    let end = body.find("\n)").expect("the list's end");
    body[..end]
        .lines()
        .skip(2)
        .filter_map(|l| l.trim().split_once('='))
        .map(|(name, source)| (name.to_string(), source.to_string()))
        .collect()
}

#[test]
fn every_figure_of_the_manual_is_its_results_picture() {
    let listed = listed_figures();
    assert!(listed.len() > 20, "read {} entries", listed.len());
    let figures = crate_dir().join("docs/src/figures");
    for (name, source) in &listed {
        let copy = fs::read(figures.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        let original = fs::read(crate_dir().join("runs/results").join(source))
            .unwrap_or_else(|e| panic!("{source}: {e}"));
        assert!(
            copy == original,
            "docs/src/figures/{name} differs from runs/results/{source}: copy it again \
             (the end of runs/regenerate_charts.sh does)"
        );
    }
    let names: BTreeSet<&str> = listed.iter().map(|(n, _)| n.as_str()).collect();
    for entry in fs::read_dir(&figures).expect("figures") {
        let name = entry
            .expect("entry")
            .file_name()
            .into_string()
            .expect("utf-8");
        assert!(
            names.contains(name.as_str()),
            "docs/src/figures/{name} is in no FIGURES entry of runs/regenerate_charts.sh"
        );
    }
}
