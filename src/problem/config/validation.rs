//! [`Scene::validate`]: every check that needs no initial field, each error naming the dotted
//! key and the reason.

use super::c0::{C0Field, C0Spec};
use super::scene::{
    axis_index, AreaMethod, Dynamics, FlowSpec, Method, Scene, Scheme, Symmetry, MAX_LBFGS_MEMORY,
};
use super::shapes::{AxisymBranch, Initial, Shape};
use crate::error::{Error, Result};

impl Scene {
    /// Check every field that can be checked without building the initial field.
    ///
    /// # Errors
    /// `Error::Config` naming the first invalid field and the reason.
    pub fn validate(&self) -> Result<()> {
        if self.dim != 2 && self.dim != 3 {
            return Err(Error::config(
                "dim",
                format!("must be 2 or 3, got {}", self.dim),
            ));
        }
        if self.n.len() != self.dim {
            return Err(Error::config(
                "n",
                format!(
                    "needs {} entries (dim = {}), got {}",
                    self.dim,
                    self.dim,
                    self.n.len()
                ),
            ));
        }
        if let Some(&bad) = self.n.iter().find(|&&m| m < 4) {
            return Err(Error::config(
                "n",
                format!("every entry must be at least 4, got {bad}"),
            ));
        }
        positive("h", self.h)?;
        positive("eps", self.eps)?;
        positive("dt", self.dt)?;
        if let Some(t) = self.t_end {
            positive("t_end", t)?;
        }
        if self.max_steps == Some(0) {
            return Err(Error::config("max_steps", "must be at least 1"));
        }
        if let Some(r) = self.stop_residual {
            positive("stop_residual", r)?;
        }
        if self.t_end.is_none() && self.max_steps.is_none() && self.stop_residual.is_none() {
            return Err(Error::config(
                "t_end",
                "the run needs a stop rule: set t_end, max_steps or stop_residual",
            ));
        }
        if self.threads == Some(0) {
            return Err(Error::config("threads", "must be at least 1"));
        }
        self.validate_method()?;
        self.validate_area()?;
        self.validate_volume()?;
        self.validate_c0()?;
        self.validate_area_difference()?;
        self.validate_symmetry()?;
        self.validate_walls()?;
        self.validate_flow()?;
        if let Initial::Shape(s) = &self.initial {
            validate_shape(s, "initial", self.dim)?;
        }
        if let Some(m) = self.max_wall_minutes {
            positive("max_wall_minutes", m)?;
        }
        self.validate_output()?;
        Ok(())
    }

    /// Each output given in one form (a schedule or the step-count keys), every interval
    /// positive.
    fn validate_output(&self) -> Result<()> {
        let o = &self.output;
        if let Some(m) = o.checkpoint_minutes {
            if !(m > 0.0 && m.is_finite()) {
                return Err(Error::config(
                    "output.checkpoint_minutes",
                    "must be positive (checkpoints are always written at the end)",
                ));
            }
        }
        if o.record_every == Some(0) {
            return Err(Error::config("output.record_every", "must be at least 1"));
        }
        let both = |new: &str, old: &str| {
            Error::config(
                format!("output.{new}"),
                format!("give either output.{new} or output.{old}, not both"),
            )
        };
        if let Some(s) = &o.records {
            if o.record_every.is_some() {
                return Err(both("records", "record_every"));
            }
            s.validate("output.records")?;
        }
        if let Some(s) = &o.snapshots {
            if o.snapshot_every != 0 {
                return Err(both("snapshots", "snapshot_every"));
            }
            s.validate("output.snapshots")?;
        }
        if let Some(s) = &o.checkpoints {
            if o.checkpoint_every != 0 {
                return Err(both("checkpoints", "checkpoint_every"));
            }
            if o.checkpoint_minutes.is_some() {
                return Err(both("checkpoints", "checkpoint_minutes"));
            }
            s.validate("output.checkpoints")?;
        }
        Ok(())
    }

