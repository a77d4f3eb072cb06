//! The diagram file (`runs/diagram.json`, `runs/diagram_c0.json`): which reduced spontaneous
//! curvatures c̄0, branches and reduced volumes, at which resolutions ε/R0, and how each case
//! is run. Strict JSON: unknown keys are refused, every value is checked, and errors name the
//! key.

use crate::analysis::axisym::Branch;
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// Reduced volumes per branch name (`prolate`, `oblate`, `stomatocyte`).
pub type Branches = BTreeMap<String, Vec<f64>>;

/// A diagram: every listed `(branch, v)` at every `c0` and every `r0` is one independent case.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DiagramSpec {
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// Reduced spontaneous curvatures c̄0 = c0 R0 (default `[0]`, the c0 = 0 diagram).
    #[serde(default = "zero_c0")]
    pub c0: Vec<f64>,
    /// Reduced volumes per branch, at every slice that `branches_by_c0` or `branches_by_da`
    /// does not list.
    #[serde(default)]
    pub branches: Branches,
    /// Reduced volumes per branch at one c̄0 (the key, as a number: `"-0.5"`), replacing
    /// `branches` there.
    #[serde(default)]
    pub branches_by_c0: BTreeMap<String, Branches>,
    /// Reduced volumes per branch at one slice of an ADE or bilayer-couple diagram (the key, as
    /// a number: its Δa0 or Δa), replacing `branches` there (a bilayer couple's prolate and
    /// oblate exist at different Δa).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub branches_by_da: BTreeMap<String, Branches>,
    /// Area-difference elasticity: the diagram's slices are the preferred Δa0 at one α (and
    /// the single c̄0 of `c0`); each case's scene holds `"ade"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ade: Option<AdeSlices>,
    /// The bilayer couple: the slices are the Δa held (the single c̄0 of `c0`); each case's
    /// scene holds `"bilayer_couple"`, which L-BFGS holds as its second constraint.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bilayer_couple: Option<BcSlices>,
    /// R0/ε of each resolution (ε = 1); at least two for the extrapolation in ε/R0.
    pub r0: Vec<f64>,
    /// ε/h (the grid spacing is h = 1/eps_over_h).
    #[serde(default = "one")]
    pub eps_over_h: f64,
    /// Outside bulk kept between the shape and the box faces: `margin` ε + `margin_r0` R0.
    #[serde(default = "default_margin")]
    pub margin: f64,
    /// See `margin`: the part that scales with the vesicle, so the box keeps its proportions.
    #[serde(default = "default_margin_r0")]
    pub margin_r0: f64,
    /// Stationarity tolerance RMS(μ − μ̄) of each relaxation (README: 1e-6 for diagrams).
    #[serde(default = "default_stop_residual")]
    pub stop_residual: f64,
    /// Most L-BFGS iterations per case.
    #[serde(default = "default_max_iterations")]
    pub max_iterations: usize,
    /// Unconstrained SBDF1 steps of Δt = 0.01 that build the profile before A0 is taken.
    #[serde(default = "default_prepare_steps")]
    pub prepare_steps: usize,
    /// Reduced volumes whose finest-resolution shapes get a thumbnail picture.
    #[serde(default)]
    pub thumbnails: Vec<f64>,
    /// Thinnest part (of the body or of a gap it encloses, [`super::thickness::thinnest`]) that
    /// every start shape must keep at the coarsest resolution, in ε.
    #[serde(default = "default_min_width")]
    pub min_width: f64,
}

/// `bilayer_couple` of a diagram file: the Δa of each slice.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BcSlices {
    /// The reduced area differences Δa held, a slice each.
    pub da: Vec<f64>,
}

/// `ade` of a diagram file: α and the Δa0 of each slice.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct AdeSlices {
    /// α = κ̄/κ.
    pub alpha: f64,
    /// The preferred reduced area differences Δa0, a slice each.
    pub da0: Vec<f64>,
}

