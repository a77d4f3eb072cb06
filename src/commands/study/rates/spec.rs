//! The rates study file (`runs/studies/rates.json`): which modes, tensions and sizes of the
//! quasi-circle, the quasi-sphere and the flat membrane, the fluid and the lattice. Strict:
//! unknown keys are refused, every value checked, errors name the key.

use crate::commands::study::checks::{at_least, h_over_eps, positive, within};
use crate::error::{Error, Result};
use serde::{Deserialize, Deserializer};

/// The study file's keys.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// `"rates"`.
    pub study: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// h/ε of every case.
    pub h_over_eps: f64,
    /// η.
    pub viscosity: f64,
    /// M of the diffusive channel: one number, or a list, smallest first; every case runs at
    /// each, and each M is extrapolated in ε/R on its own.
    #[serde(deserialize_with = "one_or_many")]
    pub mobility: Vec<f64>,
    /// The seeded mode's amplitude: relative to R (circle, sphere) or to λ (flat).
    pub amplitude: f64,
    /// The largest Δt (the explicit flow's stability: Δt = 4 ran and Δt = 8 diverged at
    /// M = 0.01, h = ε/2).
    pub dt_max: f64,
    /// Δt = min(`dt_max`, `step_per_rate` / Γ): the rate's resolution in time.
    pub step_per_rate: f64,
    /// The e-folds of the mode each case runs for (after its first tenth, which is left out of
    /// the fit).
    pub e_folds: f64,
    /// Steps of the conserved flow (SBDF1, M = 1, σ = 0) that build the tanh profile first.
    pub prepare_steps: usize,
    /// The quasi-circle (2D).
    #[serde(default)]
    pub circle: Option<Family>,
    /// The quasi-sphere (3D).
    #[serde(default)]
    pub sphere: Option<Family>,
    /// The flat membrane (2D).
    #[serde(default)]
    pub flat: Option<Flat>,
}

/// Modes of a closed vesicle: groups of (modes, tensions) with the sizes each is run at.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct Family {
    /// L/R, the periodic box's side over the radius: one number, or a list of boxes each size
    /// runs in, whose ratios are extrapolated to L → ∞ (in (R/L)^d, the order of the lowest
    /// mode's images) before the extrapolation in ε/R.
    #[serde(rename = "box", deserialize_with = "one_or_many")]
    pub boxes: Vec<f64>,
    /// Run each case on a mirror-reduced box: the sphere's quarter box about x and y (the
    /// quasi-sphere's P_l(cos θ) about z is even in both, z left periodic) for odd l and its
    /// eighth box (z mirrored too) for even l; the circle's quarter box (cos nθ is even about
    /// both axes for even n only, so a mirrored circle takes even modes). The same rate (the
    /// reduced box reproduces the full one to round-off) on a quarter or an eighth of the
    /// points.
    #[serde(default)]
    pub mirror: bool,
    /// The groups.
    pub groups: Vec<Group>,
}

/// Modes and tensions run at the same sizes.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct Group {
    /// n (circle) or l (sphere), each ≥ 2.
    pub modes: Vec<usize>,
    /// σ̄ = σR²/κ.
    pub sigma_bar: Vec<f64>,
    /// R/ε of each size (at least two: the rate is extrapolated in ε/R).
    pub r0: Vec<f64>,
    /// λ = η_in/η_out of each case (η_out the spec's `viscosity`; unequal viscosities run the
    /// circle on the full periodic box; the sphere is not taken, its box factor being known at
    /// λ = 1 only).
    #[serde(default = "equal_viscosities")]
    pub viscosity_ratio: Vec<f64>,
    /// The membrane models each case runs: `drop` (one global tension, the default) and/or
    /// `inextensible` (`flow.inextensible`, a tension field: the sharp rates are then Milner &
    /// Safran's in 3D, the circle's unchanged, with the box factor of the constrained
    /// mobility; on the full periodic box, at equal viscosities).
    #[serde(default = "drop_only")]
    pub models: Vec<Model>,
}

/// A membrane model of the rates study.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Model {
    /// One global tension: a drop with bending rigidity.
    Drop,
    /// A tension field holding the surface incompressible.
    Inextensible,
}

/// A number or a list of numbers, read as a list.
fn one_or_many<'de, D: Deserializer<'de>>(d: D) -> std::result::Result<Vec<f64>, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum OneOrMany {
        One(f64),
        Many(Vec<f64>),
    }
    Ok(match OneOrMany::deserialize(d)? {
        OneOrMany::One(x) => vec![x],
        OneOrMany::Many(v) => v,
    })
}

/// The drop alone.
fn drop_only() -> Vec<Model> {
    vec![Model::Drop]
}

/// λ = 1.
fn equal_viscosities() -> Vec<f64> {
    vec![1.0]
}

/// Wavelengths of the flat membrane.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct Flat {
    /// λ/ε of each case (the box is one wavelength long).
    pub wavelengths: Vec<f64>,
    /// σ/(κk²) of each case.
    pub sigma_bar: Vec<f64>,
    /// The box's height over λ (the slab is half of it: the two interfaces λ·height/2 apart).
    pub height: f64,
    /// η_in/η_out of each case (inside the slab over outside).
    #[serde(default = "equal_viscosities")]
    pub viscosity_ratio: Vec<f64>,
}

