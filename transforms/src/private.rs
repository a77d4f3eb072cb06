//! Scratch owned by one thread of a parallel pass, kept off the cache lines of other data (the
//! transforms' plans, and vesicle's FD sweeps).

use std::ops::{Deref, DerefMut};

/// Unused bytes on either side of a [`Private`] buffer: two cache lines, the unit of the L2's
/// adjacent-line prefetch.
const GUARD_BYTES: usize = 128;

/// A thread's own buffer of `len` values between two guards of 128 unused bytes, so that no line
/// it touches holds another thread's data. Per-thread buffers allocated one after another
/// otherwise share a line where one ends and the next begins, and two threads writing them pass
/// the line back and forth (`benches/PERFORMANCE.md`, "Per-thread scratch off other threads'
/// cache lines").
#[derive(Debug)]
pub struct Private<T> {
    buf: Vec<T>,
    guard: usize,
}

impl<T: Clone> Private<T> {
    /// `len` copies of `value`, guarded.
    pub fn new(len: usize, value: T) -> Self {
        let guard = GUARD_BYTES.div_ceil(std::mem::size_of::<T>().max(1));
        Private {
            buf: vec![value; len + 2 * guard],
            guard,
        }
    }
}

impl<T> Deref for Private<T> {
    type Target = [T];
    fn deref(&self) -> &[T] {
        &self.buf[self.guard..self.buf.len() - self.guard]
    }
}

impl<T> DerefMut for Private<T> {
    fn deref_mut(&mut self) -> &mut [T] {
        let end = self.buf.len() - self.guard;
        &mut self.buf[self.guard..end]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The buffer holds `len` values, and the guards are at least 128 bytes each side.
    #[test]
    fn guarded_buffer_has_its_length_and_guards() {
        let mut p = Private::new(5, 1.0f64);
        assert_eq!(p.len(), 5);
        p[4] = 2.0;
        assert_eq!(&p[..], &[1.0, 1.0, 1.0, 1.0, 2.0]);
        assert!(p.guard * 8 >= GUARD_BYTES && p.buf.len() == 5 + 2 * p.guard);
        let c = Private::new(3, num_complex::Complex64::default());
        assert!(c.guard * 16 >= GUARD_BYTES && c.len() == 3);
    }
}