/// The area-difference term of a slice: ADE at α and Δa0, or the bilayer couple at Δa.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Couple {
    /// Area-difference elasticity.
    Ade {
        /// α = κ̄/κ.
        alpha: f64,
        /// Δa0.
        da0: f64,
    },
    /// The bilayer couple.
    Bc {
        /// The Δa held.
        da: f64,
    },
}

impl Couple {
    /// The scene's key and its object (`"ade": {...}` or `"bilayer_couple": {...}`).
    pub fn scene_entry(&self) -> (&'static str, serde_json::Value) {
        match *self {
            Couple::Ade { alpha, da0 } => ("ade", serde_json::json!({"alpha": alpha, "da0": da0})),
            Couple::Bc { da } => ("bilayer_couple", serde_json::json!({"da": da})),
        }
    }
}

/// Where a slice of a diagram sits: its reduced spontaneous curvature and, with an
/// area-difference term, its α and Δa0 or its Δa.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SliceAt {
    /// c̄0 = c0 R0.
    pub c0: f64,
    /// The area-difference term, if any.
    pub couple: Option<Couple>,
}

impl SliceAt {
    /// The value that orders and labels the slices: Δa0 (ADE), Δa (bilayer couple), else c̄0.
    pub fn value(&self) -> f64 {
        match self.couple {
            Some(Couple::Ade { da0, .. }) => da0,
            Some(Couple::Bc { da }) => da,
            None => self.c0,
        }
    }

    /// The slice's parameter as the tables head it: `c0R0`, `da0` or `da`.
    pub fn label(&self) -> &'static str {
        match self.couple {
            Some(Couple::Ade { .. }) => "da0",
            Some(Couple::Bc { .. }) => "da",
            None => "c0R0",
        }
    }

    /// The slice's folder name (`c0_0.50`, `da0_1.10`, `da_1.10`).
    pub fn folder(&self) -> String {
        match self.couple {
            Some(Couple::Ade { da0, .. }) => format!("da0_{}", c0_tag(da0)),
            Some(Couple::Bc { da }) => format!("da_{}", c0_tag(da)),
            None => format!("c0_{}", c0_tag(self.c0)),
        }
    }

    /// A few words for titles: `c0 R0 = 0.5`, `α = 1.4, Δa0 = 1.1`, `bilayer couple Δa = 1.1`
    /// (with c̄0 when not 0).
    pub fn describe(&self) -> String {
        let term = match self.couple {
            Some(Couple::Ade { alpha, da0 }) => format!("α = {alpha}, Δa0 = {da0}"),
            Some(Couple::Bc { da }) => format!("bilayer couple Δa = {da}"),
            None => return format!("c0 R0 = {}", self.c0),
        };
        if self.c0 == 0.0 {
            term
        } else {
            format!("{term}, c0 R0 = {}", self.c0)
        }
    }

    /// The name of the energy the slice compares: w with ADE, else e.
    pub fn energy_name(&self) -> &'static str {
        match self.couple {
            Some(Couple::Ade { .. }) => "w",
            _ => "e",
        }
    }
}

fn zero_c0() -> Vec<f64> {
    vec![0.0]
}
fn default_min_width() -> f64 {
    5.0
}

/// Largest ε|c0| = |c̄0|/(R0/ε) a resolution may have: the phase-field spontaneous-curvature
/// term εC0 = εc0/√2 must stay a small perturbation of the double well (its error is a power
/// of ε|c0|, not exponentially small).
pub const MAX_EPS_C0: f64 = 0.1;

fn one() -> f64 {
    1.0
}
fn default_margin() -> f64 {
    4.0
}
fn default_margin_r0() -> f64 {
    0.1
}
fn default_stop_residual() -> f64 {
    1e-6
}
fn default_max_iterations() -> usize {
    20_000
}
fn default_prepare_steps() -> usize {
    20
}

