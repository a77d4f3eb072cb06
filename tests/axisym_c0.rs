//! The axisymmetric reference at spontaneous curvature c̄0 ≠ 0 (`vesicle::analysis::axisym`
//! with `Options::c0`): the sphere law, the c̄0 term against the envelope theorem, c̄0 = 0
//! against the published transitions, convergence in the number of modes, the pear
//! bifurcation off the prolate and its continuation to a narrow neck, and `vesicle axisym
//! --c0`.

use std::process::Command;
use std::sync::OnceLock;
use vesicle::analysis::axisym::{self, phase, Branch, Options, PearBranch, PearEnd, Solution};

/// The pear branch at c̄0 = 3 (default options: 241 nodes, K = 80, neck stop 0.005 R0),
/// followed once for the tests that read it (about 15 s).
fn pear3() -> &'static PearBranch {
    static BRANCH: OnceLock<PearBranch> = OnceLock::new();
    BRANCH.get_or_init(|| axisym::follow_pear(0.5, &Options::default().with_c0(3.0)))
}

/// The sphere (v = 1) has e = (1 − c̄0/2)² for every c̄0, negative included, and integrated
/// mean curvature J = ∮2H dA/(8πR0) = 1: Clenshaw–Curtis integrates the sphere's integrands
/// exactly, so only round-off (≤ 1e-12) remains.
#[test]
fn sphere_law() {
    for c0 in [-2.0, -1.0, -0.5, 0.5, 1.0, 2.0, 3.0] {
        let opts = Options::default().with_c0(c0);
        let s = axisym::solve(Branch::Prolate, 1.0, &opts).unwrap();
        let want = (1.0f64 - c0 / 2.0).powi(2);
        assert!(
            (s.e - want).abs() < 1e-12,
            "c0 = {c0}: e = {} vs {want}",
            s.e
        );
        assert!((s.mean_curvature - 1.0).abs() < 1e-12);
    }
}

/// Envelope theorem: at a stationary shape, de*/dc̄0 at fixed v is the explicit derivative of
/// e = e_0 − c̄0 J + c̄0²/4, i.e. −J + c̄0/2. A wrong gradient of the c̄0 term would leave the
/// solver at a non-stationary shape, where the two differ at first order. Central difference
/// with δ = 1e-3 (error O(δ²) ≈ 1e-6 relative), prolate and oblate at v = 0.8, c̄0 = 1.
#[test]
fn c0_derivative_is_minus_mean_curvature() {
    let d = 1e-3;
    for b in [Branch::Prolate, Branch::Oblate] {
        let at = |c0: f64| axisym::solve(b, 0.8, &Options::default().with_c0(c0)).unwrap();
        let mid = at(1.0);
        let fd = (at(1.0 + d).e - at(1.0 - d).e) / (2.0 * d);
        let want = -mid.mean_curvature + 0.5;
        assert!((fd - want).abs() < 1e-5, "{b:?}: de/dc0 = {fd} vs {want}");
        // A non-spherical shape has J ≠ 1 (so the check is not the sphere's).
        assert!((mid.mean_curvature - 1.0).abs() > 1e-3);
    }
}

/// c̄0 = 0 through the c̄0 diagram reproduces the c0 = 0 diagram: the same prolate energies
/// as `branch_curve` (identical code path, to round-off), and the lowest-energy branch
/// changes where Seifert, Berndl & Lipowsky (1991) put the transitions: prolate/oblate near
/// v = 0.652 and oblate/stomatocyte near 0.59 (the c0 = 0 suite pins them to 1e-3; here
/// within 0.005).
#[test]
fn c0_zero_reproduces_the_symmetric_diagram() {
    let vs: Vec<f64> = (0..=49).map(|i| 0.5 + 0.01 * i as f64).collect();
    let opts = Options::default();
    let s = phase::slice(0.0, &vs, &opts);
    let reference = axisym::branch_curve(Branch::Prolate, &vs, &opts);
    for (a, b) in s.curves[0].iter().zip(&reference) {
        assert!((a.e - b.e).abs() < 1e-13);
    }
    let find = |lo: Branch, hi: Branch| {
        s.lowest
            .changes
            .iter()
            .find(|t| t.below == lo && t.above == hi && t.crossing)
            .map(|t| t.x)
            .unwrap_or_else(|| panic!("no {lo:?}/{hi:?} change in {:?}", s.lowest.changes))
    };
    let po = find(Branch::Oblate, Branch::Prolate);
    let os = find(Branch::Stomatocyte, Branch::Oblate);
    assert!((po - 0.652).abs() < 0.005, "prolate/oblate at {po}");
    assert!((os - 0.59).abs() < 0.005, "oblate/stomatocyte at {os}");
}

