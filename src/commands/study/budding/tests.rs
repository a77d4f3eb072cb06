use super::*;
use crate::commands::measure::measure_field;

fn spec(edit: impl FnOnce(&mut Value)) -> std::result::Result<Spec, String> {
    let mut v = json!({
        "study": "budding",
        "scene": {"dim": 3, "n": [32, 32, 48], "dt": 0.01, "stop_residual": 1e-6, "max_steps": 100},
        "v": 0.8, "r0": 10.0, "c0": [1.0, 1.5], "seed": 0.02
    });
    edit(&mut v);
    let spec: Spec = serde_json::from_value(v).map_err(|e| e.to_string())?;
    check(&spec).map_err(|e| e.to_string())?;
    base_scene(&spec).map_err(|e| e.to_string())?;
    Ok(spec)
}

fn refused(edit: impl FnOnce(&mut Value)) -> String {
    spec(edit).expect_err("should be refused")
}

/// The file's refusals name the key: v outside (0, 1), a path that repeats a value (a path
/// may come back down), ε|c0| above 0.2 (c0 R0 = 2.5 at R0 = 10ε is 0.25), a seed out of range, and the scene keys the
/// study sets.
#[test]
fn bad_files_are_refused_naming_the_key() {
    assert!(spec(|_| {}).is_ok());
    assert!(refused(|v| v["v"] = json!(1.0)).contains("`v`"));
    assert!(refused(|v| v["c0"] = json!([1.0, 1.0])).contains("twice in a row"));
    assert!(spec(|v| v["c0"] = json!([1.0, 1.5, 1.0])).is_ok());
    assert!(refused(|v| v["c0"] = json!([])).contains("c0"));
    let high = refused(|v| v["c0"] = json!([1.0, 2.5]));
    assert!(high.contains("`c0`") && high.contains("0.250"), "{high}");
    assert!(refused(|v| v["seed"] = json!(0.5)).contains("`seed`"));
    assert!(refused(|v| v["scene"]["c0"] = json!(0.1)).contains("`scene.c0`"));
    assert!(refused(|v| v["scene"]["symmetry"] = json!(["z"])).contains("`scene.symmetry`"));
    assert!(refused(|v| v["scene"]["dt"] = json!(-1.0)).contains("`scene.dt`"));
    assert!(refused(|v| v["scene"]["dim"] = json!(2)).contains("scene"));
}

/// Two spheres of radius 9 joined by a cylinder of radius 3 along z: the neck measured on
/// the tanh field is the cylinder's radius. The slices through the cylinder are discs of
/// radius 3 whose diffuse profile the marching-squares area resolves to O(h²) in the
/// contour's curvature (1/3 here): within 0.05.
#[test]
fn the_neck_of_two_spheres_joined_by_a_cylinder_is_the_cylinder_radius() {
    let grid = Grid::new(&[32, 32, 64], 1.0, &[false; 3]);
    let (r_ball, r_neck, centre) = (9.0, 3.0, 12.5);
    let phi = grid.field_from(|p| {
        let rho = p[0].hypot(p[1]);
        let ball = |zc: f64| r_ball - (rho * rho + (p[2] - zc).powi(2)).sqrt();
        let tube = if p[2].abs() <= centre {
            r_neck - rho
        } else {
            -1e9
        };
        shapes::profile(ball(centre).max(ball(-centre)).max(tube), 1.0)
    });
    let m = measure_field(&phi, 2, 1.0, 0, 0.0);
    let (neck, _) = m.neck.expect("a neck");
    assert!((neck - r_neck).abs() < 0.05, "neck {neck}");
    assert!(
        (m.r_max - r_ball).abs() < 0.05,
        "largest radius {}",
        m.r_max
    );
    assert!(
        m.skewness.abs() < 1e-9,
        "symmetric: skewness {}",
        m.skewness
    );
    assert_eq!((m.pieces, state(&m)), (1, "symmetric"));
}

/// The sharp prolate's contour at v = 0.79, c̄0 = 3 (a peanut with a waist), revolved onto
/// the grid at R0 = 10ε: the neck the slice profile measures is the solver's waist radius
/// (an independent figure: the contour's own narrowest r) within 0.1ε, the volume is
/// symmetric (skewness at round-off), one piece, and the φ = 0 reduced volume is within 0.01
/// of the solver's. A box too short for the shape is refused naming `scene.n`.
#[test]
fn the_revolved_prolate_has_the_solvers_waist() {
    let sharp = axisym::solve(Branch::Prolate, 0.79, &Options::default().with_c0(3.0)).unwrap();
    let waist = 10.0 * sharp.neck().expect("the prolate at c0 R0 = 3 has a waist");
    let grid = Grid::new(&[32, 32, 56], 1.0, &[false; 3]);
    let phi = revolved(&sharp.r, &sharp.z, 10.0, 1.0, &grid);
    check_fits(&phi).unwrap();
    let m = measure_field(&phi, 2, 1.0, 0, 0.0);
    let (neck, _) = m.neck.expect("a waist");
    assert!((neck - waist).abs() < 0.1, "neck {neck}, solver {waist}");
    assert!(m.skewness.abs() < 1e-6, "skewness {}", m.skewness);
    assert_eq!(state(&m), "symmetric");
    assert!(
        (m.surface.reduced_volume - 0.79).abs() < 0.01,
        "v {}",
        m.surface.reduced_volume
    );
    let cramped = Grid::new(&[32, 32, 30], 1.0, &[false; 3]);
    let err = check_fits(&revolved(&sharp.r, &sharp.z, 10.0, 1.0, &cramped)).unwrap_err();
    assert!(err.to_string().contains("scene.n"), "{err}");
}
