//! The ADE and bilayer-couple (BC) models of the axisymmetric reference
//! (`vesicle::analysis::axisym::{ade, bc, limits, ade_phase}`): the sphere's Δa, the closed
//! loop ADE → SC at c̄0,eff, the BC constraint and the BC slope ∂e/∂Δa = c̄0,eff, the limit
//! lines' end points, convergence in the number of modes, and a two-volume diagram end to end.

use std::f64::consts::{PI, SQRT_2};
use vesicle::analysis::axisym::{
    self, ade_phase, ade_solution, bc_solution, inner_spheres_da, l_pear, l_pear_at, l_sto_at,
    limit_line, outer_buds_da, Branch, Limit, LimitShape, Model, Options,
};

/// 121 nodes (K = 40): the ADE/BC checks below are identities between solves of one
/// discretisation, so a coarse one keeps each test to a fraction of a second.
fn opts() -> Options {
    Options::with_nodes(121)
}

/// The bending energy at c̄0 = 0 of a shape with energy `e` at `c0` and area difference `da`:
/// `e_0 = e + c̄0 Δa − c̄0²/4` (`e = e_0 − c̄0 Δa + c̄0²/4` at fixed area).
fn e0(e: f64, c0: f64, da: f64) -> f64 {
    e + c0 * da - 0.25 * c0 * c0
}

/// Δa = ∮2H dA/(8πR0) of the sphere is 1 in every model: the sphere is the ADE shape at v = 1
/// whatever Δa0 (its Δa cannot change), with w = (1 − c̄0/2)² + πα(1 − Δa0)². Clenshaw–Curtis
/// is exact on the sphere, so round-off (1e-12) remains.
#[test]
fn sphere_has_unit_area_difference() {
    let s = axisym::solve(Branch::Prolate, 1.0, &opts()).unwrap();
    assert!((s.da() - 1.0).abs() < 1e-12, "Δa = {}", s.da());
    let (alpha, da0) = (1.4, 1.3);
    let o = opts().with_model(Model::Ade { alpha, da0 });
    let s = axisym::solve(Branch::Prolate, 1.0, &o).unwrap();
    let want = 1.0 + PI * alpha * (1.0 - da0).powi(2);
    assert!((s.da() - 1.0).abs() < 1e-12);
    assert!((s.w - want).abs() < 1e-12, "w = {} vs {want}", s.w);
    assert!((s.c0_eff - 2.0 * PI * alpha * (da0 - 1.0)).abs() < 1e-12);
}

/// The closed loop: an ADE shape (α = 1.4, Δa0 given) re-solved as an SC shape at its
/// c̄0,eff = c̄0 + 2πα(Δa0 − Δa), from the sphere by continuation in v (an independent path),
/// gives the same bending energy and Δa. Both are Newton solutions to 1e-11 of one
/// discretisation, so they agree to about 1e-10; the issue asks for 1e-8.
#[test]
fn ade_shape_is_the_sc_shape_at_c0_eff() {
    for (b, v, da0) in [
        (Branch::Prolate, 0.85, 1.3),
        (Branch::Prolate, 0.75, 1.45),
        (Branch::Oblate, 0.8, 1.0),
    ] {
        let alpha = 1.4;
        let a = ade_solution(b, v, alpha, da0, &opts()).unwrap();
        assert_eq!(a.model, Model::Ade { alpha, da0 });
        let c_eff = 2.0 * PI * alpha * (da0 - a.da());
        assert!((a.c0_eff - c_eff).abs() < 1e-12);
        assert!((a.w - a.e - PI * alpha * (a.da() - da0).powi(2)).abs() < 1e-12);
        let sc = axisym::solve(b, v, &opts().with_c0(a.c0_eff)).unwrap();
        let de = (e0(sc.e, a.c0_eff, sc.da()) - a.e).abs();
        let dda = (sc.da() - a.da()).abs();
        println!("{b:?} v = {v} Δa0 = {da0}: Δa = {:.8}, c0_eff = {:.6}, |Δe| = {de:.1e}, |ΔΔa| = {dda:.1e}", a.da(), a.c0_eff);
        assert!(de < 1e-8 && dda < 1e-8, "{b:?}: {de:e} {dda:e}");
    }
}