/// Convergence in the number of modes at c̄0 = 1, prolate v = 0.75: doubling K from 40 to 80
/// changes e by less than 1e-6 (the target accuracy of e is 1e-5). Measured: K = 40, 80 and
/// 160 all give e = 0.5724873252122 (agreement to 1e-13, as at c0 = 0: the c̄0 term adds
/// only smooth integrands).
#[test]
fn converges_in_modes_at_c0() {
    let e = |nodes: usize| {
        axisym::solve(
            Branch::Prolate,
            0.75,
            &Options::with_nodes(nodes).with_c0(1.0),
        )
        .unwrap()
        .e
    };
    let (coarse, fine) = (e(121), e(241));
    assert!(
        (coarse - fine).abs() < 1e-6,
        "K = 40: {coarse}, K = 80: {fine}"
    );
}

/// The pear at c̄0 = 3: the prolate loses stability to up–down asymmetric deformations at
/// v_b (measured 0.7526), where the pear leaves it: the first pear state (odd amplitude 0.02)
/// has the prolate's energy at its own v to 1e-6 (the branches touch at the pitchfork, the
/// gap is O((v − v_b)²)), the prolate there is up–down symmetric and the pear not. The pitchfork
/// is subcritical (the pear first rises in v, folds, and comes back down), and the
/// continuation follows it past the fold until the neck is at most 0.005 R0 (measured: 0.00496
/// at v = 0.7699, above L_pear = 0.7458, where it would close), every shape on the way
/// converged (residual below the tolerance) and the stop below the fold.
#[test]
fn pear_bifurcates_from_the_prolate_and_narrows() {
    let opts = Options::default().with_c0(3.0);
    let pear = pear3();
    let b = pear.bifurcation.as_ref().expect("a bifurcation at c0 = 3");
    assert!(b.v > 0.72 && b.v < 0.8, "v_b = {}", b.v);
    assert!(b.prolate.asymmetry() == 0.0);
    let first = &pear.shapes[0];
    assert!(first.asymmetry() > 0.01);
    let prolate = axisym::solve(Branch::Prolate, first.v, &opts).unwrap();
    assert!(
        (first.e - prolate.e).abs() < 1e-6,
        "pear {} prolate {}",
        first.e,
        prolate.e
    );
    // Energy and v meet at the bifurcation: the pear's first state is within 1e-3 in v.
    assert!((first.v - b.v).abs() < 1e-3 && (first.e - b.e).abs() < 1e-3);
    let top = pear.shapes.iter().map(|s| s.v).fold(0.0, f64::max);
    match pear.end {
        Some(PearEnd::Neck { v, neck }) => {
            assert!(neck <= 0.005 && neck > 0.0, "neck {neck}");
            assert!(v < top, "stop at {v} above the fold {top}");
            assert!(
                v > axisym::l_pear(3.0).unwrap(),
                "open neck above L_pear: {v}"
            );
        }
        ref other => panic!("pear ended with {other:?}"),
    }
    assert!(
        top > b.v + 0.05,
        "subcritical: the pear rises in v (fold at {top})"
    );
    assert!(pear.shapes.iter().all(|s| s.residual < opts.tol));
}

