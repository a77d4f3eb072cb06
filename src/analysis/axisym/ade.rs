//! The area-difference-elasticity (ADE) model: its stationary shapes at fixed `v` as the image
//! of the bilayer-couple branches ([`super::bc`]) under `Δa0 = Δa + (c̄0,eff − c̄0)/(2πα)`
//! ([`super::model`]), and [`ade_solution`], which solves the ADE functional itself by Newton
//! from that image.
//!
//! Along a BC branch at fixed `v`, `w(Δa; Δa0) = e_BC(Δa) + πα(Δa − Δa0)²` is stationary in
//! `Δa` where `de_BC/dΔa = c̄0,eff − c̄0 = 2πα(Δa0 − Δa)`, and
//! `d²w/dΔa² = dc̄0,eff/dΔa + 2πα = 2πα dΔa0/dΔa`: the ADE shape is stable against changes
//! of `Δa` (within its branch) where the image runs forward, `dΔa0/dΔa > 0`, and a maximum of
//! `w(Δa)` where it folds back. Where the image folds, two stable shapes of one branch coexist
//! at the same `Δa0` (a discontinuous transition within the branch).

use super::bc::{basis_of, bc_curve};
use super::map::reproject;
use super::solver::{newton, NewtonSettings};
use super::{ade_da0, solution, Branch, Model, Options, Solution};
use crate::error::{Error, Result};

/// One BC shape seen in the ADE model of `α` and `c̄0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdePoint {
    /// The preferred area difference at which the shape is a stationary ADE shape.
    pub da0: f64,
    /// Its area difference `Δa`.
    pub da: f64,
    /// Its ADE energy `w = e + πα(Δa − Δa0)²`.
    pub w: f64,
    /// Its bending energy `e` at `c̄0`.
    pub e: f64,
    /// `c̄0,eff = c̄0 + 2πα(Δa0 − Δa)`, the BC shape's own `c̄0,eff`.
    pub c0_eff: f64,
    /// Whether the image runs forward there (`dΔa0/dΔa > 0`, from the neighbours): a local
    /// minimum of `w` in `Δa`.
    pub stable: bool,
}

/// The ADE image of a BC curve (shapes in increasing `Δa`, computed at the `c̄0` of the ADE
/// model) for `α > 0`: one [`AdePoint`] per shape, in the same order.
pub fn ade_image(shapes: &[Solution], alpha: f64) -> Vec<AdePoint> {
    let da0: Vec<f64> = shapes
        .iter()
        .map(|s| ade_da0(s.c0, alpha, s.da(), s.c0_eff))
        .collect();
    let n = shapes.len();
    shapes
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let (l, r) = (i.saturating_sub(1), (i + 1).min(n - 1));
            let slope = if r > l {
                (da0[r] - da0[l]) / (shapes[r].da() - shapes[l].da())
            } else {
                1.0
            };
            AdePoint {
                da0: da0[i],
                da: s.da(),
                w: Model::Ade { alpha, da0: da0[i] }.energy(s.e, s.da()),
                e: s.e,
                c0_eff: s.c0_eff,
                stable: slope > 0.0,
            }
        })
        .collect()
}

/// The `Δa` window over which the BC branches are followed for their ADE image (by
/// [`ade_solution`] and the ADE diagram): wide enough that the image, `Δa0 − Δa =
/// (c̄0,eff − c̄0)/2πα`, covers the diagrams' `Δa0`.
pub const ADE_WINDOW: (f64, f64) = (0.0, 2.5);

/// The stationary ADE shape of `branch` at reduced volume `v`, `α = alpha`, preferred area
/// difference `da0` and spontaneous curvature `opts.c0`: the BC branch at `v` is followed over
/// [`ADE_WINDOW`] (the whole path, as the ADE diagram follows it: the image folds, and a path
/// that leaves `da0` can cover it again further on, as the prolate budding at both poles does
/// at v = 0.86–0.90 near Δa0 = 1.9); of the stable pieces that cover `da0`, the one of lowest
/// `w` gives the start (interpolated between its two BC shapes), from which Newton solves the ADE
/// functional (at fixed `v`, closure held for the asymmetric branches). The result has
/// [`Solution::model`] `Ade`, `w`, `e`, `Δa` ([`Solution::da`]) and `c̄0,eff`.
///
/// # Errors
/// `Error::Config` (field `alpha`) unless `α > 0` and finite; (field `v`) for `v ∉ (0, 1)`;
/// (field `da0`) if no stable shape of the branch has this `Δa0` at `v`, or Newton fails.
pub fn ade_solution(
    branch: Branch,
    v: f64,
    alpha: f64,
    da0: f64,
    opts: &Options,
) -> Result<Solution> {
    if !(alpha > 0.0 && alpha.is_finite()) {
        return Err(Error::config(
            "alpha",
            format!("need 0 < α < ∞, got {alpha}"),
        ));
    }
    if !(v > 0.0 && v < 1.0) {
        return Err(Error::config("v", format!("need 0 < v < 1, got {v}")));
    }
    if !da0.is_finite() {
        return Err(Error::config("da0", format!("must be finite, got {da0}")));
    }
    let bc = opts.with_model(Model::Sc);
    let curve = bc_curve(branch, v, ADE_WINDOW, &bc);
    let img = ade_image(&curve.shapes, alpha);
    let best = img
        .windows(2)
        .enumerate()
        .filter(|(_, p)| p[0].stable && p[1].stable && (p[0].da0 - da0) * (p[1].da0 - da0) <= 0.0)
        .map(|(i, p)| {
            let f = (da0 - p[0].da0) / (p[1].da0 - p[0].da0);
            (i, f, p[0].w + f * (p[1].w - p[0].w))
        })
        .min_by(|a, b| a.2.total_cmp(&b.2))
        .ok_or_else(|| {
            Error::config(
                "da0",
                format!(
                    "no stable {} shape at v = {v} has Δa0 = {da0} (α = {alpha})",
                    branch.name()
                ),
            )
        })?;
    let (i, f, _) = best;
    let (s0, s1) = (&curve.shapes[i], &curve.shapes[i + 1]);
    // Both in the coordinates of s0's map (a map changes as a neck narrows).
    let a1 = reproject(&s1.coefficients, &s1.map, &s0.map, &s1.modes);
    let a0: Vec<f64> = s0
        .coefficients
        .iter()
        .zip(&a1)
        .map(|(x, y)| x + f * (y - x))
        .collect();
    let model = Model::Ade { alpha, da0 };
    let basis = basis_of(branch, &opts.with_model(model)).with_map(s0.map);
    let set = NewtonSettings {
        tol: opts.tol,
        max_iter: opts.max_iter,
        max_step: 0.5,
    };
    let c = newton(&basis, &a0, v, !branch.up_down_symmetric(), &set)
        .ok_or_else(|| Error::config("da0", format!("Newton failed at Δa0 = {da0}, v = {v}")))?;
    Ok(solution(branch, &basis, &c))
}
