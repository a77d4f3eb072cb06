use std::time::Instant;
use vesicle::analysis::axisym::*;
fn main() {
    let opts = Options::with_nodes(121);
    for v in [0.9, 0.7] {
        let t = Instant::now();
        for b in Branch::WITH_PEAR {
            let c = bc_curve(b, v, (0.5, 1.6), &opts);
            print!("v {v} {} {} shapes bif {:?} ({:.2}s):", b.name(), c.shapes.len(), c.bifurcation, t.elapsed().as_secs_f64());
            for s in c.shapes.iter().step_by((c.shapes.len() / 8).max(1)) {
                print!(" [{:.4} {:.4} {:.2}]", s.da(), s.e, s.c0_eff);
            }
            if let Some(s) = c.shapes.last() { print!(" last [{:.4} {:.4} {:.2} neck {:?}]", s.da(), s.e, s.c0_eff, s.neck()); }
            println!();
        }
    }
    let t = Instant::now();
    match ade_solution(Branch::Prolate, 0.9, 1.4, 1.1, &opts) {
        Ok(s) => {
            println!("ade: da {} w {} e {} ceff {} ({:.2}s)", s.da(), s.w, s.e, s.c0_eff, t.elapsed().as_secs_f64());
            let sc = solve(Branch::Prolate, 0.9, &opts.with_c0(s.c0_eff)).unwrap();
            println!("sc: da {} e0 {}", sc.da(), sc.e + s.c0_eff * sc.da() - s.c0_eff * s.c0_eff / 4.0);
        }
        Err(e) => println!("{e}"),
    }
}