/// One case: a branch at a reduced volume, a reduced spontaneous curvature and a resolution.
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    /// Position in [`DiagramSpec::cases`] (the `--case` number).
    pub index: usize,
    /// The branch.
    pub branch: Branch,
    /// Reduced spontaneous curvature c̄0 = c0 R0.
    pub c0: f64,
    /// The area-difference term of an ADE or bilayer-couple diagram.
    pub couple: Option<Couple>,
    /// Target reduced volume (the axisymmetric start's).
    pub v: f64,
    /// R0/ε.
    pub r0: f64,
}

impl Case {
    /// Folder name of the case: `<index>_<branch>_v<v>_r<r0>` at c̄0 = 0 (the names of the
    /// c0 = 0 diagram), `<index>_<branch>_v<v>_c<c̄0>_r<r0>` otherwise (`c0.50`, `cm1.00`).
    pub fn folder(&self) -> String {
        let mut c0 = if self.c0 == 0.0 {
            String::new()
        } else {
            format!("_c{}", c0_tag(self.c0))
        };
        match self.couple {
            Some(Couple::Ade { da0, .. }) => c0 += &format!("_a{}", c0_tag(da0)),
            Some(Couple::Bc { da }) => c0 += &format!("_b{}", c0_tag(da)),
            None => {}
        }
        format!(
            "{:03}_{}_v{:.4}{c0}_r{}",
            self.index,
            self.branch.name(),
            self.v,
            self.r0
        )
    }

    /// c0 of the scene, in units of ε: c̄0 / (R0/ε).
    pub fn scene_c0(&self) -> f64 {
        self.c0 / self.r0
    }

    /// The slice the case belongs to.
    pub fn slice(&self) -> SliceAt {
        SliceAt {
            c0: self.c0,
            couple: self.couple,
        }
    }
}

/// `c̄0` as it appears in folder names (`-0.5` → `m0.50`).
pub use crate::commands::axisym::phase::c0_tag;

/// The branches a diagram may list, in its order: those of c0 = 0 and, in an ADE or
/// bilayer-couple diagram, the pear.
pub const BRANCHES: [Branch; 4] = Branch::WITH_PEAR;

/// The branch called `name`.
pub fn branch_named(name: &str) -> Option<Branch> {
    BRANCHES.into_iter().find(|b| b.name() == name)
}

impl DiagramSpec {
    /// Read and check a diagram file.
    ///
    /// # Errors
    /// `Error::Config` naming the key: unreadable file, malformed JSON, unknown key, wrong
    /// type, or a value [`DiagramSpec::validate`] refuses.
    pub fn load(path: &Path) -> Result<Self> {
        let bytes = std::fs::read(path).map_err(|e| {
            Error::config(
                "(diagram file)",
                format!("{} cannot be read: {e}", path.display()),
            )
        })?;
        let mut de = serde_json::Deserializer::from_slice(&bytes);
        let spec: DiagramSpec = serde_path_to_error::deserialize(&mut de).map_err(|e| {
            let at = e.path().to_string();
            let field = if at == "." || at == "?" {
                "(file)".to_string()
            } else {
                at
            };
            Error::config(field, e.inner().to_string())
        })?;
        spec.validate()?;
        Ok(spec)
    }

