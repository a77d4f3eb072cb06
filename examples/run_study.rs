//! Run a study by name, as `vesicle study NAME FILE --quick --out DIR` does, and use its tables
//! from the library: typed columns from the same rows as the CSV files it writes. The default,
//! the quick convergence study, takes about a minute on two cores.
//!
//! ```sh
//! cargo run --release --example run_study [NAME] [STUDY.json] [OUT]
//! ```

use std::path::PathBuf;
use vesicle::{StudyArgs, StudyValues};

fn main() -> vesicle::Result<()> {
    let mut args = std::env::args().skip(1);
    let name = args.next().unwrap_or_else(|| "convergence".to_string());
    let file = args.next().map_or_else(
        || PathBuf::from("runs/studies/convergence.json"),
        PathBuf::from,
    );
    let out = args
        .next()
        .map_or_else(|| std::env::temp_dir().join("vesicle-study"), PathBuf::from);
    let study = StudyArgs {
        file: &file,
        quick: true,
        set: &[],
        out: &out,
        force: true,
    };
    // Writes the folder `out` (the printed table, CSV files, charts) and returns the tables.
    for table in vesicle::run_study(&name, &study)? {
        println!("{}.csv:", table.name);
        for (header, values) in &table.columns {
            let summary = match values {
                StudyValues::Float(x) => {
                    let finite: Vec<f64> = x.iter().copied().filter(|v| v.is_finite()).collect();
                    let lo = finite.iter().copied().fold(f64::INFINITY, f64::min);
                    let hi = finite.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                    format!("{} numbers in [{lo:.3e}, {hi:.3e}]", x.len())
                }
                StudyValues::Int(n) => {
                    format!("{} counts, total {}", n.len(), n.iter().sum::<i64>())
                }
                StudyValues::Text(t) => {
                    let mut distinct = t.clone();
                    distinct.sort();
                    distinct.dedup();
                    format!("{} names: {}", t.len(), distinct.join(" | "))
                }
            };
            println!("  {header:<16} {summary}");
        }
    }
    println!("written to {}", out.display());
    Ok(())
}
