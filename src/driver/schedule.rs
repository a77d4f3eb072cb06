//! [`Timer`]: an observer's [`Schedule`] and when it is next due, kept as state (the next step,
//! the next simulated time, the next wall time) rather than found from a remainder, so that each
//! due time is met once, the driver can land a step on it, and a checkpoint carries it over.

use crate::driver::simulation::Clock;
use crate::problem::config::Schedule;

/// A schedule and its next due step, simulated time and wall time (each read only when the
/// schedule sets that interval).
#[derive(Clone, Debug, PartialEq)]
pub struct Timer {
    /// The observer's name for it (unique among a run's observers).
    pub name: String,
    /// The intervals.
    pub schedule: Schedule,
    /// Due at the first step ≥ this: the next multiple of `every_steps`.
    next_step: usize,
    /// Due at the first state with t ≥ this (within 1e-6 of the last step).
    next_time: f64,
    /// Due once the clock's wall seconds reach this.
    next_wall: f64,
}

/// The fields a checkpoint stores for a timer, in order.
pub const SAVED: [&str; 6] = [
    "every_steps",
    "every_time",
    "every_minutes",
    "next_step",
    "next_time",
    "next_wall",
];

impl Timer {
    /// A timer named `name` for `schedule`, started at `clock`: next due at the first multiple
    /// of `every_steps` after the clock's step, at t + `every_time`, and `every_minutes` of wall
    /// time from now.
    pub fn new(name: &str, schedule: Schedule, clock: &Clock) -> Self {
        let mut timer = Timer {
            name: name.to_string(),
            schedule,
            next_step: 0,
            next_time: 0.0,
            next_wall: 0.0,
        };
        if let Some(n) = schedule.every_steps {
            timer.next_step = (clock.step / n + 1) * n;
        }
        if let Some(dt) = schedule.every_time {
            timer.next_time = clock.t + dt;
        }
        timer.restart_wall(clock);
        timer
    }

    fn restart_wall(&mut self, clock: &Clock) {
        if let Some(m) = self.schedule.every_minutes {
            self.next_wall = clock.wall_seconds + 60.0 * m;
        }
    }

    /// Whether the schedule is due at `clock` (the state after a step); if so, the next due
    /// step and time move past it and the wall interval starts again from now.
    pub fn due(&mut self, clock: &Clock) -> bool {
        let s = self.schedule;
        let by_steps = s.every_steps.is_some() && clock.step >= self.next_step;
        let tolerance = 1e-6 * clock.last_dt.abs();
        let by_time = s.every_time.is_some() && clock.t >= self.next_time - tolerance;
        let by_wall = s.every_minutes.is_some() && clock.wall_seconds >= self.next_wall;
        if !(by_steps || by_time || by_wall) {
            return false;
        }
        if let Some(n) = s.every_steps {
            if by_steps {
                self.next_step = (clock.step / n + 1) * n;
            }
        }
        if let Some(dt) = s.every_time {
            if by_time {
                self.next_time += dt;
                // A step longer than the interval (which the driver's landing prevents) or an
                // interval below the round-off of t: start again from now.
                if self.next_time <= clock.t + tolerance {
                    self.next_time = clock.t + dt;
                }
            }
        }
        self.restart_wall(clock);
        true
    }

    /// The next simulated time it is due at, if it runs on simulated time: the driver shortens
    /// the step that would pass it so as to land on it.
    pub fn next_time(&self) -> Option<f64> {
        self.schedule.every_time.map(|_| self.next_time)
    }

    /// The values of [`SAVED`] (an interval not set as 0).
    pub fn saved(&self) -> [f64; 6] {
        let s = self.schedule;
        [
            s.every_steps.unwrap_or(0) as f64,
            s.every_time.unwrap_or(0.0),
            s.every_minutes.unwrap_or(0.0),
            self.next_step as f64,
            self.next_time,
            self.next_wall,
        ]
    }