/// The bilayer couple holds Δa to round-off (the constraint of the Newton system, solved to
/// 1e-11), its shape is the SC shape at its c̄0,eff = −λ_Δa (same e and v), and along the BC
/// branch ∂e/∂Δa = c̄0,eff (the envelope theorem; central difference with δ = 1e-4 on a branch
/// whose c̄0,eff changes by O(1) per 0.01 of Δa: agreement to 1e-3 relative).
#[test]
fn bilayer_couple_holds_da_and_its_multiplier_is_the_slope() {
    let (v, da) = (0.75, 1.2);
    let s = bc_solution(Branch::Prolate, v, da, &opts()).unwrap();
    assert!((s.da() - da).abs() < 1e-11, "Δa = {}", s.da());
    assert!((s.v - v).abs() < 1e-11);
    let sc = axisym::solve(Branch::Prolate, v, &opts().with_c0(s.c0_eff)).unwrap();
    assert!((e0(sc.e, s.c0_eff, sc.da()) - s.e).abs() < 1e-8);
    assert!((sc.da() - da).abs() < 1e-8);
    let d = 1e-4;
    let ep = bc_solution(Branch::Prolate, v, da + d, &opts()).unwrap().e;
    let em = bc_solution(Branch::Prolate, v, da - d, &opts()).unwrap().e;
    let slope = (ep - em) / (2.0 * d);
    println!(
        "BC prolate v = {v}, Δa = {da}: de/dΔa = {slope:.6}, c0_eff = {:.6}",
        s.c0_eff
    );
    assert!((slope - s.c0_eff).abs() < 1e-3 * s.c0_eff.abs().max(1.0));
}

/// The limit lines' end points from R1² + R2² = 1: L_pear from two equal spheres
/// (R1 = R2 = 1/√2: v = 1/√2, Δa = √2, neck condition 1/R1 + 1/R2 = 2√2, the c̄0 at which
/// the SC budding limit `l_pear` begins) to one sphere (v = Δa = 1); L_sto from v = Δa = 0
/// to (1, 1); e = 2 at c̄0 = 0 on both. Closed forms: round-off only.
#[test]
fn limit_lines_end_points() {
    let h = 1.0 / SQRT_2;
    let p = LimitShape::new(Limit::Pear, h).unwrap();
    assert!((p.v - h).abs() < 1e-14 && (p.da - SQRT_2).abs() < 1e-14);
    assert!((p.c0_neck - 2.0 * SQRT_2).abs() < 1e-14);
    assert!((l_pear(2.0 * SQRT_2).unwrap() - p.v).abs() < 1e-12);
    let s = LimitShape::new(Limit::Stomatocyte, h).unwrap();
    assert!(s.v.abs() < 1e-14 && s.da.abs() < 1e-14);
    for kind in [Limit::Pear, Limit::Stomatocyte] {
        let one = LimitShape::new(kind, 0.0).unwrap();
        assert!((one.v - 1.0).abs() < 1e-15 && (one.da - 1.0).abs() < 1e-15);
        for l in limit_line(kind, 20) {
            assert!((l.e(0.0) - 2.0).abs() < 1e-14);
            assert!((l.r1 * l.r1 + l.r2 * l.r2 - 1.0).abs() < 1e-14);
        }
    }
    // Along L_pear the SC budding limit at the neck's c̄0 is the same shape.
    for l in limit_line(Limit::Pear, 10) {
        // (the equal-sphere end's neck c̄0 is 2√2 up to round-off, which `l_pear` rejects below)
        let c = l.c0_neck.max(2.0 * SQRT_2);
        assert!((l_pear(c).unwrap() - l.v).abs() < 1e-12);
    }
    // The inverses in v.
    let q = l_pear_at(0.9).unwrap();
    assert!((q.v - 0.9).abs() < 1e-12 && q.da > 1.0 && q.da < SQRT_2);
    let r = l_sto_at(0.5).unwrap();
    assert!((r.v - 0.5).abs() < 1e-12 && r.da > 0.0 && r.da < 1.0);
    // A sphere with one sphere inside is L_sto; with two (R1² + 2R2² = 1) Δa is smaller.
    for v in [0.3, 0.6, 0.9, 0.99] {
        let one = inner_spheres_da(v, 1).unwrap();
        let two = inner_spheres_da(v, 2).unwrap();
        assert!((one - l_sto_at(v).unwrap().da).abs() < 1e-12, "v = {v}");
        assert!(two < one, "v = {v}: {two} against {one}");
    }
    assert!(inner_spheres_da(1.0, 1).is_none());
    assert!(l_pear_at(0.7).is_none());
    // A sphere with one bud outside is L_pear; with two (R1² + 2R2² = 1, v = R1³ + 2R2³) Δa is
    // larger: at v = 0.9, R2 = 0.19828 and Δa = 1.35643 (solved by hand), down to three equal
    // spheres at v = 1/√3.
    for v in [0.75, 0.9, 0.99] {
        let one = outer_buds_da(v, 1).unwrap();
        let two = outer_buds_da(v, 2).unwrap();
        assert!((one - l_pear_at(v).unwrap().da).abs() < 1e-12, "v = {v}");
        assert!(two > one, "v = {v}: {two} against {one}");
    }
    assert!((outer_buds_da(0.9, 2).unwrap() - 1.35643).abs() < 1e-5);
    assert!(outer_buds_da(0.57, 2).is_none() && outer_buds_da(0.58, 2).is_some());
}