    fn validate_method(&self) -> Result<()> {
        if self.method == Method::Fd {
            if self.scheme != Scheme::Sbdf1 {
                return Err(Error::config(
                    "scheme",
                    "the fd method is explicit Euler; sbdf schemes belong to the spectral method",
                ));
            }
            if self.adaptive.settings().is_some() {
                return Err(Error::config(
                    "adaptive",
                    "the fd reference runs with a fixed step (its stability bound); use the spectral method",
                ));
            }
            if self.dynamics != Dynamics::Conserved {
                return Err(Error::config(
                    "dynamics",
                    "the fd method runs conserved dynamics only",
                ));
            }
        }
        if self.dynamics == Dynamics::Relaxational && self.area_method() == AreaMethod::Lagrangian {
            return Err(Error::config(
                "area.method",
                "relaxational dynamics holds the area exactly; use projection or none",
            ));
        }
        if self.lbfgs_memory == 0 {
            return Err(Error::config("lbfgs_memory", "must be at least 1"));
        }
        if self.lbfgs_memory > MAX_LBFGS_MEMORY {
            return Err(Error::config(
                "lbfgs_memory",
                format!("must be at most {MAX_LBFGS_MEMORY}"),
            ));
        }
        if !(self.stabilizer().s2 >= 0.0 && self.stabilizer().s2.is_finite()) {
            return Err(Error::config("stabilizer.s2", "must be finite and ≥ 0"));
        }
        if !(self.stabilizer().s4 >= 0.0 && self.stabilizer().s4.is_finite()) {
            return Err(Error::config("stabilizer.s4", "must be finite and ≥ 0"));
        }
        if let Some(a) = self.adaptive.settings() {
            if let Some(m) = a.dt_min {
                positive("adaptive.dt_min", m)?;
                if m > self.dt {
                    return Err(Error::config("adaptive.dt_min", "must not exceed dt"));
                }
            }
            if let Some(m) = a.dt_max {
                positive("adaptive.dt_max", m)?;
                if m < self.dt {
                    return Err(Error::config("adaptive.dt_max", "must not be below dt"));
                }
            }
            if !(a.growth > 1.0 && a.growth < 1.0 + 2f64.sqrt()) {
                return Err(Error::config(
                    "adaptive.growth",
                    format!(
                        "must lie in (1, 1+√2) for SBDF2 stability, got {}",
                        a.growth
                    ),
                ));
            }
            if !(a.shrink > 0.0 && a.shrink < 1.0) {
                return Err(Error::config("adaptive.shrink", "must lie in (0, 1)"));
            }
            if !(a.energy_alpha >= 0.0 && a.energy_alpha.is_finite()) {
                return Err(Error::config(
                    "adaptive.energy_alpha",
                    "must be finite and ≥ 0",
                ));
            }
        }
        Ok(())
    }

    fn validate_area(&self) -> Result<()> {
        if let Some(a) = self.area.alpha {
            positive("area.alpha", a)?;
        }
        if let Some(t) = self.area.target {
            positive("area.target", t)?;
        }
        if self.area.alpha.is_some() && self.area_method() != AreaMethod::Lagrangian {
            return Err(Error::config(
                "area.alpha",
                "only the lagrangian area method uses alpha",
            ));
        }
        match (self.area_method(), self.area.sigma) {
            (AreaMethod::Fixed, None) => Err(Error::config(
                "area.sigma",
                "the fixed area method holds σ at area.sigma: give it",
            )),
            (AreaMethod::Fixed, Some(sigma)) => {
                finite("area.sigma", sigma)?;
                if self.area.target.is_some() {
                    return Err(Error::config(
                        "area.target",
                        "the fixed area method holds σ, not the area; drop target",
                    ));
                }
                if self.method == Method::Fd || self.dynamics == Dynamics::Relaxational {
                    return Err(Error::config(
                        "area.method",
                        "a fixed tension is held by the spectral engine's time step only \
                         (conserved or stokes dynamics)",
                    ));
                }
                Ok(())
            }
            (_, Some(_)) => Err(Error::config(
                "area.sigma",
                "only the fixed area method uses sigma",
            )),
            (_, None) => Ok(()),
        }
    }

