//! The spectral step's passes on the CPU ([`CpuPasses`]): the update and area-quadratic sweeps
//! over the spectrum, piece by piece ([`super::pieces`]), and the evaluation of the new state
//! ([`Evaluator`]). [`SpectralEngine`] is the shared [`Stepper`] on them; the update's formula
//! is in [`super::update`].

use super::curvature::{add_couple, couple_sums, CoupleInputs, CoupleSums};
use super::evaluator::{axis_symbol, write_inverse_value, Evaluator, ExplicitTerm, State};
use super::flow::FlowStats;
use super::inextensible::Inextensibility;
use super::kernels::{sum, wide_fn};
use super::pieces::{for_each_piece, mode, per_width, re_dot, reals, reals_mut, Piece, PIECE};
use super::saved::spectrum;
use super::stepper::{
    DeviceFailure, DeviceState, Evaluation, Passes, SavedSpectra, States, Stepper,
};
use super::tensions::Replay;
use super::update::{Update, MAX_LEVELS};
use crate::engines::numerics::sum_in_fixed_tree;
use crate::engines::{Diverged, Saved, SavedArray};
use crate::problem::area_difference::AreaDifference;
use crate::problem::config::{AreaMethod, Laplacian, Scene, Stabilizer};
use crate::problem::grid::Grid;
use crate::problem::model::{Measures, C0};
use ndarray::{Array3, CowArray, Ix3};
use num_complex::Complex64;
use rayon::prelude::*;

// The sweeps read at most two levels of history (φ̂ⁿ, N̂ⁿ and φ̂ⁿ⁻¹, N̂ⁿ⁻¹): a scheme with more
// levels extends [`values`] and [`Inputs`].
const _: () = assert!(MAX_LEVELS == 2);

