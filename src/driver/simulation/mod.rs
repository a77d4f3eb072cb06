//! The simulation driver: the one owner of the step loop. A [`Simulation`] holds an engine, its
//! [`Clock`] and its observers' [`Timer`]s; [`Simulation::run`] steps until one of the
//! [`StopRules`] fires, the engine stalls, an [`Observer`] asks to stop, or a step fails, landing
//! exactly on `t_end` and on every due time of an observer's schedule on simulated time.
//! Observers (the time-series recorder, the progress bar, snapshot and checkpoint writers, the
//! studies' probes) see the initial state, every accepted step on which their schedule is due
//! (every step when they have none) and the end; the driver itself does no I/O.
//!
//! ```no_run
//! use vesicle::driver::simulation::{Simulation, StopRules};
//! let scene = vesicle::problem::config::load(std::path::Path::new("runs/ellipse2d.json"), &[]).unwrap();
//! let problem = vesicle::problem::setup::build(&scene).unwrap();
//! let (mut sim, _a0) = Simulation::of_scene(&scene, &problem).unwrap();
//! let stopped = sim.run(&StopRules::of(&scene), &mut []).unwrap();
//! println!("{}: e = {}", stopped.as_str(), sim.record().reduced_energy);
//! ```

mod start;
mod stop;

pub use start::{
    build_engine, check_engine, check_stability, constrain, stability_bound, Prepared,
};
pub use stop::{StopRules, Stopped};

use crate::driver::awake::KeepAwake;
use crate::driver::record::Record;
use crate::driver::schedule::Timer;
use crate::engines::{Engine, StepReport};
use crate::error::{Error, Result};
use crate::problem::config::Schedule;
use std::time::Instant;

/// Where a simulation is: accepted steps, time, the step to offer next, and counters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clock {
    /// Accepted steps.
    pub step: usize,
    /// Simulated time (nominal for the relaxational engine).
    pub t: f64,
    /// The step to offer the engine next (before landing on `t_end`).
    pub dt: f64,
    /// The step that produced the current state (0 for the initial state).
    pub last_dt: f64,
    /// max|Δφ|/Δt of the step that produced the current state (NaN for the initial state).
    pub last_rate: f64,
    /// Rejected attempts in all.
    pub rejected: usize,
    /// Wall seconds spent stepping, over every call of [`Simulation::run`].
    pub wall_seconds: f64,
}

impl Clock {
    /// At t = 0 before any step, offering `dt` first.
    pub fn new(dt: f64) -> Self {
        Clock {
            step: 0,
            t: 0.0,
            dt,
            last_dt: 0.0,
            last_rate: f64::NAN,
            rejected: 0,
            wall_seconds: 0.0,
        }
    }
}

/// What observers see: the record of the current state, the engine holding it, and the state
/// of every timer.
pub struct Now<'a> {
    /// The clock (with the step to offer next, which the record lacks).
    pub clock: Clock,
    /// Row of the current state (step, t, measures, σ, residual, rate, counters, wall).
    pub record: Record,
    /// The engine (its φ, σ, measures).
    pub engine: &'a dyn Engine,
    /// The step that produced the state (`None` for the state a run starts from).
    pub report: Option<StepReport>,
    /// The observers' timers, moved past this state (what a checkpoint keeps).
    pub timers: &'a [Timer],
}

/// An observer's answer after a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Flow {
    /// Go on.
    Continue,
    /// End the run, for this reason (reported as [`Stopped::Requested`]).
    Stop(&'static str),
}

/// How a run ended, as observers see it at the end.
#[derive(Clone, Copy, Debug)]
pub enum Ending<'a> {
    /// A stop rule fired (or an observer asked, or the engine stalled).
    Stopped(Stopped),
    /// A step failed; the engine still holds the last good state.
    Failed(&'a Error),
}

/// Sees a simulation's states. Every method defaults to doing nothing.
pub trait Observer {
    /// Once per [`Simulation::run`] call, with the state it starts from.
    ///
    /// # Errors
    /// Any error ends the run with it (e.g. a write failure).
    fn start(&mut self, _now: &Now) -> Result<()> {
        Ok(())
    }
    /// After every accepted step on which [`Observer::schedule`] is due.
    ///
    /// # Errors
    /// As [`Observer::start`].
    fn step(&mut self, _now: &Now) -> Result<Flow> {
        Ok(Flow::Continue)
    }
    /// When [`Observer::step`] is called, under a name unique among a run's observers (a
    /// checkpoint keeps the schedule's state under it); `None`: after every step.
    fn schedule(&self) -> Option<(&'static str, Schedule)> {
        None
    }
    /// Once at the end of a [`Simulation::run`] call, with the last good state.
    ///
    /// # Errors
    /// As [`Observer::start`].
    fn finish(&mut self, _now: &Now, _ending: Ending) -> Result<()> {
        Ok(())
    }
}