    /// Check every value.
    ///
    /// # Errors
    /// `Error::Config` naming the key and the reason.
    pub fn validate(&self) -> Result<()> {
        self.validate_c0()?;
        self.validate_ade()?;
        self.validate_by_da()?;
        for slice in self.slices() {
            let (key, branches) = self.branches_at(slice);
            let Some(branches) = branches else {
                let by = if slice.couple.is_some() {
                    "branches_by_da"
                } else {
                    "branches_by_c0"
                };
                return Err(Error::config(
                    "branches",
                    format!(
                        "list the branches of {} (here or in {by})",
                        slice.describe()
                    ),
                ));
            };
            validate_branches(&key, branches, slice)?;
        }
        if self.r0.len() < 2 {
            return Err(Error::config(
                "r0",
                "give at least two R0/ε to extrapolate in ε/R0",
            ));
        }
        if let Some(r) = self.r0.iter().find(|r| !(**r >= 6.0 && **r <= 200.0)) {
            return Err(Error::config(
                "r0",
                format!("need 6 ≤ R0/ε ≤ 200 (the interface must be thin), got {r}"),
            ));
        }
        let mut r0 = self.r0.clone();
        r0.sort_by(f64::total_cmp);
        if r0.windows(2).any(|w| w[1] - w[0] < 1e-6) {
            return Err(Error::config("r0", "resolutions must be distinct"));
        }
        let positive = [
            ("eps_over_h", self.eps_over_h, 0.5, 4.0),
            ("margin", self.margin, 2.0, 50.0),
            ("margin_r0", self.margin_r0, 0.0, 2.0),
            ("stop_residual", self.stop_residual, 1e-12, 1e-2),
            ("min_width", self.min_width, 0.0, 50.0),
        ];
        for (key, value, lo, hi) in positive {
            if !(value >= lo && value <= hi) {
                return Err(Error::config(
                    key,
                    format!("need {lo} ≤ {key} ≤ {hi}, got {value}"),
                ));
            }
        }
        if self.max_iterations == 0 {
            return Err(Error::config("max_iterations", "must be at least 1"));
        }
        let (c0, r0) = (
            self.c0.iter().fold(0.0f64, |m, c| m.max(c.abs())),
            self.coarsest(),
        );
        if c0 / r0 > MAX_EPS_C0 {
            return Err(Error::config(
                "c0",
                format!(
                    "|c0| = {c0} at the coarsest R0 = {r0} ε is ε|c0| = {:.3} > {MAX_EPS_C0}: \
                     raise r0 to at least {} or lower |c0|",
                    c0 / r0,
                    c0 / MAX_EPS_C0
                ),
            ));
        }
        Ok(())
    }

    /// `ade`: α > 0 finite, distinct Δa0 in (0, 3); `bilayer_couple`: distinct Δa in (0, 3);
    /// not both; one c̄0 with either.
    fn validate_ade(&self) -> Result<()> {
        let (key, values) = match (&self.ade, &self.bilayer_couple) {
            (None, None) => return Ok(()),
            (Some(_), Some(_)) => {
                return Err(Error::config(
                    "bilayer_couple",
                    "give ade or bilayer_couple, not both",
                ))
            }
            (Some(a), None) => {
                if !(a.alpha > 0.0 && a.alpha <= 1e3) {
                    return Err(Error::config(
                        "ade.alpha",
                        format!("need 0 < α ≤ 1000, got {}", a.alpha),
                    ));
                }
                ("ade.da0", &a.da0)
            }
            (None, Some(b)) => ("bilayer_couple.da", &b.da),
        };
        if values.is_empty() {
            return Err(Error::config(key, "list at least one value"));
        }
        if let Some(d) = values.iter().find(|d| !(**d > 0.0 && **d < 3.0)) {
            return Err(Error::config(
                key,
                format!("need values in (0, 3), got {d}"),
            ));
        }
        let mut sorted = values.clone();
        sorted.sort_by(f64::total_cmp);
        if sorted.windows(2).any(|w| w[1] - w[0] < 1e-6) {
            return Err(Error::config(key, "values must be distinct"));
        }
        if self.c0.len() != 1 {
            return Err(Error::config(
                "c0",
                format!("a diagram of {key} takes one c0 (its slices are the values of {key})"),
            ));
        }
        Ok(())
    }

