//! The `vesicle` command line: thin; parsing and dispatch live in `vesicle::cli`.

fn main() {
    std::process::exit(vesicle::cli::main());
}