impl Spec {
    /// Check every value.
    ///
    /// # Errors
    /// `Error::Config` naming the key.
    pub fn validate(&self) -> Result<()> {
        h_over_eps(self.h_over_eps)?;
        for (key, v) in [
            ("viscosity", self.viscosity),
            ("dt_max", self.dt_max),
            ("step_per_rate", self.step_per_rate),
            ("e_folds", self.e_folds),
        ] {
            positive(key, v)?;
        }
        if self.mobility.is_empty() || self.mobility.iter().any(|&m| !(m > 0.0 && m.is_finite())) {
            return Err(Error::config("mobility", "need values M > 0, at least one"));
        }
        if self.mobility.windows(2).any(|w| w[0] >= w[1]) {
            return Err(Error::config(
                "mobility",
                "list the mobilities once each, smallest first",
            ));
        }
        if !(self.amplitude > 0.0 && self.amplitude < 0.2) {
            return Err(Error::config(
                "amplitude",
                "need 0 < a < 0.2 (a linear mode)",
            ));
        }
        if self.circle.is_none() && self.sphere.is_none() && self.flat.is_none() {
            return Err(Error::config("circle", "give circle, sphere and/or flat"));
        }
        for (key, family) in [("circle", &self.circle), ("sphere", &self.sphere)] {
            if let Some(f) = family {
                f.validate().map_err(|e| within(key, e))?;
            }
        }
        if let Some(f) = &self.sphere {
            if f.unequal_viscosities() {
                return Err(Error::config(
                    "sphere.groups.viscosity_ratio",
                    "the quasi-sphere's box factor is known at equal viscosities only: run \
                     unequal viscosities on the circle or the flat membrane",
                ));
            }
        }
        let mirrored_circle = self.circle.as_ref().filter(|f| f.mirror);
        if let Some(n) = mirrored_circle.and_then(|f| {
            f.groups
                .iter()
                .flat_map(|g| &g.modes)
                .find(|&&n| n % 2 == 1)
        }) {
            return Err(Error::config(
                "circle.mirror",
                format!(
                    "the circle's quarter box holds even modes only: cos {n}θ is odd about \
                     x = 0; run odd modes on the full box"
                ),
            ));
        }
        if let Some(f) = &self.flat {
            if f.wavelengths.is_empty() || f.wavelengths.iter().any(|w| !at_least(*w, 8.0)) {
                return Err(Error::config(
                    "flat.wavelengths",
                    "need λ/ε ≥ 8, at least one",
                ));
            }
            if f.sigma_bar.is_empty() || f.sigma_bar.iter().any(|s| !at_least(*s, 0.0)) {
                return Err(Error::config(
                    "flat.sigma_bar",
                    "need values ≥ 0, at least one",
                ));
            }
            ratios(&f.viscosity_ratio).map_err(|e| within("flat", e))?;
            if !at_least(f.height, 2.0) {
                return Err(Error::config(
                    "flat.height",
                    "need ≥ 2 (the interfaces at least a wavelength apart)",
                ));
            }
        }
        Ok(())
    }
}

/// Every λ = η_in/η_out > 0, at least one.
fn ratios(values: &[f64]) -> Result<()> {
    if values.is_empty() || values.iter().any(|&l| !(l > 0.0 && l.is_finite())) {
        return Err(Error::config(
            "viscosity_ratio",
            "need values η_in/η_out > 0, at least one",
        ));
    }
    Ok(())
}

impl Family {
    /// Whether any group runs a viscosity ratio other than 1.
    fn unequal_viscosities(&self) -> bool {
        self.groups
            .iter()
            .flat_map(|g| &g.viscosity_ratio)
            .any(|&l| l != 1.0)
    }

    fn validate(&self) -> Result<()> {
        if self.mirror && self.unequal_viscosities() {
            return Err(Error::config(
                "mirror",
                "unequal viscosities run on the full periodic box: drop mirror",
            ));
        }
        let inextensible = self
            .groups
            .iter()
            .any(|g| g.models.contains(&Model::Inextensible));
        if self.mirror && inextensible {
            return Err(Error::config(
                "mirror",
                "the inextensible membrane runs on the full periodic box: drop mirror",
            ));
        }
        if self.boxes.is_empty() || self.boxes.iter().any(|&b| !at_least(b, 2.5)) {
            return Err(Error::config(
                "box",
                "need L/R ≥ 2.5 (the vesicle and its images apart), at least one",
            ));
        }
        if self.boxes.windows(2).any(|w| w[0] >= w[1]) {
            return Err(Error::config(
                "box",
                "list the boxes once each, smallest first",
            ));
        }
        if self.groups.is_empty() {
            return Err(Error::config("groups", "need at least one group"));
        }
        for (i, g) in self.groups.iter().enumerate() {
            g.validate()
                .map_err(|e| within(&format!("groups[{i}]"), e))?;
        }
        Ok(())
    }
}

impl Group {
    fn validate(&self) -> Result<()> {
        if self.modes.is_empty() || self.modes.iter().any(|&m| m < 2) {
            return Err(Error::config("modes", "need modes ≥ 2, at least one"));
        }
        if self.sigma_bar.is_empty() || self.sigma_bar.iter().any(|s| !at_least(*s, 0.0)) {
            return Err(Error::config("sigma_bar", "need values ≥ 0, at least one"));
        }
        ratios(&self.viscosity_ratio)?;
        if self.models.is_empty() {
            return Err(Error::config("models", "need at least one model"));
        }
        if self.models.contains(&Model::Inextensible)
            && self.viscosity_ratio.iter().any(|&l| l != 1.0)
        {
            return Err(Error::config(
                "models",
                "the inextensible membrane runs at equal viscosities: drop viscosity_ratio \
                 or run it in a group of its own",
            ));
        }
        if self.r0.len() < 2 || self.r0.iter().any(|r| !at_least(*r, 6.0)) {
            return Err(Error::config(
                "r0",
                "need at least two R/ε ≥ 6 (the rate is extrapolated in ε/R)",
            ));
        }
        Ok(())
    }
}