    /// The slices in increasing order of their value: each c̄0, or each Δa0 (ADE) or Δa
    /// (bilayer couple) at the one c̄0.
    pub fn slices(&self) -> Vec<SliceAt> {
        let sorted = |v: &[f64]| {
            let mut v = v.to_vec();
            v.sort_by(f64::total_cmp);
            v
        };
        let at = |couple| SliceAt {
            c0: self.c0[0],
            couple: Some(couple),
        };
        match (&self.ade, &self.bilayer_couple) {
            (Some(a), _) => sorted(&a.da0)
                .into_iter()
                .map(|da0| {
                    at(Couple::Ade {
                        alpha: a.alpha,
                        da0,
                    })
                })
                .collect(),
            (None, Some(b)) => sorted(&b.da)
                .into_iter()
                .map(|da| at(Couple::Bc { da }))
                .collect(),
            (None, None) => self
                .c0_sorted()
                .into_iter()
                .map(|c0| SliceAt { c0, couple: None })
                .collect(),
        }
    }

    /// The `c0` list: distinct finite values, `branches_by_c0` keys among them.
    fn validate_c0(&self) -> Result<()> {
        if self.c0.is_empty() {
            return Err(Error::config("c0", "list at least one value"));
        }
        if let Some(c) = self.c0.iter().find(|c| !(c.is_finite() && c.abs() <= 10.0)) {
            return Err(Error::config(
                "c0",
                format!("need finite values with |c0| ≤ 10, got {c}"),
            ));
        }
        let mut sorted = self.c0.clone();
        sorted.sort_by(f64::total_cmp);
        if sorted.windows(2).any(|w| w[1] - w[0] < 1e-6) {
            return Err(Error::config("c0", "values must be distinct"));
        }
        for key in self.branches_by_c0.keys() {
            let at = format!("branches_by_c0.{key}");
            let Ok(c) = key.parse::<f64>() else {
                return Err(Error::config(
                    at,
                    "the key must be a number (a value of c0)",
                ));
            };
            if !self.c0.contains(&c) {
                return Err(Error::config(at, format!("{c} is not listed in c0")));
            }
        }
        Ok(())
    }

    /// `branches_by_da`: only with `ade` or `bilayer_couple`, each key a number among the
    /// slice values (Δa0 or Δa).
    fn validate_by_da(&self) -> Result<()> {
        let values: Vec<f64> = match (&self.ade, &self.bilayer_couple) {
            (Some(a), _) => a.da0.clone(),
            (None, Some(b)) => b.da.clone(),
            (None, None) => Vec::new(),
        };
        for key in self.branches_by_da.keys() {
            let at = format!("branches_by_da.{key}");
            if values.is_empty() {
                return Err(Error::config(
                    at,
                    "branches_by_da needs ade or bilayer_couple (its keys are their values)",
                ));
            }
            let Ok(x) = key.parse::<f64>() else {
                return Err(Error::config(
                    at,
                    "the key must be a number (a value of ade.da0 or bilayer_couple.da)",
                ));
            };
            if !values.contains(&x) {
                return Err(Error::config(
                    at,
                    format!("{x} is not a slice value (ade.da0 or bilayer_couple.da)"),
                ));
            }
        }
        Ok(())
    }

    /// The branches of the slice `at` and the key they come from: `branches_by_da.<Δa>` (an
    /// ADE or bilayer-couple slice), `branches_by_c0.<c0>` (a c̄0 slice) or `branches`.
    pub fn branches_at(&self, at: SliceAt) -> (String, Option<&Branches>) {
        let (name, map, value) = match at.couple {
            Some(_) => ("branches_by_da", &self.branches_by_da, at.value()),
            None => ("branches_by_c0", &self.branches_by_c0, at.c0),
        };
        match map
            .iter()
            .find(|(k, _)| k.parse::<f64>().ok() == Some(value))
        {
            Some((k, b)) => (format!("{name}.{k}"), Some(b)),
            None => (
                "branches".to_string(),
                (!self.branches.is_empty()).then_some(&self.branches),
            ),
        }
    }