/// Convergence in modes: the ADE shape at v = 0.75, Δa0 = 1.45 (a prolate with a waist,
/// c̄0,eff ≈ 2.35) with 31, 46, 61 and 121 nodes (K = 10, 15, 20, 40) against 241 (K = 80):
/// the error in w falls with K (spectrally: each step at least tenfold) and is at round-off
/// (below 1e-10) by K = 40.
#[test]
fn ade_converges_in_modes() {
    let at =
        |n: usize| ade_solution(Branch::Prolate, 0.75, 1.4, 1.45, &Options::with_nodes(n)).unwrap();
    let reference = at(241);
    let errs: Vec<f64> = [31, 46, 61, 121]
        .iter()
        .map(|&n| (at(n).w - reference.w).abs())
        .collect();
    println!(
        "w(K = 80) = {:.12}, |Δw| at K = 10, 15, 20, 40: {errs:?}",
        reference.w
    );
    for p in errs.windows(2) {
        assert!(p[1] < 0.1 * p[0] || p[1] < 1e-12, "{errs:?}");
    }
    assert!(errs[3] < 1e-10);
}

/// A two-volume ADE and BC diagram end to end (81 nodes): at v = 0.8 and 0.9 the lowest
/// branch changes from oblate to prolate at one energy crossing between Δa0 = 0.9 and 1.1 (as
/// v → 1 every shape has Δa → 1 and c̄0,eff → 0 at the crossing, so Δa0 → 1 there); in the
/// BC diagram an invaginated or flattened shape (oblate or stomatocyte) is lowest at
/// Δa = 0.95 and an elongated one (prolate or pear) at 1.15.
#[test]
fn small_diagrams_end_to_end() {
    let o = Options::with_nodes(81);
    let da0s: Vec<f64> = (0..=10).map(|i| 0.9 + 0.02 * i as f64).collect();
    for v in [0.8, 0.9] {
        let s = ade_phase::v_slice(v, (0.5, 2.0), &o);
        let l = ade_phase::ade_lowest(&s, 1.4, &da0s);
        assert_eq!(l.points.last().unwrap().1, Branch::Prolate, "v = {v}");
        let ch: Vec<_> = l
            .changes
            .iter()
            .filter(|c| c.crossing && c.below == Branch::Oblate && c.above == Branch::Prolate)
            .collect();
        assert_eq!(ch.len(), 1, "v = {v}: {:?}", l.changes);
        println!("v = {v}: oblate/prolate at Δa0 = {:.4}", ch[0].x);
        assert!(ch[0].x > 0.9 && ch[0].x < 1.1);
        let b = ade_phase::bc_lowest(&s, &[0.95, 1.15]);
        assert!(matches!(
            b.points[0].1,
            Branch::Oblate | Branch::Stomatocyte
        ));
        assert!(matches!(b.points[1].1, Branch::Prolate | Branch::Pear));
    }
}