/// The budding limit `L_pear`: two spheres of radii R1 ≥ R2 (units of R0) with the area of
/// the vesicle, R1² + R2² = 1, and the neck condition 1/R1 + 1/R2 = c̄0 (a sphere of radius R
/// has 2H = 2/R here, so two spheres of radius 2/c̄0 have e = 0). The returned radii satisfy
/// both conditions to round-off and v = R1³ + R2³; the formula starts exactly at the two equal
/// spheres, c̄0 = 2√2 → v = 1/√2 (to round-off, 1e-15), does not exist below, and rises with
/// c̄0. Independent check: the values of an outside solver of the shape equations (rounded to
/// three decimals in issue #51) at c̄0 = 3, 3.245, 3.64, 4, within 1e-3.
#[test]
fn l_pear_two_sphere_limit() {
    let edge = 2.0 * std::f64::consts::SQRT_2;
    let v = axisym::l_pear(edge).unwrap();
    assert!((v - 1.0 / std::f64::consts::SQRT_2).abs() < 1e-15, "{v}");
    let (r1, r2) = axisym::l_pear_radii(edge).unwrap();
    assert!((r1 - r2).abs() < 1e-7, "equal spheres at 2√2: {r1} {r2}");
    assert!(axisym::l_pear(edge - 1e-12).is_none());
    assert!(axisym::l_pear(2.0).is_none());
    assert!(axisym::l_pear(f64::NAN).is_none());
    let mut last = 0.0;
    for i in 0..=40 {
        let c0 = edge + 0.05 * f64::from(i);
        let (r1, r2) = axisym::l_pear_radii(c0).unwrap();
        assert!(r1 >= r2 && r2 > 0.0);
        assert!((r1 * r1 + r2 * r2 - 1.0).abs() < 1e-13, "area at {c0}");
        assert!((1.0 / r1 + 1.0 / r2 - c0).abs() < 1e-12, "neck at {c0}");
        let v = axisym::l_pear(c0).unwrap();
        assert!((v - (r1.powi(3) + r2.powi(3))).abs() < 1e-14);
        assert!(v > last && v < 1.0, "v = {v} at {c0}");
        last = v;
    }
    for (c0, want) in [(3.0, 0.746), (3.245, 0.789), (3.64, 0.839), (4.0, 0.871)] {
        let v = axisym::l_pear(c0).unwrap();
        assert!(
            (v - want).abs() < 1e-3,
            "c0 = {c0}: L_pear at {v}, issue {want}"
        );
    }
}

/// The prolate at v = 0.789 loses stability to up–down asymmetric deformations where its
/// up–down test function μ(c̄0) (smallest eigenvalue of the odd block of the constrained
/// Hessian, `axisym::prolate_updown`) crosses zero. It is stable at c̄0 = 3 (μ > 0) and the zero,
/// located by `prolate_updown_zero` on [3.5, 3.7], is within 1e-3 of the independent solver's:
/// issue #51 gives its test function as +0.0102 at c̄0 = 3.62 and −0.0009 at 3.64, whose linear
/// zero is 3.6384 (quoted as 3.64). This program measures μ = +0.0078 at 3.62 and −0.0007 at
/// 3.64 (its normalisation of μ differs, the zero does not); μ at the zero found is below 1e-6.
#[test]
fn prolate_loses_updown_stability_near_3_64() {
    let v = 0.789;
    let opts = Options::default();
    let mu = |c0: f64| axisym::prolate_updown(v, &opts.with_c0(c0)).unwrap();
    assert!(mu(3.0) > 0.1, "stable at c0 = 3");
    let root = axisym::prolate_updown_zero(v, (3.5, 3.7), &opts).expect("a zero in [3.5, 3.7]");
    assert!(mu(root).abs() < 1e-6, "μ({root}) = {}", mu(root));
    let issue = 3.62 + 0.02 * 0.0102 / (0.0102 + 0.0009);
    assert!(
        (root - issue).abs() < 1e-3,
        "zero of μ at c0 = {root}, independent {issue}"
    );
    assert!(
        axisym::prolate_updown_zero(v, (3.0, 3.5), &opts).is_none(),
        "no sign change on [3, 3.5]"
    );
}