    /// Unequal viscosities (`flow.viscosity_inside` ≠ `flow.viscosity`) and the locally
    /// inextensible membrane (`flow.inextensible`) run on the periodic box: no declared mirror
    /// plane and no walls (an imposed shear is then the periodic Kolmogorov flow); the two do
    /// not run together.
    fn validate_periodic_flow(&self, flow: FlowSpec) -> Result<()> {
        let what = match (flow.contrast().is_some(), flow.inextensible) {
            (false, false) => return Ok(()),
            (true, true) => {
                return Err(Error::config(
                    "flow.inextensible",
                    "the inextensible membrane runs at equal viscosities: drop \
                     flow.viscosity_inside or set it to flow.viscosity",
                ))
            }
            (true, false) => "unequal viscosities (flow.viscosity_inside)",
            (false, true) => "the inextensible membrane (flow.inextensible)",
        };
        if let Symmetry::Axes(axes) = &self.symmetry {
            if !axes.is_empty() {
                return Err(Error::config(
                    "symmetry",
                    format!(
                        "{what} runs on the periodic box: drop the mirror planes \
                         (\"symmetry\": [] or \"auto\", which then takes none)"
                    ),
                ));
            }
        }
        if !self.walls.is_empty() {
            return Err(Error::config(
                "walls",
                format!("{what} runs on the periodic box: drop the walls"),
            ));
        }
        Ok(())
    }

    /// `dynamics: "stokes"` needs `flow` with η > 0 and M > 0, the spectral CPU engine with its
    /// spectral Laplacian (on any box: periodic, mirrored or walled axes in any mix), and no
    /// area-difference term; an imposed shear along x, varying along y, takes neither an x nor
    /// a y mirror plane nor walls across x. `flow` belongs to it alone.
    fn validate_flow(&self) -> Result<()> {
        let Some(flow) = self.flow else {
            if self.dynamics == Dynamics::Stokes {
                return Err(Error::config(
                    "flow",
                    "stokes dynamics needs the fluid: \"flow\": {\"viscosity\": η, \"mobility\": M}",
                ));
            }
            return Ok(());
        };
        if self.dynamics != Dynamics::Stokes {
            return Err(Error::config(
                "flow",
                "only \"dynamics\": \"stokes\" has a fluid; drop flow or set the dynamics",
            ));
        }
        positive("flow.viscosity", flow.viscosity)?;
        positive("flow.mobility", flow.mobility)?;
        if let Some(g) = flow.shear_rate {
            finite("flow.shear_rate", g)?;
        }
        if let Some(inside) = flow.viscosity_inside {
            positive("flow.viscosity_inside", inside)?;
        }
        self.validate_periodic_flow(flow)?;
        if self.method == Method::Fd {
            return Err(Error::config(
                "dynamics",
                "stokes dynamics runs on the spectral engine; use method spectral",
            ));
        }
        if self.laplacian != crate::problem::config::Laplacian::Spectral {
            return Err(Error::config(
                "laplacian",
                "stokes dynamics takes the spectral Laplacian (the flow's derivatives are spectral)",
            ));
        }
        if let (Some(_), Symmetry::Axes(axes)) = (flow.shear_rate, &self.symmetry) {
            if let Some(a) = axes.iter().find(|a| matches!(a.as_str(), "x" | "y")) {
                return Err(Error::config(
                    "symmetry",
                    format!(
                        "the imposed shear (u_x varying along y) is not even about the plane \
                         {a} = 0; drop {a:?} (walls across y bound a Couette flow: \"walls\": [\"y\"])"
                    ),
                ));
            }
        }
        if self.walls.iter().any(|w| w == "x") && flow.shear_rate.is_some() {
            return Err(Error::config(
                "walls",
                "the imposed shear flows along x: walls across x would stop it; put the walls \
                 across y",
            ));
        }
        if self.ade.is_some() || self.bilayer_couple.is_some() {
            return Err(Error::config(
                if self.ade.is_some() {
                    "ade"
                } else {
                    "bilayer_couple"
                },
                "the area-difference term is not in the stokes step yet; use conserved dynamics",
            ));
        }
        Ok(())
    }

    /// `volume`: f > 0 and T > 0, finite; only the spectral engine's conserved dynamics holds
    /// a time-dependent volume.
    fn validate_volume(&self) -> Result<()> {
        let Some(v) = &self.volume else {
            return Ok(());
        };
        positive("volume.final_fraction", v.final_fraction)?;
        positive("volume.ramp_time", v.ramp_time)?;
        if self.method == Method::Fd {
            return Err(Error::config(
                "volume",
                "a time-dependent volume is held by the spectral engine only; use method spectral",
            ));
        }
        if self.dynamics == Dynamics::Relaxational {
            return Err(Error::config(
                "volume",
                "relaxational dynamics has no time to ramp the volume in; use conserved dynamics",
            ));
        }
        Ok(())
    }