    /// The timer `name` from the values of [`SAVED`], or `None` if they are not a timer's.
    pub fn from_saved(name: &str, v: [f64; 6]) -> Option<Self> {
        let count =
            |x: f64| (x >= 0.0 && x.fract() == 0.0 && x < 2f64.powi(53)).then_some(x as usize);
        let interval = |x: f64| (x != 0.0).then_some(x);
        Some(Timer {
            name: name.to_string(),
            schedule: Schedule {
                every_steps: Some(count(v[0])?).filter(|&n| n > 0),
                every_time: interval(v[1]),
                every_minutes: interval(v[2]),
            },
            next_step: count(v[3])?,
            next_time: v[4],
            next_wall: v[5],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(step: usize, t: f64, last_dt: f64, wall: f64) -> Clock {
        let mut c = Clock::new(last_dt);
        c.step = step;
        c.t = t;
        c.last_dt = last_dt;
        c.wall_seconds = wall;
        c
    }

    /// Every 3 steps from step 0 is due at 3, 6, 9 (the multiples), and from step 7 first at 9.
    #[test]
    fn steps_are_due_at_the_multiples() {
        let mut timer = Timer::new("r", Schedule::steps(3), &at(0, 0.0, 0.1, 0.0));
        let due: Vec<usize> = (1..=10)
            .filter(|&k| timer.due(&at(k, 0.0, 0.1, 0.0)))
            .collect();
        assert_eq!(due, [3, 6, 9]);
        let mut late = Timer::new("r", Schedule::steps(3), &at(7, 0.0, 0.1, 0.0));
        assert!(!late.due(&at(8, 0.0, 0.1, 0.0)));
        assert!(late.due(&at(9, 0.0, 0.1, 0.0)));
    }

    /// Every 0.25 in steps of 0.1 (no landing here): due at the first state past each multiple,
    /// 0.3, 0.5, 0.8, 1.0, and the next due time is the multiple, not the state's t + 0.25.
    #[test]
    fn time_is_due_once_per_interval_and_keeps_the_grid() {
        let mut timer = Timer::new("s", Schedule::time(0.25), &at(0, 0.0, 0.1, 0.0));
        let mut due = Vec::new();
        for k in 1..=10 {
            let t = k as f64 * 0.1;
            if timer.due(&at(k, t, 0.1, 0.0)) {
                due.push(k);
            }
        }
        assert_eq!(due, [3, 5, 8, 10]);
        assert_eq!(timer.next_time(), Some(1.25));
        // Within 1e-6 of the last step below a due time counts as reaching it.
        let mut timer = Timer::new("s", Schedule::time(0.5), &at(0, 0.0, 0.1, 0.0));
        assert!(timer.due(&at(5, 0.5 - 1e-9, 0.1, 0.0)));
        assert_eq!(timer.next_time(), Some(1.0));
    }

    /// Every minute of wall time, counted from the last time it was due (by any interval).
    #[test]
    fn wall_minutes_count_from_the_last_due() {
        let both = Schedule {
            every_steps: Some(10),
            every_minutes: Some(1.0),
            ..Schedule::NEVER
        };
        let mut timer = Timer::new("c", both, &at(0, 0.0, 0.1, 5.0));
        assert!(!timer.due(&at(1, 0.0, 0.1, 64.0)));
        assert!(timer.due(&at(2, 0.0, 0.1, 65.0)));
        assert!(timer.due(&at(10, 0.0, 0.1, 70.0)));
        assert!(!timer.due(&at(11, 0.0, 0.1, 129.0)));
        assert!(timer.due(&at(12, 0.0, 0.1, 130.0)));
    }

    /// Saved and read back, a timer is the same timer; a never-due one too.
    #[test]
    fn saved_timers_read_back() {
        let both = Schedule {
            every_steps: Some(4),
            every_time: Some(0.3),
            every_minutes: None,
        };
        let mut timer = Timer::new("snapshots", both, &at(0, 0.0, 0.1, 0.0));
        assert!(timer.due(&at(4, 0.4, 0.1, 1.0)));
        assert_eq!(Timer::from_saved("snapshots", timer.saved()), Some(timer));
        let never = Timer::new("x", Schedule::NEVER, &at(3, 1.0, 0.1, 0.0));
        assert_eq!(Timer::from_saved("x", never.saved()), Some(never));
        assert_eq!(
            Timer::from_saved("x", [-1.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
            None
        );
    }
}