/// At c̄0 = 3, v = 0.789 a stable pear lies below the prolate. The pear branch, followed past
/// its fold (v = 0.8903) to neck 0.005 R0, comes back down in v below the prolate; solved
/// there at v = 0.789 it is up–down asymmetric with an open neck. With the modes clustered at
/// the neck the pear is converged in K: K = 80 and K = 160 give e = 0.1854252747 and neck
/// 0.010329 R0 alike (to 1e-10 and 1e-6). The independent solver of issue #51 gives neck
/// 0.0104 and e = 0.1863 (9e-4 above this resolved Ritz minimum); the prolate's 0.2487 is
/// matched to 1e-3. Asserted: the neck within 5e-4 of 0.0104, e within 1.5e-3 of 0.1863, and
/// the pear below the prolate by more than 0.05.
#[test]
fn stable_pear_below_the_prolate_at_c0_3() {
    let opts = Options::default().with_c0(3.0);
    let v = 0.789;
    let pear = axisym::pear_at(v, pear3(), &opts).expect("a pear after the fold at v = 0.789");
    let prolate = axisym::solve(Branch::Prolate, v, &opts).unwrap();
    assert!((pear.v - v).abs() < 1e-10);
    assert!(pear.asymmetry() > 0.1 && !pear.self_intersecting());
    let neck = pear.neck().expect("a neck");
    assert!((neck - 0.0104).abs() < 5e-4, "neck {neck}");
    assert!(
        (prolate.e - 0.2487).abs() < 1e-3,
        "prolate e = {}",
        prolate.e
    );
    assert!(
        pear.e < prolate.e - 0.05,
        "pear {} prolate {}",
        pear.e,
        prolate.e
    );
    assert!((pear.e - 0.1863).abs() < 1.5e-3, "pear e = {}", pear.e);
}

