//! The `vesicle` command line: thin; parsing and dispatch live in `vesicle::commands::cli`.

fn main() {
    std::process::exit(vesicle::commands::cli::main());
}
