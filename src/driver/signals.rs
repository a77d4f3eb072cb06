//! SIGINT and SIGTERM: recorded, not fatal, so a run can finish its step, write its checkpoint
//! and outputs, and exit with 130 or 143. The handlers are installed even when the process was
//! started in the background with SIGINT ignored.

use crate::driver::simulation::{Flow, Now, Observer};
use crate::error::Result;
use signal_hook::consts::{SIGINT, SIGTERM};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

/// The signals received so far (the first one counts).
#[derive(Clone, Debug)]
pub struct Interrupts {
    received: Arc<AtomicUsize>,
}

impl Interrupts {
    /// Install the handlers for SIGINT and SIGTERM.
    ///
    /// # Panics
    /// If the handlers cannot be installed (the signals are valid, so only on a broken libc).
    pub fn install() -> Self {
        let received = Arc::new(AtomicUsize::new(0));
        for sig in [SIGINT, SIGTERM] {
            let flag = Arc::clone(&received);
            // SAFETY: the handler only stores to an atomic, which is async-signal-safe.
            unsafe {
                signal_hook::low_level::register(sig, move || {
                    let _ =
                        flag.compare_exchange(0, sig as usize, Ordering::SeqCst, Ordering::SeqCst);
                })
            }
            .expect("signal handler");
        }
        Interrupts { received }
    }

    /// The first signal received, if any.
    pub fn received(&self) -> Option<i32> {
        match self.received.load(Ordering::SeqCst) {
            0 => None,
            s => Some(s as i32),
        }
    }

    /// The shell's exit code for a process ended by the first signal: 128 + its number (130 for
    /// SIGINT, 143 for SIGTERM).
    pub fn exit_code(&self) -> Option<i32> {
        self.received().map(|s| 128 + s)
    }
}

impl Observer for Interrupts {
    fn step(&mut self, _now: &Now) -> Result<Flow> {
        Ok(match self.received() {
            Some(_) => Flow::Stop("interrupted"),
            None => Flow::Continue,
        })
    }
}
