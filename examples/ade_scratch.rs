use vesicle::analysis::axisym::*;
fn main() {
    let opts = Options::with_nodes(121);
    for v in [0.86, 0.96] {
        let c = bc_curve(Branch::Pear, v, (0.9, 1.35), &opts);
        println!(
            "pear v {v}: bif {:?} {} shapes",
            c.bifurcation.as_ref().map(|s| (s.da(), s.c0_eff)),
            c.shapes.len()
        );
    }
}