    /// `ade` and `bilayer_couple`: one or the other, 3D only (in 2D ∮κ ds = 2π for every
    /// closed curve, so the term is a constant), finite values, α ≥ 0, Δa > 0; the bilayer
    /// couple's second multiplier is solved by the spectral engine only (the conserved step and
    /// the relaxational L-BFGS).
    fn validate_area_difference(&self) -> Result<()> {
        let field = match (&self.ade, &self.bilayer_couple) {
            (None, None) => return Ok(()),
            (Some(_), Some(_)) => return Err(Error::config(
                "bilayer_couple",
                "give ade or bilayer_couple, not both (the bilayer couple is ADE's limit α → ∞)",
            )),
            (Some(_), None) => "ade",
            (None, Some(_)) => "bilayer_couple",
        };
        if self.dim != 3 {
            return Err(Error::config(
                field,
                "in 2D the integrated curvature ∮κ ds = 2π of every closed curve is constant: \
                 the area difference has no effect; use dim 3",
            ));
        }
        if let Some(a) = &self.ade {
            finite("ade.alpha", a.alpha)?;
            if a.alpha < 0.0 {
                return Err(Error::config(
                    "ade.alpha",
                    format!("must be ≥ 0, got {}", a.alpha),
                ));
            }
            finite("ade.da0", a.da0)?;
            if a.multiplier.is_some()
                && (self.method == Method::Fd || self.dynamics == Dynamics::Relaxational)
            {
                return Err(Error::config(
                    "ade.multiplier",
                    "only the spectral conserved step chooses how to treat λ (the fd reference \
                     lags it; relaxational dynamics minimises the energy itself)",
                ));
            }
        }
        if let Some(b) = &self.bilayer_couple {
            positive("bilayer_couple.da", b.da)?;
            if self.method == Method::Fd {
                return Err(Error::config(
                    "bilayer_couple",
                    "the bilayer couple's second multiplier is solved by the spectral engine \
                     only (the conserved step or relaxational dynamics); use method spectral \
                     (or ade with a large alpha)",
                ));
            }
        }
        Ok(())
    }

    fn validate_c0(&self) -> Result<()> {
        let f = match &self.c0 {
            C0Spec::Uniform(c) => return finite("c0", *c),
            C0Spec::Field(f) => f,
        };
        if let Some(t) = f.ramp_time() {
            positive("c0.ramp_time", t)?;
        }
        let blend = |inside: f64, outside: f64, width: f64| -> Result<()> {
            finite("c0.inside", inside)?;
            finite("c0.outside", outside)?;
            positive("c0.width", width)
        };
        match f {
            C0Field::Ball(b) => {
                blend(b.inside, b.outside, b.width)?;
                if let Some(r) = b.radius {
                    positive("c0.radius", r)?;
                }
                check_center("c0.center", &b.center, self.dim)
            }
            C0Field::Cap(c) => {
                blend(c.inside, c.outside, c.width)?;
                if !(c.angle > 0.0 && c.angle < 180.0) {
                    return Err(Error::config(
                        "c0.angle",
                        format!(
                            "must lie in (0, 180) degrees (the rim's polar angle), got {}",
                            c.angle
                        ),
                    ));
                }
                check_axis("c0.axis", &c.axis, self.dim)?;
                check_center("c0.center", &c.center, self.dim)
            }
            C0Field::Band(b) => {
                blend(b.inside, b.outside, b.width)?;
                positive("c0.half_width", b.half_width)?;
                check_axis("c0.axis", &b.axis, self.dim)?;
                check_center("c0.center", &b.center, self.dim)
            }
            C0Field::File(_) => Ok(()),
        }
    }

    /// `walls`: known axes, each once, none of them also a mirror axis.
    fn validate_walls(&self) -> Result<()> {
        axis_list("walls", &self.walls, self.dim)?;
        if let Symmetry::Axes(axes) = &self.symmetry {
            if let Some(a) = self.walls.iter().find(|a| axes.contains(a)) {
                return Err(Error::config(
                    "walls",
                    format!("axis {a:?} has walls and a mirror plane; give one or the other"),
                ));
            }
        }
        Ok(())
    }

