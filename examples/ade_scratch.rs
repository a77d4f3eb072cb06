use vesicle::analysis::axisym::*;
fn main() {
    let c = bc_curve(Branch::Pear, 0.94, (0.9, 1.35), &Options::with_nodes(121));
    println!("{} shapes, bif {:?}", c.shapes.len(), c.bifurcation.as_ref().map(|s| (s.da(), s.c0_eff)));
}