/// The modes of a piece in the reals `inputs` = [φ̂ⁿ, N̂ⁿ, T̂ⁿ, φ̂ⁿ⁻¹, N̂ⁿ⁻¹, T̂ⁿ⁻¹] ([`Inputs`]),
/// as the first `L` levels of history, zipped with the piece's |k|² and w. Inputs the sweep does
/// not read (a second level with one, T̂ without a flow) may be any reals of the piece.
#[inline(always)]
fn values<'a, const W: usize, const L: usize>(
    p: &'a Piece,
    inputs: [&'a [f64]; 6],
) -> impl Iterator<Item = ([[&'a [f64; W]; 3]; L], (f64, f64))> + 'a {
    let [x, n, t, x0, n0, t0] = inputs.map(|v| p.modes::<W, _>(v).iter());
    x.zip(n)
        .zip(t)
        .zip(x0.zip(n0).zip(t0))
        .zip(p.symbols())
        .map(|((((x, n), t), ((x0, n0), t0)), kw)| {
            let levels = [[x, n, t], [x0, n0, t0]];
            (std::array::from_fn(|j| levels[j]), kw)
        })
}

wide_fn! {
/// One piece of [`CpuPasses::area_quadratic`], mode by mode from the piece's reals
/// `inputs` ([`values`]): with P̂, Q̂ of [`Update::at`] (Q̂ with the flow's T̂ when `FLOW`) and
/// the area weight a = (3/(2√2)) ε |k|² w, returns (A_PP, A_PQ, A_QQ) = Σ a (|P̂|², Re P̂Q̂*,
/// |Q̂|²). Each mode's factors are formed and used at once (`t` scratch for its three terms).
fn quadratic_values<const L: usize, const W: usize, const FLOW: bool>(
    u: &Update,
    p: &Piece,
    area_prefactor: f64,
    inputs: [&[f64]; 6],
    t: &mut [[f64; PIECE]; 3],
) -> [f64; 3] {
    let len = p.len;
    let [tpp, tpq, tqq] = t;
    let terms = tpp[..len].iter_mut().zip(&mut tpq[..len]).zip(&mut tqq[..len]);
    for (((pp, pq), qq), (v, (k, w))) in terms.zip(values::<W, L>(p, inputs)) {
        let (pv, qv) = u.at::<L>(k).apply::<W, FLOW>(v);
        let aw = area_prefactor * k * w;
        *pp = aw * re_dot(pv, pv);
        *pq = aw * re_dot(pv, qv);
        *qq = aw * re_dot(qv, qv);
    }
    [sum(&tpp[..len]), sum(&tpq[..len]), sum(&tqq[..len])]
}
}

wide_fn! {
/// One piece of [`CpuPasses::write_update`], mode by mode: φ̂^{n+1} = P̂ + σQ̂ (Q̂ with the
/// flow's T̂ when `FLOW`) into `hat`, and the inverse transforms' inputs
/// ([`write_inverse_value`]) into `copy` and `lap`; returns the piece's area (`t` scratch for
/// each mode's term).
fn write_values<const L: usize, const W: usize, const FLOW: bool>(
    u: &Update,
    p: &Piece,
    area_prefactor: f64,
    sigma: f64,
    inputs: [&[f64]; 6],
    out: [&mut [f64]; 3],
    t: &mut [f64; PIECE],
) -> f64 {
    let [hat, copy, lap] = out.map(|o| p.modes_mut::<W, _>(o).iter_mut());
    let outputs = hat.zip(copy.zip(lap)).zip(&mut t[..p.len]);
    for (((hat, (copy, lap)), term), (v, (k, w))) in outputs.zip(values::<W, L>(p, inputs)) {
        let (pv, qv) = u.at::<L>(k).apply::<W, FLOW>(v);
        *hat = mode(|c| pv[c] + sigma * qv[c]);
        *term = write_inverse_value(*hat, k, area_prefactor * k * w, copy, lap);
    }
    sum(&t[..p.len])
}
}

/// φ̂ⁿ, N̂ⁿ, T̂ⁿ and (two levels) φ̂ⁿ⁻¹, N̂ⁿ⁻¹, T̂ⁿ⁻¹, as interleaved reals: T̂ the Stokes flow's
/// advection per unit σ of a flow split in σ ([`super::flow`]), kept as the state's second
/// spectrum.
#[derive(Clone, Copy)]
struct Inputs<'a> {
    cur: [&'a [f64]; 3],
    prev: Option<[&'a [f64]; 3]>,
}

impl<'a> Inputs<'a> {
    /// The inputs of an update from `cur` reading `levels` levels of history (`prev` and
    /// `prev_t` when two); T̂ with `flow`.
    fn new(
        cur: &'a State,
        (prev, prev_t): (
            Option<&'a [Array3<Complex64>; 2]>,
            Option<&'a Array3<Complex64>>,
        ),
        levels: usize,
        flow: bool,
    ) -> Self {
        // Without a flow T̂ is not read: φ̂ stands in for it.
        let second = |h: &'a Array3<Complex64>, t: Option<&'a Array3<Complex64>>| match flow {
            true => flat(t.expect("a flow split in σ keeps T̂ at every level")),
            false => flat(h),
        };
        Inputs {
            cur: [
                flat(&cur.hat),
                flat(&cur.nonlinear),
                second(&cur.hat, Some(&cur.curvature_hat)),
            ],
            prev: prev
                .filter(|_| levels > 1)
                .map(|[h, n]| [flat(h), flat(n), second(h, prev_t)]),
        }
    }

    /// The reals `range` of φ̂ⁿ, N̂ⁿ, T̂ⁿ, φ̂ⁿ⁻¹, N̂ⁿ⁻¹, T̂ⁿ⁻¹ (without a previous step the last
    /// three are those of the current one again: the one-level sweeps do not read them).
    #[inline]
    fn reals(&self, range: std::ops::Range<usize>) -> [&'a [f64]; 6] {
        let [h, n, t] = self.cur.map(|v| &v[range.clone()]);
        let [h0, n0, t0] = self
            .prev
            .map_or([h, n, t], |p| p.map(|v| &v[range.clone()]));
        [h, n, t, h0, n0, t0]
    }
}

/// A spectrum as interleaved reals.
fn flat(a: &Array3<Complex64>) -> &[f64] {
    reals(a.as_slice().expect("standard layout"))
}

/// The area-difference term's inputs of an update reading `levels` levels: (φ̂, N̂, m̂) of the
/// current state `cur` and, with two, of the one before (`prev`, `prev_curvature`)
/// ([`CoupleInputs`]).
fn couple_inputs<'a>(
    cur: &'a State,
    prev: Option<&'a [Array3<Complex64>; 2]>,
    prev_curvature: Option<&'a Array3<Complex64>>,
    levels: usize,
) -> CoupleInputs<'a> {
    let mut inputs = vec![[
        flat(&cur.hat),
        flat(&cur.nonlinear),
        flat(&cur.curvature_hat),
    ]];
    if levels > 1 {
        let [h, n] = prev.expect("two levels need the history");
        let m = prev_curvature.expect("and its m̂");
        inputs.push([flat(h), flat(n), flat(m)]);
    }
    CoupleInputs { levels: inputs }
}

/// Frozen-coefficient stability bound of the semi-implicit step at σ = 0:
/// with the bulk linearisation −2k²(2 + ε²k²)² split into implicit b = 2ε⁴k⁶ + S and explicit
/// a = 8k² + 8ε²k⁴, the amplification (1 + Δt(S − a))/(1 + Δt(b + S)) stays in [−1, 1] for
/// Δt ≤ 2 / max_k (a − b − 2S). Infinite when a − b − 2S ≤ 0 for every k (e.g. S ≥ a/2).
pub fn stability_bound(grid: &Grid, eps: f64, s: &Stabilizer, laplacian: Laplacian) -> f64 {
    let k2_max: f64 = (0..3)
        .filter(|&a| grid.shape[a] > 1)
        .map(|_| axis_symbol(std::f64::consts::PI / grid.h, grid.h, laplacian))
        .sum();
    let e2 = eps * eps;
    let worst = (0..=4000)
        .map(|i| {
            let k2 = k2_max * i as f64 / 4000.0;
            let a = 8.0 * k2 + 8.0 * e2 * k2 * k2;
            let b = 2.0 * e2 * e2 * k2 * k2 * k2;
            let stab = s.s2 * k2 + s.s4 * e2 * k2 * k2;
            a - b - 2.0 * stab
        })
        .fold(0.0f64, f64::max);
    if worst > 0.0 {
        2.0 / worst
    } else {
        f64::INFINITY
    }
}

/// The spectral conserved flow on the CPU.
pub type SpectralEngine = Stepper<CpuPasses>;

impl SpectralEngine {
    /// Engine holding `phi` at t = 0, no area constraint yet.
    ///
    /// # Errors
    /// [`Diverged`] if `phi` is not finite.
    pub fn new(scene: &Scene, grid: Grid, c0: C0, phi: Array3<f64>) -> Result<Self, Diverged> {
        let c0_ramped = c0.is_ramped();
        let mut ev = Evaluator::new(
            grid,
            scene.eps,
            c0,
            scene.laplacian,
            ExplicitTerm::ConservedRhs,
            scene.threads(),
        );
        if scene.ade.is_some() || scene.bilayer_couple.is_some() {
            ev = ev.with_curvature();
        }
        // A fixed tension acts from the first step (the flow's force holds it).
        let sigma = match scene.area_method() {
            AreaMethod::Fixed => scene.area.sigma.unwrap_or(0.0),
            _ => 0.0,
        };
        if let Some(flow) = scene.stokes_flow() {
            ev = ev.with_flow(flow);
            if scene.area_method() == AreaMethod::Fixed {
                ev = ev.with_fixed_tension(sigma);
            }
        }
        let cur = ev.state_at(&phi, 0.0, sigma)?;
        let passes = CpuPasses {
            states: States::new(cur, ev.blank()),
            ev,
            prev_curvature: None,
        };
        Ok(Stepper::with_passes(passes, scene, c0_ramped))
    }
}

/// The spectral step's passes on the CPU: the states and the evaluator (transforms, tables,
/// scratch).
pub struct CpuPasses {
    ev: Evaluator,
    states: States<State>,
    /// m̂ⁿ⁻¹ of the area-difference term, beside the history of two-level schemes.
    prev_curvature: Option<Array3<Complex64>>,
}

impl DeviceState for State {
    type Spectrum = Array3<Complex64>;

    fn measures(&self) -> Measures {
        self.measures
    }

    fn residual(&self) -> f64 {
        self.residual
    }

    fn spectra(&self) -> [&Array3<Complex64>; 2] {
        [&self.hat, &self.nonlinear]
    }

    fn spectra_mut(&mut self) -> [&mut Array3<Complex64>; 2] {
        [&mut self.hat, &mut self.nonlinear]
    }
}

impl CpuPasses {
    /// [`Passes::area_quadratic`] reading `L` levels of history.
    fn area_quadratic_with<const L: usize, const FLOW: bool>(&self, u: &Update) -> [f64; 3] {
        let history = (self.states.prev.as_ref(), self.prev_curvature.as_ref());
        let inputs = Inputs::new(&self.states.cur, history, L, FLOW);
        let sym = &self.ev.symbols;
        let (task, total) = (sym.task_reals(), 2 * self.states.cur.hat.len());
        let partials = (0..total.div_ceil(task)).into_par_iter().map(|t| {
            let mut acc = [0.0; 3];
            let mut terms = [[0.0; PIECE]; 3];
            let (a, len) = (sym.area_prefactor, task.min(total - t * task));
            for_each_piece(sym, t, len, |p, at| {
                let x = inputs.reals(t * task + at..t * task + at + p.reals());
                let s =
                    per_width!(sym, W => quadratic_values::<L, W, FLOW>(u, p, a, x, &mut terms));
                acc = [acc[0] + s[0], acc[1] + s[1], acc[2] + s[2]];
            });
            acc
        });
        sum_in_fixed_tree(
            partials,
            || [0.0; 3],
            |a, b| [a[0] + b[0], a[1] + b[1], a[2] + b[2]],
        )
    }

    /// [`Passes::write_update`] reading `L` levels of history: φ̂^{n+1} into `next.hat`, its
    /// copy into `next.nonlinear` and −|k|²φ̂^{n+1} into the evaluator's spare (see
    /// [`Evaluator::finish`]).
    fn write_update_with<const L: usize, const FLOW: bool>(
        &mut self,
        u: &Update,
        sigma: f64,
    ) -> f64 {
        let States { cur, next, prev } = &mut self.states;
        let inputs = Inputs::new(cur, (prev.as_ref(), self.prev_curvature.as_ref()), L, FLOW);
        let sym = &self.ev.symbols;
        let task = sym.task_reals();
        let hat = reals_mut(next.hat.as_slice_mut().expect("standard layout"));
        let copy = reals_mut(next.nonlinear.as_slice_mut().expect("standard layout"));
        let lap = reals_mut(self.ev.spare.as_slice_mut().expect("standard layout"));
        hat.par_chunks_mut(task)
            .zip(copy.par_chunks_mut(task))
            .zip(lap.par_chunks_mut(task))
            .enumerate()
            .with_max_len(1)
            .map(|(t, ((hat, copy), lap))| {
                let mut terms = [0.0; PIECE];
                let mut area = 0.0;
                for_each_piece(sym, t, hat.len(), |p, at| {
                    let r = at..at + p.reals();
                    let x = inputs.reals(t * task + r.start..t * task + r.end);
                    let out = [&mut hat[r.clone()], &mut copy[r.clone()], &mut lap[r]];
                    let a = sym.area_prefactor;
                    area += per_width!(sym, W => {
                        write_values::<L, W, FLOW>(u, p, a, sigma, x, out, &mut terms)
                    });
                });
                area
            })
            .sum()
    }
}

impl Passes for CpuPasses {
    type State = State;

    fn grid(&self) -> &Grid {
        &self.ev.grid
    }

    fn states(&self) -> &States<State> {
        &self.states
    }

    fn phi(&self) -> &Array3<f64> {
        &self.states.cur.phi
    }

    fn area_quadratic(&self, u: &Update) -> Result<[f64; 3], DeviceFailure> {
        Ok(match (u.levels(), self.ev.splits_flow()) {
            (1, false) => self.area_quadratic_with::<1, false>(u),
            (1, true) => self.area_quadratic_with::<1, true>(u),
            (_, false) => self.area_quadratic_with::<2, false>(u),
            (_, true) => self.area_quadratic_with::<2, true>(u),
        })
    }

    fn write_update(&mut self, u: &Update, sigma: f64) -> Result<f64, DeviceFailure> {
        Ok(match (u.levels(), self.ev.splits_flow()) {
            (1, false) => self.write_update_with::<1, false>(u, sigma),
            (1, true) => self.write_update_with::<1, true>(u, sigma),
            (_, false) => self.write_update_with::<2, false>(u, sigma),
            (_, true) => self.write_update_with::<2, true>(u, sigma),
        })
    }

    fn set_mean_mode(&mut self, value: f64) -> Result<(), DeviceFailure> {
        let next = &mut self.states.next;
        next.hat[[0, 0, 0]].re = value;
        next.nonlinear[[0, 0, 0]].re = value;
        Ok(())
    }

    fn finish_next(&mut self, area: f64, t: f64, sigma: f64) -> Evaluation {
        let States { cur, next, .. } = &mut self.states;
        Ok(self.ev.finish(next, area, t, Some(&cur.phi), Some(sigma)))
    }

    fn accept(&mut self, keep_history: bool) -> Result<(), DeviceFailure> {
        self.states.accept(keep_history, |s| Ok(s.clone()))?;
        if let Some(constraint) = self.ev.inextensibility() {
            constraint.accept();
        }
        if keep_history && self.ev.has_second_term() {
            let old = &mut self.states.next.curvature_hat;
            match &mut self.prev_curvature {
                Some(m) => std::mem::swap(m, old),
                None => self.prev_curvature = Some(old.clone()),
            }
        }
        Ok(())
    }

    fn spectra(&self) -> (SavedArray<'_>, Option<[SavedArray<'_>; 2]>) {
        fn complex(a: &Array3<Complex64>) -> SavedArray<'_> {
            SavedArray::Complex(a.view().into())
        }
        let history = self
            .states
            .prev
            .as_ref()
            .map(|[h, n]| [complex(h), complex(n)]);
        (complex(&self.states.cur.hat), history)
    }

    fn flow_arrays(&self) -> Vec<(String, SavedArray<'_>)> {
        self.ev
            .inextensibility_ref()
            .map_or_else(Vec::new, Inextensibility::saved)
    }

    fn read_spectrum<'s>(
        &self,
        saved: &'s Saved<'_>,
        name: &str,
    ) -> Result<CowArray<'s, Complex64, Ix3>, String> {
        spectrum(saved, name, &self.ev.transform)
    }

    fn restore(&mut self, saved: SavedSpectra<'_, '_>, t: f64, sigma: f64) -> Result<(), String> {
        let SavedSpectra {
            hat,
            history,
            checkpoint,
        } = saved;
        self.states.cur.hat.assign(&hat);
        self.states.prev = history.map(|[h, n]| [h.into_owned(), n.into_owned()]);
        if let Some(constraint) = self.ev.inextensibility() {
            constraint.restore(checkpoint)?;
        }
        let replay = |ev: &mut Evaluator, which| {
            if let Some(constraint) = ev.inextensibility() {
                constraint.set_replay(which);
            }
        };
        // m̂ⁿ⁻¹ (or T̂ⁿ⁻¹) is not saved: it is evaluated again from φ̂ⁿ⁻¹, before the current
        // state, each with its own tension where the membrane is inextensible.
        self.prev_curvature = None;
        let second = self.ev.has_second_term();
        if let (true, Some([h, _])) = (second, &self.states.prev) {
            let mut before = self.ev.blank();
            before.hat.assign(h);
            replay(&mut self.ev, Some(Replay::Before));
            self.ev
                .evaluate(&mut before, t, None, None)
                .map_err(|d| d.0)?;
            self.prev_curvature = Some(before.curvature_hat);
        }
        replay(&mut self.ev, Some(Replay::Current));
        let evaluated = self.ev.evaluate(&mut self.states.cur, t, None, Some(sigma));
        replay(&mut self.ev, None);
        evaluated.map_err(|d| d.0)?;
        Ok(())
    }

    fn name(&self) -> &'static str {
        "spectral"
    }

    fn flow(&self) -> Option<FlowStats> {
        self.ev.has_flow().then_some(self.states.cur.flow)
    }

    fn set_area_difference(&mut self, term: AreaDifference) -> Result<(), DeviceFailure> {
        self.ev.area_difference = Some(term);
        Ok(())
    }

    fn couple_sums(&self, u: &Update) -> Result<CoupleSums, DeviceFailure> {
        let total = 2 * self.states.cur.hat.len();
        let (prev, prev_m) = (self.states.prev.as_ref(), self.prev_curvature.as_ref());
        let inputs = couple_inputs(&self.states.cur, prev, prev_m, u.levels());
        Ok(couple_sums(&self.ev.symbols, u, &inputs, total))
    }

    fn add_couple(&mut self, u: &Update, lambda: f64) -> Result<f64, DeviceFailure> {
        let States { cur, next, prev } = &mut self.states;
        let inputs = couple_inputs(cur, prev.as_ref(), self.prev_curvature.as_ref(), u.levels());
        let out = [
            reals_mut(next.hat.as_slice_mut().expect("standard layout")),
            reals_mut(next.nonlinear.as_slice_mut().expect("standard layout")),
            reals_mut(self.ev.spare.as_slice_mut().expect("standard layout")),
        ];
        Ok(add_couple(&self.ev.symbols, u, &inputs, lambda, out))
    }

    fn set_residual(&mut self, next: bool, sigma: f64, lambda: f64) -> Result<(), DeviceFailure> {
        let States { cur, next: n, .. } = &mut self.states;
        let state = if next { n } else { cur };
        state.residual = self.ev.residual_with(state, sigma, lambda);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engines::Engine;
    use serde_json::json;

    /// The area quadratic A(σ) = A_PP + 2σ A_PQ + σ² A_QQ of a step (SBDF1, and SBDF2 with its
    /// φ̂ⁿ⁻¹, N̂ⁿ⁻¹ terms) equals the area of the update written at that σ, to 1e-12 (relative),
    /// at σ = −0.3, 0, 0.7 on an odd-sized box (pieces filled unevenly): a term or a weight wrong
    /// in either sweep would miss by far more.
    #[test]
    fn area_quadratic_predicts_the_written_area() {
        for scheme in ["sbdf1", "sbdf2"] {
            let scene = json!({"dim": 3, "n": [21, 20, 23], "h": 1.0, "eps": 1.0,
                "method": "spectral", "scheme": scheme, "dt": 0.5, "max_steps": 3,
                "initial": {"shape": "ellipsoid", "axes": [7.0, 5.0, 5.0]}});
            let scene = crate::problem::config::from_value(scene).expect("scene");
            let pb = crate::problem::setup::build(&scene).expect("problem");
            let mut e = SpectralEngine::new(&scene, pb.grid, pb.c0, pb.phi).expect("engine");
            for n in 0..2 {
                e.step(n as f64 * 0.5, 0.5).expect("step");
            }
            let u = e.update(0.7);
            assert_eq!(u.levels(), if scheme == "sbdf2" { 2 } else { 1 });
            let passes = e.passes_mut();
            let [app, apq, aqq] = passes.area_quadratic(&u).expect("cpu");
            for sigma in [-0.3, 0.0, 0.7] {
                let predicted = app + 2.0 * sigma * apq + sigma * sigma * aqq;
                let written = passes.write_update(&u, sigma).expect("cpu");
                let rel = (predicted - written).abs() / written;
                assert!(
                    rel <= 1e-12,
                    "{scheme} σ {sigma}: {predicted} against {written}"
                );
            }
        }
    }
}