    /// The key that lists `case`'s branch at its c̄0 (`branches.prolate`,
    /// `branches_by_c0.-1.oblate`).
    pub fn key_of(&self, case: &Case) -> String {
        format!(
            "{}.{}",
            self.branches_at(case.slice()).0,
            case.branch.name()
        )
    }

    /// Every case, numbered: the slices (c̄0, or Δa0) in increasing order, in each the branches in diagram order
    /// (prolate, oblate, stomatocyte), each reduced volume in increasing order, each resolution
    /// in increasing R0.
    pub fn cases(&self) -> Vec<Case> {
        let mut r0 = self.r0.clone();
        r0.sort_by(f64::total_cmp);
        let mut out = Vec::new();
        for slice in self.slices() {
            let SliceAt { c0, couple } = slice;
            let Some(branches) = self.branches_at(slice).1 else {
                continue;
            };
            for branch in BRANCHES {
                let Some(vs) = branches.get(branch.name()) else {
                    continue;
                };
                let mut vs = vs.clone();
                vs.sort_by(f64::total_cmp);
                for &v in &vs {
                    for &r in &r0 {
                        out.push(Case {
                            index: out.len(),
                            branch,
                            c0,
                            couple,
                            v,
                            r0: r,
                        });
                    }
                }
            }
        }
        out
    }

    /// The c̄0 values in increasing order.
    pub fn c0_sorted(&self) -> Vec<f64> {
        let mut c0 = self.c0.clone();
        c0.sort_by(f64::total_cmp);
        c0
    }

    /// The smallest R0/ε (the coarsest resolution).
    pub fn coarsest(&self) -> f64 {
        self.r0.iter().cloned().fold(f64::INFINITY, f64::min)
    }

    /// The largest R0/ε (the finest resolution).
    pub fn finest(&self) -> f64 {
        self.r0.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
    }
}

/// Check the reduced volumes `branches` listed under `key` for `slice`: known branches
/// (the pear only with ADE or the bilayer couple, whose references solve each listed branch),
/// non-empty distinct lists, inside the range where the branch is computed (at c̄0 = 0 the
/// ranges of the c0 = 0 diagram; elsewhere, and for the pear, (0.3, 1), the start shape's
/// solve refusing a volume the branch does not reach).
fn validate_branches(key: &str, branches: &Branches, slice: SliceAt) -> Result<()> {
    let c0 = slice.c0;
    if branches.is_empty() {
        return Err(Error::config(key, "list at least one branch"));
    }
    let known = if slice.couple.is_some() {
        "prolate, oblate, stomatocyte or pear"
    } else {
        "prolate, oblate or stomatocyte; the pear with ade or bilayer_couple"
    };
    for (name, vs) in branches {
        let at = format!("{key}.{name}");
        let listable = |b: &Branch| *b != Branch::Pear || slice.couple.is_some();
        let Some(branch) = branch_named(name).filter(listable) else {
            return Err(Error::config(at, format!("unknown branch ({known})")));
        };
        let (lo, hi) = match branch {
            Branch::Pear => (0.3, 1.0),
            _ if c0 != 0.0 => (0.3, 1.0),
            Branch::Prolate => (0.3, 1.0),
            Branch::Oblate => (0.51, 1.0),
            Branch::Stomatocyte => (0.3, 0.66),
        };
        if vs.is_empty() {
            return Err(Error::config(at, "list at least one reduced volume"));
        }
        if let Some(v) = vs.iter().find(|v| !(**v > lo && **v < hi)) {
            return Err(Error::config(
                at,
                format!("the {name} branch is computed for {lo} < v < {hi}, got {v}"),
            ));
        }
        let mut sorted = vs.clone();
        sorted.sort_by(f64::total_cmp);
        if sorted.windows(2).any(|w| w[1] - w[0] < 1e-6) {
            return Err(Error::config(at, "reduced volumes must be distinct"));
        }
    }
    Ok(())
}
