//! The shear study file (`runs/studies/shear.json`, 2D; `runs/studies/shear3d.json`, 3D): the
//! dimension, the vesicles' reduced areas (volumes in 3D) and sizes, the capillary number, the
//! channel and the fluid, and single cases that vary one of them. Strict: unknown keys are
//! refused, every value checked, errors name the key.

use crate::commands::study::checks::{at_least, h_over_eps, positive};
use crate::error::{Error, Result};
use serde::Deserialize;

/// How the shear is imposed.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Profile {
    /// Plane Couette flow u_x = γ̇y between free-slip walls across y.
    Walls,
    /// The periodic Kolmogorov flow u_x = (γ̇/k₀) sin(k₀y), of local shear rate γ̇ at y = 0.
    Kolmogorov,
}

impl Profile {
    /// The name in the tables.
    pub fn name(self) -> &'static str {
        match self {
            Profile::Walls => "walls",
            Profile::Kolmogorov => "kolmogorov",
        }
    }
}

/// The study file's keys.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// `"shear"`.
    pub study: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// 2 (a contour in the shear plane) or 3 (a surface on the half box mirrored about the
    /// shear plane z = 0, the one mirror plane the shear keeps); default 2.
    #[serde(default = "two")]
    pub dimension: usize,
    /// h/ε of every case.
    pub h_over_eps: f64,
    /// η.
    pub viscosity: f64,
    /// M of the diffusive channel.
    pub mobility: f64,
    /// Ca = ηγ̇R0³/κ.
    pub capillary: f64,
    /// The vesicles' reduced areas (each started as an ellipse of that reduced area); in 3D
    /// reduced volumes (each started as a prolate spheroid along the flow).
    pub reduced_areas: Vec<f64>,
    /// R0/ε of each size (at least two: the angle is extrapolated in ε/R0).
    pub r0: Vec<f64>,
    /// The channel's width (wall to wall, or the Kolmogorov period) over R0.
    pub channel: f64,
    /// The periodic box's length along the flow (and in 3D along the vorticity z) over R0.
    pub length: f64,
    /// How the shear is imposed.
    pub profile: Profile,
    /// The run's length in strain units γ̇t.
    pub strains: f64,
    /// The largest Δt of the adaptive SBDF2 steps.
    pub dt_max: f64,
    /// Single cases, each at one reduced area and size, varying the capillary number, the
    /// channel, the box's length or the profile (what the angle does not depend on, or how much it does).
    #[serde(default)]
    pub variations: Vec<Variation>,
}

/// One case beside the main grid.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct Variation {
    /// Its reduced area.
    pub reduced_area: f64,
    /// Its R0/ε.
    pub r0: f64,
    /// Ca, else the spec's.
    #[serde(default)]
    pub capillary: Option<f64>,
    /// W/R0, else the spec's.
    #[serde(default)]
    pub channel: Option<f64>,
    /// L/R0, else the spec's.
    #[serde(default)]
    pub length: Option<f64>,
    /// The profile, else the spec's.
    #[serde(default)]
    pub profile: Option<Profile>,
    /// η_in/η_out (`viscosity` is then the outside's), else 1: 2D on the periodic Kolmogorov
    /// profile only (unequal viscosities run on the periodic box).
    #[serde(default)]
    pub viscosity_ratio: Option<f64>,
}

impl Spec {
    /// Check every value.
    ///
    /// # Errors
    /// `Error::Config` naming the key.
    pub fn validate(&self) -> Result<()> {
        if !matches!(self.dimension, 2 | 3) {
            return Err(Error::config(
                "dimension",
                format!("need 2 or 3, got {}", self.dimension),
            ));
        }
        h_over_eps(self.h_over_eps)?;
        for (key, v) in [
            ("viscosity", self.viscosity),
            ("mobility", self.mobility),
            ("capillary", self.capillary),
            ("strains", self.strains),
            ("dt_max", self.dt_max),
        ] {
            positive(key, v)?;
        }
        if self.reduced_areas.is_empty() {
            return Err(Error::config("reduced_areas", "need at least one"));
        }
        for &v in &self.reduced_areas {
            reduced_area("reduced_areas", v)?;
        }
        if self.r0.len() < 2 || self.r0.iter().any(|r| !at_least(*r, 6.0)) {
            return Err(Error::config(
                "r0",
                "need at least two R0/ε ≥ 6 (the angle is extrapolated in ε/R0)",
            ));
        }
        channel("channel", self.channel)?;
        length("length", self.length)?;
        for (i, v) in self.variations.iter().enumerate() {
            let key = |k: &str| format!("variations[{i}].{k}");
            reduced_area(&key("reduced_area"), v.reduced_area)?;
            if !at_least(v.r0, 6.0) {
                return Err(Error::config(key("r0"), "need R0/ε ≥ 6"));
            }
            if let Some(c) = v.capillary {
                positive(&key("capillary"), c)?;
            }
            if let Some(w) = v.channel {
                channel(&key("channel"), w)?;
            }
            if let Some(l) = v.length {
                length(&key("length"), l)?;
            }
            if let Some(ratio) = v.viscosity_ratio {
                positive(&key("viscosity_ratio"), ratio)?;
                let profile = v.profile.unwrap_or(self.profile);
                if ratio != 1.0 && (self.dimension != 2 || profile != Profile::Kolmogorov) {
                    return Err(Error::config(
                        key("viscosity_ratio"),
                        "unequal viscosities run on the periodic box: 2D, profile kolmogorov",
                    ));
                }
            }
        }
        Ok(())
    }
}