    fn validate_symmetry(&self) -> Result<()> {
        if let Symmetry::Axes(axes) = &self.symmetry {
            for (a, i) in axes.iter().zip(axis_list("symmetry", axes, self.dim)?) {
                if !self.n[i].is_multiple_of(2) {
                    return Err(Error::config(
                        "symmetry",
                        format!("mirror axis {a:?} needs an even n, got {}", self.n[i]),
                    ));
                }
            }
        }
        Ok(())
    }
}

fn positive(field: &str, x: f64) -> Result<()> {
    if x > 0.0 && x.is_finite() {
        Ok(())
    } else {
        Err(Error::config(
            field,
            format!("must be a finite number > 0, got {x}"),
        ))
    }
}

fn finite(field: &str, x: f64) -> Result<()> {
    if x.is_finite() {
        Ok(())
    } else {
        Err(Error::config(field, format!("must be finite, got {x}")))
    }
}

fn check_center(field: &str, center: &Option<Vec<f64>>, dim: usize) -> Result<()> {
    if let Some(c) = center {
        if c.len() != dim {
            return Err(Error::config(
                field,
                format!("needs {dim} entries, got {}", c.len()),
            ));
        }
        if c.iter().any(|x| !x.is_finite()) {
            return Err(Error::config(field, "entries must be finite"));
        }
    }
    Ok(())
}

fn check_axis(field: &str, axis: &Option<String>, dim: usize) -> Result<()> {
    match axis {
        Some(a) if axis_index(a, dim).is_none() => Err(Error::config(
            field,
            format!("unknown axis {a:?} for dim {dim}"),
        )),
        _ => Ok(()),
    }
}