/// The lowest state at c̄0 = 3 changes from prolate (above) to pear (below) where their
/// energies cross: bisection on e_pear(v) − e_prolate(v) (`pear_at`, `solve`) from [0.81, 0.84]
/// to 1e-6. Measured 0.8237 (0.823681 in the K = 160 summary; the pear's energies agree to 1e-10
/// there, the prolate's to 1e-13), so the resolved crossing lies 1.7e-3 above the 0.822 of
/// issue #51, whose pear energy is higher (0.1863 against 0.18543 at v = 0.789: a less
/// resolved neck, which moves the crossing down). Asserted: the crossing above 0.822 and
/// within 3e-3 of it.
#[test]
fn pear_prolate_crossing_at_c0_3() {
    let opts = Options::default().with_c0(3.0);
    let gap = |v: f64| {
        let pear = axisym::pear_at(v, pear3(), &opts).unwrap();
        let prolate = axisym::solve(Branch::Prolate, v, &opts).unwrap();
        pear.e - prolate.e
    };
    let (mut lo, mut hi) = (0.81, 0.84);
    assert!(gap(lo) < 0.0 && gap(hi) > 0.0);
    while hi - lo > 1e-6 {
        let mid = 0.5 * (lo + hi);
        if gap(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let x = 0.5 * (lo + hi);
    assert!(x > 0.822 && x < 0.822 + 3e-3, "crossing at {x}");
}

/// Towards the budding limit the pear's poles become those of L_pear's two spheres and its v
/// tends to L_pear's: `axisym::neck_limit` extrapolates the path's shapes with necks between
/// 0.02 and 0.005 R0 to a closed neck. Against the two-sphere formula (v = 0.745776, the neck
/// condition 1/R1 + 1/R2 = c̄0 = 3) it measures v = 0.745780 and a pole-curvature sum of
/// 3.0012 (K = 80); asserted to 1e-4 in v (the issue's target) and 0.01 in the sum. Far from
/// the limit (v = 0.868, just below the fold) the sum is above 4 (measured 4.12), and it falls
/// towards 3 along the path (3.14 at the neck stop). The unit sphere has both pole
/// curvatures 1.
#[test]
fn pear_pole_curvatures_approach_the_neck_condition() {
    let sphere = axisym::solve(Branch::Prolate, 1.0, &Options::default()).unwrap();
    let (a, b) = sphere.pole_curvatures();
    assert!((a - 1.0).abs() < 1e-9 && (b - 1.0).abs() < 1e-9, "{a} {b}");
    let opts = Options::default().with_c0(3.0);
    let branch = pear3();
    let sum = |s: &Solution| {
        let (k0, k1) = s.pole_curvatures();
        k0 + k1
    };
    let far = sum(&axisym::pear_at(0.868, branch, &opts).unwrap());
    assert!(far > 4.0, "{far}");
    let last = sum(branch.last.as_ref().unwrap());
    assert!(last > 3.0 && last < 3.2, "at the neck stop: {last}");
    let lim = axisym::neck_limit(branch).expect("enough narrow necks");
    let formula = axisym::l_pear(3.0).unwrap();
    assert!((lim.v - formula).abs() < 1e-4, "{} vs {formula}", lim.v);
    assert!((lim.pole_sum - 3.0).abs() < 0.01, "{}", lim.pole_sum);
}

/// The same limit at c̄0 = 4, a point of the L_pear line away from the two-equal-spheres end:
/// the pear (bifurcation at v = 0.8070, fold 0.9469) followed to neck ≤ 0.005 R0 (measured at
/// v = 0.8878) and extrapolated to a closed neck gives v = 0.870726 against the formula's
/// 0.870679 (R1 = 0.9402, R2 = 0.3405) and a pole-curvature sum 3.990 against c̄0 = 4
/// (K = 80, about 10 s). Asserted: 1e-4 in v, 0.02 in the sum.
#[test]
fn l_pear_from_the_closing_neck_at_c0_4() {
    let opts = Options::default().with_c0(4.0);
    let branch = axisym::follow_pear(0.5, &opts);
    match branch.end {
        Some(PearEnd::Neck { neck, .. }) => assert!(neck <= 0.005, "neck {neck}"),
        ref other => panic!("pear ended with {other:?}"),
    }
    let lim = axisym::neck_limit(&branch).expect("enough narrow necks");
    let formula = axisym::l_pear(4.0).unwrap();
    assert!((lim.v - formula).abs() < 1e-4, "{} vs {formula}", lim.v);
    assert!((lim.pole_sum - 4.0).abs() < 0.02, "{}", lim.pole_sum);
}

/// At c̄0 = 1 the prolate keeps its up–down symmetry (the odd block of the Hessian stays
/// positive definite) down to v = 0.3: no pear bifurcates from it.
#[test]
fn no_pear_bifurcation_at_c0_one() {
    assert!(axisym::pear_bifurcation(&Options::default().with_c0(1.0)).is_none());
}

/// `vesicle axisym --c0` rejects a bad list with exit 2, naming the flag, and writes nothing.
#[test]
fn cli_rejects_bad_c0() {
    let dir = std::env::temp_dir().join(format!("axisym_c0_bad_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = Command::new(env!("CARGO_BIN_EXE_vesicle"))
        .args(["axisym", "--out"])
        .arg(&dir)
        .arg("--c0=0,20")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--c0"));
    assert!(!dir.exists());
}

/// `vesicle axisym --c0 -1,3` end to end on a coarse grid: one branch file per c̄0, the
/// summary with the pear bifurcation and L_pear at c̄0 = 3 and neither at −1, and the chart.
#[test]
fn cli_writes_the_phase_diagram() {
    let dir = std::env::temp_dir().join(format!("axisym_c0_cli_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = Command::new(env!("CARGO_BIN_EXE_vesicle"))
        .args([
            "axisym",
            "--c0=-1,3",
            "--v-min",
            "0.6",
            "--dv",
            "0.05",
            "--nodes",
            "121",
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
        "branches_c0_m1.00.csv",
        "branches_c0_3.00.csv",
        "summary.csv",
        "phase.png",
        "phase.svg",
    ] {
        assert!(dir.join(f).exists(), "{f}");
    }
    let summary = std::fs::read_to_string(dir.join("summary.csv")).unwrap();
    assert!(summary
        .lines()
        .any(|l| l.starts_with("3,pear bifurcation,0.75")));
    assert!(summary
        .lines()
        .any(|l| l.starts_with("-1,pear bifurcation,,")));
    // L_pear from the two-sphere formula (s²(s − 3/c̄0), s = 1/c̄0 + √(1/c̄0² + 1): 0.745776 at
    // c̄0 = 3), none below 2√2.
    assert!(summary.lines().any(|l| l.starts_with("3,L_pear,0.745776,")));
    assert!(summary.lines().any(|l| l.starts_with("-1,L_pear,,")));
    std::fs::remove_dir_all(&dir).unwrap();
}