/// The default dimension.
fn two() -> usize {
    2
}

/// A reduced area the ellipse start can take and the tank-treading regime holds.
fn reduced_area(key: &str, v: f64) -> Result<()> {
    if v > 0.3 && v < 1.0 {
        Ok(())
    } else {
        Err(Error::config(key, format!("need 0.3 < v < 1, got {v}")))
    }
}

/// A periodic box long enough to keep the vesicle apart from its images.
fn length(key: &str, l: f64) -> Result<()> {
    if at_least(l, 3.0) {
        Ok(())
    } else {
        Err(Error::config(
            key,
            format!("need L/R0 ≥ 3 (the vesicle apart from its periodic images), got {l}"),
        ))
    }
}

/// A channel wide enough for the vesicle and its walls' layers.
fn channel(key: &str, w: f64) -> Result<()> {
    if at_least(w, 3.0) {
        Ok(())
    } else {
        Err(Error::config(
            key,
            format!("need W/R0 ≥ 3 (the vesicle clear of the walls), got {w}"),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::{json, Value};

    /// The study file `name` without its `quick` block (which the loader applies or drops).
    fn file(name: &str) -> Value {
        let text = std::fs::read_to_string(format!("runs/studies/{name}")).expect("the file");
        let mut v: Value = serde_json::from_str(&text).expect("json");
        v.as_object_mut().expect("an object").remove("quick");
        v
    }

    /// The committed 3D file validates; a dimension other than 2 or 3 is refused naming
    /// `dimension`, and a file without one (the 2D study) means 2.
    #[test]
    fn the_dimension_is_two_or_three() {
        let spec: Spec = serde_json::from_value(file("shear3d.json")).expect("parses");
        assert_eq!(spec.dimension, 3);
        spec.validate().expect("valid");
        for bad in [0, 1, 4] {
            let mut v = file("shear3d.json");
            v["dimension"] = json!(bad);
            let spec: Spec = serde_json::from_value(v).expect("parses");
            let e = spec.validate().expect_err("refused").to_string();
            assert!(
                e.contains("`dimension`") && e.contains("need 2 or 3"),
                "{e}"
            );
        }
        let spec: Spec = serde_json::from_value(file("shear.json")).expect("parses");
        assert_eq!(spec.dimension, 2);
        spec.validate().expect("valid");
    }

    /// A variation's box length below 3R0 is refused naming the variation's key.
    #[test]
    fn a_short_variation_box_is_refused() {
        let mut v = file("shear3d.json");
        v["variations"] = json!([{"reduced_area": 0.9, "r0": 8, "length": 2.5}]);
        let spec: Spec = serde_json::from_value(v).expect("parses");
        let e = spec.validate().expect_err("refused").to_string();
        assert!(e.contains("`variations[0].length`"), "{e}");
    }

    /// Unequal viscosities run on the periodic box: the committed contrast study validates (2D,
    /// Kolmogorov); a variation with η_in/η_out ≠ 1 is refused naming its key in 3D, between
    /// walls, and for a ratio ≤ 0.
    #[test]
    fn unequal_viscosities_need_the_periodic_2d_box() {
        let spec: Spec = serde_json::from_value(file("shear_contrast.json")).expect("parses");
        spec.validate().expect("valid");
        for (name, variation) in [
            (
                "shear3d.json",
                json!({"reduced_area": 0.9, "r0": 8, "viscosity_ratio": 2}),
            ),
            (
                "shear.json",
                json!({"reduced_area": 0.9, "r0": 12, "viscosity_ratio": 2}),
            ),
            (
                "shear_contrast.json",
                json!({"reduced_area": 0.9, "r0": 12, "viscosity_ratio": -1}),
            ),
        ] {
            let mut v = file(name);
            v["variations"] = json!([variation]);
            let spec: Spec = serde_json::from_value(v).expect("parses");
            let e = spec.validate().expect_err("refused").to_string();
            assert!(e.contains("`variations[0].viscosity_ratio`"), "{name}: {e}");
        }
    }
}