/// An engine and its clock, for a scene of dimension `dim` and interface width `eps` (which
/// the records' reduced quantities need).
pub struct Simulation {
    engine: Box<dyn Engine + Send>,
    /// Where the simulation is.
    pub clock: Clock,
    /// The timers of the scheduled observers of the runs so far (a resumed run's from its
    /// checkpoint): a later run whose observer has the same name and schedule continues it.
    pub timers: Vec<Timer>,
    dim: usize,
    eps: f64,
}

impl Simulation {
    /// A simulation of `engine` from t = 0, offering `dt` first.
    pub fn new(engine: Box<dyn Engine + Send>, dt: f64, dim: usize, eps: f64) -> Self {
        Simulation {
            engine,
            clock: Clock::new(dt),
            timers: Vec::new(),
            dim,
            eps,
        }
    }

    /// The engine.
    pub fn engine(&self) -> &dyn Engine {
        self.engine.as_ref()
    }

    /// The engine, mutably (to change its area constraint between runs, for instance).
    pub fn engine_mut(&mut self) -> &mut (dyn Engine + Send) {
        self.engine.as_mut()
    }

    /// Give the engine up.
    pub fn into_engine(self) -> Box<dyn Engine + Send> {
        self.engine
    }

    /// The record of the current state.
    pub fn record(&self) -> Record {
        let c = &self.clock;
        let mut r = Record::of(c.step, c.t, c.last_dt, self.engine(), self.dim, self.eps);
        r.rate = c.last_rate;
        r.rejected = c.rejected;
        r.wall_seconds = c.wall_seconds;
        r
    }

    /// Step until a rule of `rules` fires, the engine stalls, an observer asks to stop, or a
    /// step fails. The clock carries on from where an earlier call left it, so successive calls
    /// with growing `t_end` advance one simulation through a sequence of times. Each step is
    /// shortened to land on `t_end` and on the next due time of every observer's schedule on
    /// simulated time.
    ///
    /// # Errors
    /// `Error::Blowup` (step, t and reason) when a step fails: the engine then still holds the
    /// last good state, and the observers have seen it in [`Observer::finish`]. An observer's
    /// error ends the run with that error.
    pub fn run(
        &mut self,
        rules: &StopRules,
        observers: &mut [&mut dyn Observer],
    ) -> Result<Stopped> {
        let wall_before = self.clock.wall_seconds;
        let started = Instant::now();
        let slots = self.attach(observers);
        let now = self.now(None);
        for o in observers.iter_mut() {
            o.start(&now)?;
        }
        let ending = self.step_loop(rules, observers, &slots, wall_before, started);
        self.clock.wall_seconds = wall_before + started.elapsed().as_secs_f64();
        let now = self.now(None);
        let result = match ending {
            Ok(stopped) => {
                for o in observers.iter_mut() {
                    o.finish(&now, Ending::Stopped(stopped))?;
                }
                Ok(stopped)
            }
            Err(e) => {
                for o in observers.iter_mut() {
                    // The run's own error is the one to report.
                    let _ = o.finish(&now, Ending::Failed(&e));
                }
                Err(e)
            }
        };
        result
    }

