//! The inextensible membrane's tension fields across steps ([`super::inextensible`]): σ of the
//! accepted state, from which every solve of the next state starts, σ of the accepted state
//! before it, and their checkpoint.
//!
//! A solve's result depends on its start to the solve's tolerance, so a resumed run that solved
//! again would leave the uninterrupted one at that level. Instead the checkpoint holds both
//! states' σ, and a resumed run evaluates its two states with them in place of solves (a
//! *replay*). The flow of a σ is computed the same way after a solve and in a replay — the
//! unconstrained flow plus S Bᵀσ of the final σ — so the replayed flows, and the run from
//! there, are the uninterrupted run's bit for bit.

use crate::engines::{Saved, SavedArray};
use ndarray::{Array3, CowArray};

/// Which held σ the next solves take instead of solving.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Replay {
    /// The current accepted state's.
    Current,
    /// The accepted state's before it.
    Before,
}

/// σ per part (0: at σ_g = 0, 1: per unit global tension) of the current accepted state and of
/// the one before it.
pub struct Tensions {
    current: [Array3<f64>; 2],
    before: [Array3<f64>; 2],
    /// Which parts `current` and `before` hold.
    held: [bool; 2],
    held_before: [bool; 2],
    /// The σ the next solves take, if they are replayed.
    replay: Option<Replay>,
}

impl Tensions {
    /// None held yet, on fields of `shape`.
    pub fn new(shape: [usize; 3]) -> Self {
        let zeros = || Array3::zeros(shape);
        Tensions {
            current: [zeros(), zeros()],
            before: [zeros(), zeros()],
            held: [false; 2],
            held_before: [false; 2],
            replay: None,
        }
    }

    /// The start of a solve of `part`: the current accepted state's σ, if there is one.
    pub fn start(&self, part: usize) -> Option<&Array3<f64>> {
        self.held[part].then_some(&self.current[part])
    }

    /// The σ of `part` a replayed solve takes: none unless a replay is set and holds it.
    pub fn replayed(&self, part: usize) -> Option<&Array3<f64>> {
        match self.replay? {
            Replay::Current => self.held[part].then_some(&self.current[part]),
            Replay::Before => self.held_before[part].then_some(&self.before[part]),
        }
    }

    /// Replay the held σ `which` in the next solves, or (`None`) solve again.
    pub fn set_replay(&mut self, which: Option<Replay>) {
        self.replay = which;
    }

    /// A solve of `part` ended at `sigma`: with no accepted state yet (the initial state's
    /// evaluation) it is the current state's.
    pub fn solved(&mut self, part: usize, sigma: &Array3<f64>) {
        if !self.held[part] {
            self.current[part].assign(sigma);
            self.held[part] = true;
        }
    }

    /// A step was accepted whose state's solves ended at `last` (per part): the current σ
    /// becomes the one before, `last` the current.
    pub fn accept(&mut self, last: &[Array3<f64>; 2]) {
        std::mem::swap(&mut self.current, &mut self.before);
        self.held_before = self.held;
        for part in (0..2).filter(|&p| self.held[p]) {
            self.current[part].assign(&last[part]);
        }
    }

    /// The held fields for a checkpoint: `tension_P` (the current state's, part P) and
    /// `tension_before_P`.
    pub fn saved(&self) -> Vec<(String, SavedArray<'_>)> {
        let mut out = Vec::new();
        for part in 0..2 {
            if self.held[part] {
                out.push((format!("tension_{part}"), real(&self.current[part])));
            }
            if self.held_before[part] {
                out.push((format!("tension_before_{part}"), real(&self.before[part])));
            }
        }
        out
    }

    /// Hold the fields a checkpoint `saved` has ([`Tensions::saved`]); a part it lacks is
    /// solved again when its state is evaluated.
    ///
    /// # Errors
    /// If a field has another shape than the box's.
    pub fn restore(&mut self, saved: &Saved<'_>) -> Result<(), String> {
        let shape = self.current[0].shape().to_vec();
        for part in 0..2 {
            for (name, field, held) in [
                (
                    format!("tension_{part}"),
                    &mut self.current[part],
                    &mut self.held[part],
                ),
                (
                    format!("tension_before_{part}"),
                    &mut self.before[part],
                    &mut self.held_before[part],
                ),
            ] {
                *held = saved.has(&name);
                if *held {
                    field.assign(&saved.real(&name, &shape)?);
                }
            }
        }
        Ok(())
    }
}

/// A real field as a checkpoint's array, borrowed.
fn real(a: &Array3<f64>) -> SavedArray<'_> {
    SavedArray::Real(CowArray::from(a.view()))
}