fn validate_shape(s: &Shape, at: &str, dim: usize) -> Result<()> {
    let f = |k: &str| format!("{at}.{k}");
    match s {
        Shape::Sphere(s) => {
            positive(&f("radius"), s.radius)?;
            check_center(&f("center"), &s.center, dim)
        }
        Shape::Ellipsoid(s) => {
            if s.axes.len() != dim {
                return Err(Error::config(
                    f("axes"),
                    format!("needs {dim} entries, got {}", s.axes.len()),
                ));
            }
            for a in &s.axes {
                positive(&f("axes"), *a)?;
            }
            check_center(&f("center"), &s.center, dim)
        }
        Shape::Spheroid(s) => {
            if !(s.reduced_volume > 0.0 && s.reduced_volume <= 1.0) {
                return Err(Error::config(
                    f("reduced_volume"),
                    format!("must lie in (0, 1], got {}", s.reduced_volume),
                ));
            }
            positive(&f("r0"), s.r0)?;
            check_axis(&f("axis"), &s.axis, dim)?;
            check_center(&f("center"), &s.center, dim)
        }
        Shape::Cup(s) => {
            positive(&f("radius"), s.radius)?;
            positive(&f("inner_radius"), s.inner_radius)?;
            finite(&f("offset"), s.offset)?;
            if s.inner_radius + s.offset.abs() <= s.radius {
                return Err(Error::config(
                    f("offset"),
                    "the inner ball lies inside the outer one (no opening): need inner_radius + |offset| > radius",
                ));
            }
            if s.offset.abs() - s.inner_radius >= s.radius {
                return Err(Error::config(
                    f("offset"),
                    "the inner ball misses the outer one",
                ));
            }
            check_axis(&f("axis"), &s.axis, dim)?;
            check_center(&f("center"), &s.center, dim)
        }
        Shape::Harmonic(h) => {
            positive(&f("radius"), h.radius)?;
            if h.mode < 2 {
                return Err(Error::config(
                    f("mode"),
                    format!(
                        "must be at least 2 (0 and 1 are a size change and a shift), got {}",
                        h.mode
                    ),
                ));
            }
            if h.amplitude.is_nan() || h.amplitude.abs() >= 0.5 {
                return Err(Error::config(
                    f("amplitude"),
                    format!(
                        "must lie in (−0.5, 0.5) (relative to the radius), got {}",
                        h.amplitude
                    ),
                ));
            }
            check_axis(&f("axis"), &h.axis, dim)?;
            check_center(&f("center"), &h.center, dim)
        }
        Shape::Slab(s) => {
            positive(&f("thickness"), s.thickness)?;
            positive(&f("wavelength"), s.wavelength)?;
            if s.amplitude.is_nan() || s.amplitude.abs() >= s.thickness / 2.0 {
                return Err(Error::config(
                    f("amplitude"),
                    "|amplitude| must be below thickness/2 (the interfaces would cross)",
                ));
            }
            check_axis(&f("axis"), &s.axis, dim)
        }
        Shape::Capsule(s) => {
            positive(&f("radius"), s.radius)?;
            if !(s.length >= 0.0 && s.length.is_finite()) {
                return Err(Error::config(f("length"), "must be finite and ≥ 0"));
            }
            check_axis(&f("axis"), &s.axis, dim)?;
            check_center(&f("center"), &s.center, dim)
        }
        Shape::Union(u) => {
            if u.of.is_empty() {
                return Err(Error::config(f("of"), "needs at least one shape"));
            }
            for (i, s) in u.of.iter().enumerate() {
                validate_shape(s, &format!("{at}.of[{i}]"), dim)?;
            }
            Ok(())
        }
        Shape::Difference(d) => {
            validate_shape(&d.base, &f("base"), dim)?;
            validate_shape(&d.minus, &f("minus"), dim)
        }
        Shape::Star(s) => {
            if dim != 3 {
                return Err(Error::config(
                    f("shape"),
                    format!("star is a flat 3D disc with arms: it needs dim = 3, got {dim}"),
                ));
            }
            positive(&f("radius"), s.radius)?;
            positive(&f("thickness"), s.thickness)?;
            if s.arms < 2 {
                return Err(Error::config(
                    f("arms"),
                    format!("need at least 2 arms, got {}", s.arms),
                ));
            }
            if !(s.amplitude >= 0.0 && s.amplitude < 1.0) {
                return Err(Error::config(
                    f("amplitude"),
                    format!(
                        "must lie in [0, 1) (the radius stays positive), got {}",
                        s.amplitude
                    ),
                ));
            }
            check_axis(&f("axis"), &s.axis, dim)?;
            check_center(&f("center"), &s.center, dim)
        }
        Shape::Axisym(s) => {
            if dim != 3 {
                return Err(Error::config(
                    f("shape"),
                    format!("axisym is a surface of revolution: it needs dim = 3, got {dim}"),
                ));
            }
            match (&s.contour, s.branch, s.reduced_volume) {
                (Some(_), Some(_), _) | (Some(_), _, Some(_)) => {
                    return Err(Error::config(
                        f("contour"),
                        "give either branch + reduced_volume or contour, not both",
                    ))
                }
                (Some(path), None, None) => {
                    crate::problem::revolution::read_contour(path)
                        .map_err(|e| Error::config(f("contour"), e))?;
                }
                (None, None, _) => {
                    return Err(Error::config(
                        f("branch"),
                        "missing: give branch (prolate, oblate or stomatocyte) + reduced_volume, \
                         or contour",
                    ))
                }
                (None, Some(_), None) => {
                    return Err(Error::config(
                        f("reduced_volume"),
                        "missing: the branch's shape is chosen by its reduced volume",
                    ))
                }
                (None, Some(b), Some(v)) => {
                    let (lo, hi) = b.range();
                    if !(v > lo && v <= hi) {
                        return Err(Error::config(
                            f("reduced_volume"),
                            format!(
                                "the {} branch exists for {lo} < v ≤ {hi}{}, got {v}",
                                b.name(),
                                match b {
                                    AxisymBranch::Prolate => "",
                                    AxisymBranch::Oblate =>
                                        " (below v ≈ 0.503 the oblate intersects itself)",
                                    AxisymBranch::Stomatocyte =>
                                        " (the branch ends at its limit point v ≈ 0.6608)",
                                }
                            ),
                        ));
                    }
                }
            }
            positive(&f("r0"), s.r0)?;
            check_axis(&f("axis"), &s.axis, dim)?;
            check_center(&f("center"), &s.center, dim)
        }
    }
}

/// The scene axes named in `names` (field `key`): each known for `dim` and given once.
fn axis_list(key: &str, names: &[String], dim: usize) -> Result<Vec<usize>> {
    let mut seen = Vec::new();
    for a in names {
        let i = axis_index(a, dim).ok_or_else(|| {
            Error::config(
                key,
                format!(
                    "unknown axis {a:?} for dim {dim} (use x, y{})",
                    if dim == 3 { ", z" } else { "" }
                ),
            )
        })?;
        if seen.contains(&i) {
            return Err(Error::config(key, format!("axis {a:?} given twice")));
        }
        seen.push(i);
    }
    Ok(seen)
}