    fn now(&self, report: Option<StepReport>) -> Now<'_> {
        Now {
            clock: self.clock,
            record: self.record(),
            engine: self.engine(),
            report,
            timers: &self.timers,
        }
    }

    /// The index in [`Simulation::timers`] of each observer's timer (`None`: unscheduled): the
    /// timer of the same name and schedule if there is one, else a new one started now.
    fn attach(&mut self, observers: &[&mut dyn Observer]) -> Vec<Option<usize>> {
        observers
            .iter()
            .map(|o| {
                let (name, schedule) = o.schedule()?;
                let at = self.timers.iter().position(|t| t.name == name);
                let fresh = Timer::new(name, schedule, &self.clock);
                Some(match at {
                    Some(i) if self.timers[i].schedule == schedule => i,
                    Some(i) => {
                        self.timers[i] = fresh;
                        i
                    }
                    None => {
                        self.timers.push(fresh);
                        self.timers.len() - 1
                    }
                })
            })
            .collect()
    }

    fn step_loop(
        &mut self,
        rules: &StopRules,
        observers: &mut [&mut dyn Observer],
        slots: &[Option<usize>],
        wall_before: f64,
        started: Instant,
    ) -> Result<Stopped> {
        let c = self.clock;
        if let Some(s) = rules.check(c.t, c.last_dt, c.step, self.engine.residual()) {
            return Ok(s);
        }
        let mut due = vec![false; observers.len()];
        let mut longest_step = 0.0f64;
        // The pool's other workers wait for each step's parallel regions without sleeping.
        let _awake = KeepAwake::start();
        loop {
            let land = slots
                .iter()
                .flatten()
                .filter_map(|&i| self.timers[i].next_time())
                .chain(rules.t_end)
                .reduce(f64::min);
            let before = started.elapsed().as_secs_f64();
            let report = self.advance(land)?;
            self.clock.wall_seconds = wall_before + started.elapsed().as_secs_f64();
            for (d, slot) in due.iter_mut().zip(slots) {
                *d = slot.is_none_or(|i| self.timers[i].due(&self.clock));
            }
            let now = self.now(Some(report));
            let mut flow = Flow::Continue;
            for (o, _) in observers.iter_mut().zip(&due).filter(|(_, d)| **d) {
                if let Flow::Stop(why) = o.step(&now)? {
                    flow = Flow::Stop(why);
                }
            }
            // A step's wall time, for the wall-time rule, includes what its observers wrote.
            let elapsed = started.elapsed().as_secs_f64();
            longest_step = longest_step.max(elapsed - before);
            let c = self.clock;
            let stop = if self.engine.stalled() {
                Some(Stopped::Stalled)
            } else {
                rules.check(c.t, c.last_dt, c.step, self.engine.residual())
            };
            match (stop, flow) {
                (Some(s), _) => return Ok(s),
                (None, Flow::Stop(why)) => return Ok(Stopped::Requested(why)),
                (None, Flow::Continue) if rules.wall_time_up(elapsed, longest_step) => {
                    return Ok(Stopped::WallTime)
                }
                (None, Flow::Continue) => {}
            }
        }
    }

    /// One accepted step, shortened to land on `land` (the nearest of `t_end` and the
    /// observers' due times); after a shortened step the next one is offered the engine's
    /// proposal from before the shortening.
    fn advance(&mut self, land: Option<f64>) -> Result<StepReport> {
        let c = &mut self.clock;
        let proposal = self.engine.next_dt(c.dt);
        let dt = land.map_or(proposal, |te| proposal.min(te - c.t));
        let report = self.engine.step(c.t, dt).map_err(|failure| {
            let (step, t) = (c.step + 1, c.t + dt);
            let reason = format!(
                "step of Δt = {dt:.4e} from t = {:.6e} failed: {failure}",
                c.t
            );
            match failure.cause() {
                Some(cause) => Error::Blowup {
                    step,
                    t,
                    reason,
                    cause,
                },
                None => Error::Device { step, t, reason },
            }
        })?;
        c.t += report.dt;
        c.step += 1;
        c.rejected += report.rejected;
        c.last_dt = report.dt;
        c.last_rate = report.rate;
        c.dt = if dt < proposal && report.dt == dt {
            proposal
        } else {
            report.dt
        };
        Ok(report)
    }
}

/// An observer made of a closure called after every step (the studies' probes).
pub struct Probe<F>(pub F);

impl<F: FnMut(&Now) -> Result<Flow>> Observer for Probe<F> {
    fn step(&mut self, now: &Now) -> Result<Flow> {
        (self.0)(now)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engines::{AreaConstraint, Cause, Rejection, Saved, StepError};
    use crate::problem::model::Measures;
    use ndarray::Array3;

    /// An engine whose first step fails with `failure`.
    struct Failing {
        phi: Array3<f64>,
        failure: StepError,
    }

    impl Engine for Failing {
        fn phi(&self) -> &Array3<f64> {
            &self.phi
        }
        fn sigma(&self) -> f64 {
            0.0
        }
        fn measures(&self) -> Measures {
            Measures {
                energy: 1.0,
                area: 1.0,
                volume: 1.0,
                curvature: 0.0,
            }
        }
        fn residual(&self) -> f64 {
            1.0
        }
        fn set_area(&mut self, _area: AreaConstraint) {}
        fn set_area_difference(
            &mut self,
            _term: crate::problem::area_difference::AreaDifference,
        ) -> std::result::Result<(), String> {
            Err("no area-difference term".into())
        }
        fn step(&mut self, _t: f64, _dt: f64) -> std::result::Result<StepReport, StepError> {
            Err(self.failure.clone())
        }
        fn name(&self) -> &'static str {
            "failing"
        }
        fn save(&self) -> Saved<'_> {
            Saved::default()
        }
        fn restore(&mut self, _saved: &mut Saved<'_>, _t: f64) -> std::result::Result<(), String> {
            Ok(())
        }
    }

    /// A failed step reaches the caller by type: a rejection as a blow-up with its check's
    /// cause, a device failure as `Error::Device`, at step 1.
    #[test]
    fn a_failed_step_keeps_its_type() {
        let cases = [
            (
                StepError::rejected(Rejection::VolumeDrift(1e-6)),
                Some(Cause::Volume),
            ),
            (
                StepError::rejected(Rejection::NoRealRoot),
                Some(Cause::Area),
            ),
            (StepError::Device("GPU: out of memory".into()), None),
        ];
        for (failure, cause) in cases {
            let engine = Failing {
                phi: Array3::zeros((1, 4, 4)),
                failure,
            };
            let mut sim = Simulation::new(Box::new(engine), 0.5, 2, 1.0);
            let err = sim.run(&StopRules::steps(3), &mut []).expect_err("fails");
            match (&err, cause) {
                (Error::Blowup { step, cause: c, .. }, Some(want)) => {
                    assert_eq!((*step, *c), (1, want));
                }
                (Error::Device { step, .. }, None) => assert_eq!(*step, 1),
                _ => panic!("{err:?} for {cause:?}"),
            }
        }
    }
}
