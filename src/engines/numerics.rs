//! Small numerical pieces shared by the engines: the parallel chunk size, the reduction in a
//! fixed order, and the stable root of the area quadratic.

use rayon::iter::{IndexedParallelIterator, ParallelIterator};

/// Elements per parallel task in the passes over a spectrum or a field (smaller tasks cost more
/// in rayon's scheduling than they gain). The spectral sweeps split their chunks down to one a
/// task (`with_max_len(1)`): a thread that finishes its share early steals single chunks
/// instead of waiting for a larger one to end, which in rayon means falling asleep on a futex
/// and being woken (`benches/PERFORMANCE.md`).
pub const PAR_CHUNK: usize = 8192;

/// Largest relative rise of F_eff a step may make (round-off of the sums) where the scheme
/// guarantees a decrease: FD explicit Euler below its bound, stabilised SBDF1, adaptive steps.
pub const ENERGY_RISE_TOL: f64 = 1e-11;

/// Largest relative drift of V (and of A under the exact projection) before a step counts as
/// breaking a constraint (both are held to round-off, about 1e-14).
pub const CONSTRAINT_TOL: f64 = 1e-9;

/// Σ_j partial_j over a binary tree whose shape depends only on the number m of partials, which
/// are those of fixed pieces of the data (chunks, rows, tasks: never a thread's share). Every
/// piece is its own rayon job (`with_max_len(1)`): the pool then halves the index range
/// (mid = len/2) down to single pieces whatever the thread count and whoever steals what, and
/// adds the partials along that tree, so a result is the same bits on any number of threads
/// (`tests/threads.rs`). Rayon's plain `sum`/`reduce` stop splitting where the pool runs out
/// of threads and fold the rest in sequence, which is another order on each thread count.
/// Nothing is allocated (`tests/no_alloc.rs`).
pub fn sum_in_fixed_tree<T: Send>(
    partials: impl IndexedParallelIterator<Item = T>,
    zero: impl Fn() -> T + Sync + Send,
    add: impl Fn(T, T) -> T + Sync + Send,
) -> T {
    partials.with_max_len(1).reduce(zero, add)
}

/// The root of a x² + 2b x + c = 0 nearest `near` (numerically stable), `None` if not real.
pub fn nearest_root(a: f64, b: f64, c: f64, near: f64) -> Option<f64> {
    if a <= 0.0 {
        return (b != 0.0).then(|| -c / (2.0 * b));
    }
    let disc = b * b - a * c;
    if disc < 0.0 {
        return None;
    }
    let q = -(b + b.signum() * disc.sqrt());
    let r1 = q / a;
    let r2 = if q != 0.0 { c / q } else { r1 };
    Some(if (r1 - near).abs() <= (r2 - near).abs() {
        r1
    } else {
        r2
    })
}

#[cfg(test)]
mod tests {
    use super::nearest_root;

    /// (x − 1)(x − 3) = x² − 4x + 3: a = 1, b = −2, c = 3; both roots exact in binary.
    #[test]
    fn nearest_root_picks_the_closer_root() {
        assert_eq!(nearest_root(1.0, -2.0, 3.0, 0.0), Some(1.0));
        assert_eq!(nearest_root(1.0, -2.0, 3.0, 2.9), Some(3.0));
        assert_eq!(nearest_root(1.0, 0.0, 1.0, 0.0), None);
        // Linear: 2·2x − 8 = 0.
        assert_eq!(nearest_root(0.0, 2.0, -8.0, 0.0), Some(2.0));
    }
}
