//! When a simulation stops: the scene's stop rules and the names of the reasons.

use crate::problem::config::Scene;

/// The stop rules of a run; any that is set can end it. With none set the run only ends when an
/// observer asks, the engine stalls or it fails.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StopRules {
    /// Stop when t reaches this (the last step is shortened to land on it).
    pub t_end: Option<f64>,
    /// Stop after this many accepted steps in all (the clock's count, not this call's).
    pub max_steps: Option<usize>,
    /// Stop when the stationarity residual RMS(μ − μ̄) falls below this.
    pub stop_residual: Option<f64>,
    /// Stop before this call of `Simulation::run` would step for more than this many minutes
    /// of wall time (after one step at least).
    pub max_wall_minutes: Option<f64>,
}

impl StopRules {
    /// The rules a scene file sets (`t_end`, `max_steps`, `stop_residual`,
    /// `max_wall_minutes`).
    pub fn of(scene: &Scene) -> Self {
        StopRules {
            t_end: scene.t_end,
            max_steps: scene.max_steps,
            stop_residual: scene.stop_residual,
            max_wall_minutes: scene.max_wall_minutes,
        }
    }

    /// Only `t_end`.
    pub fn until(t_end: f64) -> Self {
        StopRules {
            t_end: Some(t_end),
            ..Self::default()
        }
    }

    /// Only `max_steps`.
    pub fn steps(max_steps: usize) -> Self {
        StopRules {
            max_steps: Some(max_steps),
            ..Self::default()
        }
    }

    /// Whether `max_wall_minutes` would be passed by one more step: `elapsed` seconds of
    /// stepping so far in this call plus its `longest_step` (the step and its observers'
    /// writes) exceed it.
    pub fn wall_time_up(&self, elapsed: f64, longest_step: f64) -> bool {
        self.max_wall_minutes
            .is_some_and(|m| elapsed + longest_step > 60.0 * m)
    }

    /// Which rule, if any, a state at time `t`, after `step` steps, with `residual` meets.
    /// `t_end` counts as reached within 1e-6 of the last step `dt` (a sum of many steps carries
    /// round-off, which must not cost an extra step of ~1e-13).
    pub fn check(&self, t: f64, dt: f64, step: usize, residual: f64) -> Option<Stopped> {
        if self.stop_residual.is_some_and(|tol| residual < tol) {
            Some(Stopped::Stationary)
        } else if self.t_end.is_some_and(|te| t >= te - 1e-6 * dt.abs()) {
            Some(Stopped::TimeEnd)
        } else if self.max_steps.is_some_and(|m| step >= m) {
            Some(Stopped::MaxSteps)
        } else {
            None
        }
    }
}

/// Why a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stopped {
    /// The residual fell below `stop_residual`.
    Stationary,
    /// `t_end` reached.
    TimeEnd,
    /// `max_steps` reached.
    MaxSteps,
    /// The engine could make no further progress (round-off floor).
    Stalled,
    /// One more step would pass `max_wall_minutes`.
    WallTime,
    /// An observer asked to stop, for the reason given.
    Requested(&'static str),
}

impl Stopped {
    /// The name written to `summary.json` (`"stopped"`).
    pub fn as_str(&self) -> &'static str {
        match self {
            Stopped::Stationary => "stationary",
            Stopped::TimeEnd => "t_end",
            Stopped::MaxSteps => "max_steps",
            Stopped::Stalled => "stalled",
            Stopped::WallTime => "wall_time",
            Stopped::Requested(why) => why,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rules_fire_in_order_residual_time_steps() {
        let r = StopRules {
            t_end: Some(1.0),
            max_steps: Some(10),
            stop_residual: Some(1e-6),
            max_wall_minutes: None,
        };
        assert_eq!(r.check(0.5, 0.1, 3, 1e-3), None);
        assert_eq!(r.check(1.0, 0.1, 10, 1e-7), Some(Stopped::Stationary));
        // 1 − 1e-8 is within 1e-6 Δt of t_end = 1 for Δt = 0.1: reached.
        assert_eq!(r.check(1.0 - 1e-8, 0.1, 3, 1e-3), Some(Stopped::TimeEnd));
        assert_eq!(r.check(0.9, 0.1, 3, 1e-3), None);
        assert_eq!(r.check(0.9, 0.1, 10, 1e-3), Some(Stopped::MaxSteps));
        // A NaN residual never counts as stationary.
        assert_eq!(r.check(0.5, 0.1, 3, f64::NAN), None);
    }

    /// One minute: 50 s stepped and steps of 9 s leave room for one more, of 11 s not.
    #[test]
    fn wall_time_is_up_when_one_more_step_would_pass_it() {
        let r = StopRules {
            max_wall_minutes: Some(1.0),
            ..StopRules::default()
        };
        assert!(!r.wall_time_up(50.0, 9.0));
        assert!(r.wall_time_up(50.0, 11.0));
        assert!(!StopRules::default().wall_time_up(1e9, 1e9));
    }
}