/// `vesicle axisym --ade` refuses α ≤ 0 with exit 2, naming the flag, and writes nothing.
#[test]
fn cli_rejects_bad_alpha() {
    let dir = std::env::temp_dir().join(format!("axisym_ade_bad_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_vesicle"))
        .args(["axisym", "--ade=-1", "--da0=1,1.2", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--ade"));
    assert!(!dir.exists());
}

/// `vesicle axisym --bc --da LIST` end to end on two volumes (61 nodes): the files, the
/// L_pear row at v = 0.9 with the two-sphere Δa = R1 + R2 of `l_pear_at`, and the prolate's
/// first loss of up–down stability there at the pear's bifurcation (two computations: the
/// pear's walk to its first zero of `μ`, and `μ` along the prolate's own curve).
#[test]
fn cli_writes_the_bc_diagram() {
    let dir = std::env::temp_dir().join(format!("axisym_bc_cli_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_vesicle"))
        .args([
            "axisym",
            "--bc",
            "--da=0.9,1.0,1.1,1.2",
            "--v-min",
            "0.85",
            "--v-max",
            "0.9",
            "--dv",
            "0.05",
            "--nodes",
            "61",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for f in [
        "branches_v0.850.csv",
        "branches_v0.900.csv",
        "lowest.csv",
        "summary.csv",
        "limits.csv",
        "phase.png",
        "phase.svg",
    ] {
        assert!(dir.join(f).exists(), "{f}");
    }
    let summary = std::fs::read_to_string(dir.join("summary.csv")).unwrap();
    let want = format!("0.900000,L_pear,{:.6},", l_pear_at(0.9).unwrap().da);
    assert!(summary.lines().any(|l| l.starts_with(&want)), "{summary}");
    let da_of = |event: &str| {
        let row = format!("0.900000,{event},");
        let line = summary.lines().find(|l| l.starts_with(&row));
        line.map(|l| l.split(',').nth(2).unwrap().to_string())
    };
    let bifurcation = da_of("pear bifurcation");
    assert!(bifurcation.is_some(), "{summary}");
    assert_eq!(
        bifurcation,
        da_of("prolate loses up-down stability"),
        "{summary}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The ADE pear near its budding limit: the BC pear path clusters its modes at the neck below
/// 0.1 R0, so at v = 0.8, α = 1.4, Δa0 = 1.6 (Δa ≈ 1.31, near L_pear's 1.346) the pear's w
/// converges with the nodes (unclustered, 121/181/241 nodes gave 2.27223/2.27067/2.27037:
/// 2e-3 apart); clustered, 121 and 241 nodes agree to 1e-5. At v = 0.85 the stable pear's
/// path reaches a neck below 0.01 R0 with Δa0 near L_pear's 1.728 (within 0.03: at a neck of
/// 0.005 R0 Δa0 is 1.704 with 241 nodes, 1.730 with these 121, whose K = 40 modes do not
/// converge the narrowest necks).
#[test]
fn the_ade_pear_converges_to_a_narrow_neck() {
    let w = |nodes| {
        ade_solution(Branch::Pear, 0.8, 1.4, 1.6, &Options::with_nodes(nodes))
            .unwrap()
            .w
    };
    let (coarse, fine) = (w(121), w(241));
    assert!((coarse - fine).abs() < 1e-5, "w {coarse} vs {fine}");
    let curve = axisym::bc_curve(Branch::Pear, 0.85, (1.0, 1.45), &opts());
    let img = axisym::ade_image(&curve.shapes, 1.4);
    let narrowest = curve
        .shapes
        .iter()
        .zip(&img)
        .filter(|(_, p)| p.stable)
        .filter_map(|(s, p)| s.neck().map(|n| (n, p.da0)))
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .unwrap();
    let l = l_pear_at(0.85).unwrap().da0(1.4, 0.0);
    assert!(narrowest.0 < 0.01, "neck {}", narrowest.0);
    assert!(
        (narrowest.1 - l).abs() < 0.03,
        "Δa0 {} vs L_pear {l}",
        narrowest.1
    );
}

/// The BC stomatocyte ends at its limit shape L_sto (a sphere inside a sphere). At v = 0.92
/// (L_sto at Δa = 0.7592) the path from Δa ≈ 1.02 narrows its neck towards L_sto; before the
/// stop it ran past it to Δa = 0.705 with the neck held at 0.022–0.033 R0 by the modes and e
/// rising to 2.67 (above the limit's 2), and the chart called the stomatocyte lowest there.
/// Now no shape lies below L_sto's Δa, and with its modes stretched at the neck the path
/// closes the neck to 0.005 R0 (`Options::neck_min`) within 0.005 of it (0.0022 measured,
/// e = 1.9926); its neck is below 0.1 R0 only within 0.08 of L_sto. The oblate invaginated at both poles at v = 0.96 ran to
/// Δa = 0.705 as well, past the sphere with two spheres inside (Δa = 0.764); now it stops there.
/// The prolate's limit is the sphere budded at both poles (below).
#[test]
fn bc_paths_end_at_their_limit_shapes() {
    let v = 0.92;
    let l = l_sto_at(v).unwrap();
    assert!((l.da - 0.7592).abs() < 1e-4 && (l.e(0.0) - 2.0).abs() < 1e-14);
    let c = axisym::bc_curve(Branch::Stomatocyte, v, (0.70, 1.05), &opts());
    let lowest = |c: &axisym::BcCurve| {
        c.shapes
            .iter()
            .map(|s| s.da())
            .fold(f64::INFINITY, f64::min)
    };
    let end = lowest(&c);
    println!("L_sto Δa = {:.5}, lowest Δa of the path {end:.5}", l.da);
    assert!(end >= l.da, "a stomatocyte past L_sto at Δa = {end}");
    assert!(end < l.da + 0.005, "the path stops short: {end}");
    for s in &c.shapes {
        if s.neck().is_some_and(|r| r < 0.1) {
            assert!(s.da() < l.da + 0.08, "Δa = {}, neck {:?}", s.da(), s.neck());
        }
    }
    let two = inner_spheres_da(0.96, 2).unwrap();
    let o = axisym::bc_curve(Branch::Oblate, 0.96, (0.70, 1.05), &opts());
    let end = lowest(&o);
    println!("two inner spheres Δa = {two:.5}, lowest Δa of the oblate {end:.5}");
    assert!(end >= two && end < two + 0.02, "oblate to Δa = {end}");
    // The prolate at v = 0.90 ends at the sphere budded at both poles (Δa = 1.35643, e = 3):
    // with uniform modes it ran on past it to the window's Δa = 1.39 (e = 3.81) with its necks
    // held at 0.02–0.03 R0; with the mirrored map its necks close to 0.005 R0 at Δa = 1.3517,
    // e = 2.977.
    let buds = outer_buds_da(0.90, 2).unwrap();
    let p = axisym::bc_curve(Branch::Prolate, 0.90, (1.0, 1.40), &opts());
    let last = p
        .shapes
        .iter()
        .max_by(|a, b| a.da().total_cmp(&b.da()))
        .unwrap();
    println!(
        "two buds Δa = {buds:.5}, the prolate's last Δa {:.5}, e {:.4}, neck {:?}",
        last.da(),
        last.e,
        last.neck()
    );
    assert!(
        last.da() < buds && last.da() > buds - 0.01,
        "Δa = {}",
        last.da()
    );
    assert!((last.e - 3.0).abs() < 0.05, "e = {}", last.e);
    assert!(last.neck().unwrap() < 0.006);
}

/// A walk ends outside the Δa window only on the side it set out towards: at v = 0.70 the BC
/// stomatocyte starts at Δa ≈ 0.55 (its SC shape at c̄0 = −1), below the window [0.70, 1.40]
/// of `runs/results/axisym_bc`, and before this rule had no shape in it. Now the path walks up
/// through the window to where it turns towards the symmetric shape (Δa ≈ 1.035).
#[test]
fn a_start_below_the_window_walks_into_it() {
    let c = axisym::bc_curve(Branch::Stomatocyte, 0.70, (0.70, 1.40), &opts());
    let (lo, hi) = c
        .shapes
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), s| {
            (a.min(s.da()), b.max(s.da()))
        });
    println!("{} shapes, Δa {lo:.4}..{hi:.4}", c.shapes.len());
    assert!(c.shapes.len() > 10, "{} shapes", c.shapes.len());
    assert!(
        (0.70..0.72).contains(&lo) && hi > 1.03 && hi <= 1.40,
        "{lo}..{hi}"
    );
}

/// The stomatocyte's modes are stretched at its neck (the pear's `NeckMap`) once it is below
/// 0.1 R0. At v = 0.88 (L_sto at Δa = 0.7020) and Δa = 0.71, 0.008 from L_sto, its e at 121
/// nodes is 1.981395, against 1.981394 at 181 and 241 nodes, and below the limit's e = 2,
/// which it approaches as the neck (0.016 R0) closes. With the unstretched modes e was 2.0509
/// at 121 nodes (2.0232 at 181, 2.0078 at 241): above the limit, not converged. The tolerance
/// 1e-4 allows for the map `bc_solution` takes from the path's nearest shape (4e-5 apart
/// between two maps measured).
#[test]
fn the_stomatocyte_near_l_sto_converges_in_the_nodes() {
    let (v, da) = (0.88, 0.71);
    let l = l_sto_at(v).unwrap();
    assert!((l.da - 0.7020).abs() < 1e-4);
    let s = bc_solution(Branch::Stomatocyte, v, da, &opts()).unwrap();
    println!(
        "e = {:.6}, c̄0,eff = {:.4}, neck {:?}",
        s.e,
        s.c0_eff,
        s.neck()
    );
    assert!((s.da() - da).abs() < 1e-10);
    assert!(!s.map.is_identity(), "the modes are not stretched");
    assert!((s.e - 1.981394).abs() < 1e-4, "e = {}", s.e);
    assert!(s.e < l.e(0.0), "e = {} above L_sto's 2", s.e);
}

/// `bc_solution` reaches a neck of 0.006 R0 at every resolution. At v = 0.88, Δa = 0.705
/// (0.003 above L_sto) one Newton from the path's nearest shape, 1.5e-4 away in Δa, failed at
/// 181 and 241 nodes (its first step raised the residual 115-fold); the solve now walks to Δa
/// in halved steps. e is 1.992276 at 121 nodes and 1.992274 at 181 (the stretched basis
/// converges in the nodes to 1e-5 even here), below the limit's 2.
#[test]
fn the_stomatocyte_is_solved_at_a_neck_of_six_thousandths() {
    let (v, da) = (0.88, 0.705);
    let coarse = bc_solution(Branch::Stomatocyte, v, da, &opts()).unwrap();
    let fine = bc_solution(Branch::Stomatocyte, v, da, &Options::with_nodes(181)).unwrap();
    let neck = fine.neck().expect("a stomatocyte has a neck");
    println!(
        "e = {:.6} (121), {:.6} (181), neck {neck:.4}",
        coarse.e, fine.e
    );
    assert!((fine.da() - da).abs() < 1e-10);
    assert!(neck < 0.007, "neck {neck}");
    assert!(
        (fine.e - coarse.e).abs() < 1e-5,
        "{} against {}",
        fine.e,
        coarse.e
    );
    assert!(fine.e < 2.0, "e = {} above L_sto's 2", fine.e);
}

/// The up–down symmetric branches close their necks with the modes stretched at both necks
/// (the mirrored map, `axisym::map`). The BC prolate at v = 0.90, Δa = 1.33 is a sphere
/// budding at both poles, necks 0.026 R0; the oblate at v = 0.96, Δa = 0.78 is invaginated at
/// both poles, necks 0.015 R0. With modes uniform in the contour, e at the prolate point was
/// 2.958 at 121 nodes and 2.889 at 241 (7e-2 apart, converged neither); stretched, e is
/// 2.865949, 2.864818, 2.864735 and 2.864729 at 121, 181, 241 and 361 nodes, and the oblate's
/// 2.901106, 2.900712, 2.900710 and 2.900710: within 1.3e-3 of the finest at 121 nodes and
/// 1e-4 at 181 (bounds 2e-3 and 2e-4 here).
#[test]
fn the_symmetric_branches_converge_at_narrow_necks() {
    for (branch, v, da, neck_max) in [
        (Branch::Prolate, 0.90, 1.33, 0.03),
        (Branch::Oblate, 0.96, 0.78, 0.02),
    ] {
        let e_at = |nodes: usize| {
            let s = bc_solution(branch, v, da, &Options::with_nodes(nodes)).unwrap();
            assert!((s.da() - da).abs() < 1e-10);
            assert!(
                s.map.mirrored,
                "{}: the modes are not stretched",
                branch.name()
            );
            assert!(s.neck().unwrap() < neck_max, "neck {:?}", s.neck());
            s.e
        };
        let (e121, e181, e241) = (e_at(121), e_at(181), e_at(241));
        println!("{}: e = {e121:.6}, {e181:.6}, {e241:.6}", branch.name());
        assert!((e121 - e241).abs() < 2e-3, "{e121} against {e241}");
        assert!((e181 - e241).abs() < 2e-4, "{e181} against {e241}");
    }
}

/// `ade_solution` returns the lowest stable ADE shape, as the diagram does, where the ADE image
/// of a path leaves Δa0 and covers it again. At v = 0.86, Δa0 = 1.88 (α = 1.4) the prolate's
/// image passes 1.88 near the pear bifurcation (Δa = 1.077, a smooth shape with w = 4.0995) and
/// again where the prolate buds at both poles (Δa ≈ 1.40, necks 0.02–0.03 R0); the committed
/// 241-node chart has w = 3.918710 there. The walk used to stop once the image left
/// Δa0 ± 0.1 and returned the smooth shape; it now follows the whole path: w = 3.92075 at 121
/// nodes and 3.918710 at 241.
#[test]
fn the_ade_solution_is_the_lowest_stable_shape_of_the_whole_path() {
    let (v, alpha, da0) = (0.86, 1.4, 1.88);
    let s = ade_solution(Branch::Prolate, v, alpha, da0, &opts()).unwrap();
    println!("w = {:.6}, Δa = {:.5}, neck {:?}", s.w, s.da(), s.neck());
    assert!((s.w - 3.918710).abs() < 3e-3, "w = {}", s.w);
    assert!(s.neck().is_some_and(|r| r < 0.05), "neck {:?}", s.neck());
    let c0_eff = 2.0 * PI * alpha * (da0 - s.da());
    assert!((s.c0_eff - c0_eff).abs() < 1e-9);
}

/// Every v of the BC chart's grid has a stomatocyte path. At v = 0.66 its SC start (c̄0 = 0,
/// Δa = 0.637) lies 0.001 below the SC branch's turning point in v (0.661), and the second
/// start state, the SC shape at c̄0 + 0.1, did not exist; it is now taken at c̄0 − 0.1 there.
/// At v = 0.98 the SC stomatocyte exists at none of c̄0 = 0 … −4 (it turns back at v = 0.975
/// at −4); the path now starts from the SC shape at v = 0.97 continued in v at fixed height
/// above L_sto. Both paths run from near L_sto (0.476, 0.882) or the window's bottom to their
/// upper fold near Δa = 1.0.
#[test]
fn every_v_of_the_grid_has_a_stomatocyte() {
    for (v, lo_max, hi_min) in [(0.66, 0.71, 1.03), (0.98, 0.89, 1.0)] {
        let c = axisym::bc_curve(Branch::Stomatocyte, v, (0.70, 1.40), &opts());
        let (lo, hi) = c
            .shapes
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), s| {
                (a.min(s.da()), b.max(s.da()))
            });
        println!("v = {v}: {} shapes, Δa {lo:.4}..{hi:.4}", c.shapes.len());
        assert!(c.shapes.len() > 20, "v = {v}: {} shapes", c.shapes.len());
        assert!(lo < lo_max && hi > hi_min, "v = {v}: Δa {lo}..{hi}");
        let l = l_sto_at(v).unwrap().da;
        assert!(lo >= l, "v = {v}: past L_sto");
    }
}

/// Beyond its fold next to the oblate's end (Δa = 1.023 at v = 0.88) the stomatocyte path comes
/// back as its mirror image, the invagination at the other pole, with the same e. Its neck
/// then lies at the other end of the contour: the stretched basis is made again there once the
/// neck has moved (and is the identity while the shape has no neck). Measured: the two halves'
/// e at equal Δa (the first half interpolated linearly between its shapes) differ by at most
/// 2.8e-4; on the first half's map, kept until the neck fell below 0.1 R0, the mirror half was
/// up to 9.6e-3 higher (at Δa = 0.758).
#[test]
fn the_stomatocyte_mirror_half_has_the_same_energy() {
    let c = axisym::bc_curve(Branch::Stomatocyte, 0.88, (0.70, 1.40), &opts());
    let da: Vec<f64> = c.shapes.iter().map(|s| s.da()).collect();
    let fold = (0..da.len())
        .max_by(|&a, &b| da[a].total_cmp(&da[b]))
        .unwrap();
    let half = |r: std::ops::Range<usize>| {
        let mut h: Vec<(f64, f64)> = c.shapes[r].iter().map(|s| (s.da(), s.e)).collect();
        h.sort_by(|a, b| a.0.total_cmp(&b.0));
        h
    };
    let (first, back) = (half(0..fold + 1), half(fold..da.len()));
    assert!(
        first.len() > 20 && back.len() > 20,
        "{} + {}",
        first.len(),
        back.len()
    );
    let mut worst = 0.0f64;
    for &(d, e) in &back {
        if let Some(w) = first.windows(2).find(|w| w[0].0 <= d && d <= w[1].0) {
            let t = (d - w[0].0) / (w[1].0 - w[0].0);
            worst = worst.max((w[0].1 + t * (w[1].1 - w[0].1) - e).abs());
        }
    }
    println!("fold at Δa = {:.4}, worst |Δe| = {worst:.2e}", da[fold]);
    assert!(worst < 2e-3, "the halves differ by {worst}");
}

/// The BC prolate's loss of up–down stability, walked along the BC branch in Δa, is the
/// spontaneous-curvature prolate's at the same shape: at v = 0.8 its Δa is that of the SC
/// prolate at the zero c̄0* of the SC test function, to 1e-8 (measured 1e-12), and its c̄0,eff is
/// c̄0* (measured 1e-10). At v = 0.6996 the search at fixed c̄0 finds nothing (the SC prolate of
/// fixed c̄0 folds: along the BC branch c̄0,eff peaks near 2.13), while the walk finds the
/// bifurcation, at Δa between the prolate's at c̄0,eff = 0 (1.2432) and L_pear (√2), with
/// c̄0,eff below that peak (measured Δa = 1.3028, c̄0,eff = 2.122).
#[test]
fn the_bc_bifurcation_is_the_sc_one_and_is_found_past_the_sc_fold() {
    let o = opts();
    let b = axisym::bc_bifurcation(0.8, &o).expect("the BC bifurcation at v = 0.8");
    let c = axisym::prolate_updown_zero(0.8, (3.0, 4.5), &o).expect("the SC zero");
    let sc = axisym::solve(Branch::Prolate, 0.8, &o.with_c0(c)).expect("the SC prolate");
    assert!(
        (b.da() - sc.da()).abs() < 1e-8,
        "{} against {}",
        b.da(),
        sc.da()
    );
    assert!((b.c0_eff - c).abs() < 1e-6, "{} against {c}", b.c0_eff);
    let v = 0.6996;
    assert!(axisym::prolate_updown_zero(v, (2.0, 2.5), &o).is_none());
    let b = axisym::bc_bifurcation(v, &o).expect("the BC bifurcation at v = 0.6996");
    assert!(b.da() > 1.2432 && b.da() < SQRT_2, "Δa {}", b.da());
    assert!(b.c0_eff > 2.0 && b.c0_eff < 2.2, "c0,eff {}", b.c0_eff);
}
