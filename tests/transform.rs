//! Checks of the planned 3D real transform against naive sums, the mirror-unfolded periodic
//! transform, Parseval's identity and the analytic Laplacian.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::f64::consts::PI;

use ndarray::{Array3, Zip};
use num_complex::Complex64;
use vesicle::engines::spectral::transform::Transform;
use vesicle::problem::grid::{AxisKind, Grid};

use AxisKind::{Mirror as M, Periodic as P};

/// Counts the allocations made by the current thread.
struct CountingAlloc;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

// SAFETY: every call goes on to the system allocator unchanged, so its memory and layouts are
// the system allocator's; counting allocates nothing and cannot unwind.
unsafe impl GlobalAlloc for CountingAlloc {
    /// # Safety
    /// As for [`GlobalAlloc::alloc`].
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.with(|c| c.set(c.get() + 1));
        // SAFETY: the caller's `layout`, as `GlobalAlloc::alloc` requires.
        unsafe { System.alloc(layout) }
    }
    /// # Safety
    /// As for [`GlobalAlloc::dealloc`].
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` was allocated by `alloc` above, that is by `System`, with `layout`.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: CountingAlloc = CountingAlloc;

/// Minimal linear congruential generator (Knuth's MMIX constants), uniform in [-1, 1).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

fn random_field(shape: [usize; 3], seed: u64) -> Array3<f64> {
    let mut rng = Lcg(seed);
    Array3::from_shape_simple_fn(shape, || rng.next())
}

const ALL_KINDS: [[AxisKind; 3]; 8] = [
    [P, P, P],
    [P, P, M],
    [P, M, P],
    [M, P, P],
    [P, M, M],
    [M, P, M],
    [M, M, P],
    [M, M, M],
];

const SHAPES: [[usize; 3]; 9] = [
    [4, 6, 8],
    [1, 8, 5],
    [3, 5, 7],
    [1, 1, 8],
    [1, 1, 1],
    [2, 1, 3],
    [5, 4, 1],
    [1, 9, 6],
    [6, 2, 2],
];

/// 1D kernel of one axis: `e^{−2πi j i/n}` (periodic) or `cos(π j (2i+1)/(2n))` (mirror).
fn kernel(kind: AxisKind, n: usize, j: usize, i: usize) -> Complex64 {
    let (j, i, n) = (j as f64, i as f64, n as f64);
    match kind {
        P => Complex64::from_polar(1.0, -2.0 * PI * j * i / n),
        M => Complex64::new((PI * j * (2.0 * i + 1.0) / (2.0 * n)).cos(), 0.0),
    }
}

/// Direct O(N²) evaluation of the forward transform on the spectral index range.
fn naive_forward(x: &Array3<f64>, kinds: [AxisKind; 3], spectral: [usize; 3]) -> Array3<Complex64> {
    let n = [x.shape()[0], x.shape()[1], x.shape()[2]];
    Array3::from_shape_fn(spectral, |(j0, j1, j2)| {
        let mut sum = Complex64::default();
        for ((i0, i1, i2), &v) in x.indexed_iter() {
            sum += v
                * kernel(kinds[0], n[0], j0, i0)
                * kernel(kinds[1], n[1], j1, i1)
                * kernel(kinds[2], n[2], j2, i2);
        }
        sum
    })
}

fn max_diff_c(a: &Array3<Complex64>, b: &Array3<Complex64>) -> f64 {
    assert_eq!(a.shape(), b.shape());
    Zip::from(a)
        .and(b)
        .fold(0.0f64, |m, x, y| m.max((x - y).norm()))
}

fn max_diff(a: &Array3<f64>, b: &Array3<f64>) -> f64 {
    assert_eq!(a.shape(), b.shape());
    Zip::from(a)
        .and(b)
        .fold(0.0f64, |m, x, y| m.max((x - y).abs()))
}

fn forward_of(t: &mut Transform, x: &Array3<f64>) -> Array3<Complex64> {
    let mut out = Array3::zeros(t.spectral_shape());
    t.forward(&mut x.clone(), &mut out);
    out
}

/// The forward transform in the index layout ([`Transform::unpacked`]).
fn indexed_forward_of(t: &mut Transform, x: &Array3<f64>) -> Array3<Complex64> {
    let y = forward_of(t, x);
    t.unpacked(y.view())
}

fn inverse_of(t: &mut Transform, spectrum: &Array3<Complex64>) -> Array3<f64> {
    let mut scratch = spectrum.clone();
    let mut out = Array3::zeros(t.shape());
    t.inverse(&mut scratch, &mut out);
    out
}

#[test]
fn spectral_shape_halves_a_periodic_last_axis_only() {
    assert_eq!(
        Transform::new([3, 5, 8], [P, P, P], 1).spectral_shape(),
        [3, 5, 5]
    );
    assert_eq!(
        Transform::new([3, 5, 7], [P, M, P], 1).spectral_shape(),
        [3, 5, 4]
    );
    assert_eq!(
        Transform::new([3, 5, 7], [P, P, M], 1).spectral_shape(),
        [3, 5, 7]
    );
}

#[test]
fn forward_matches_naive_sums() {
    for (s, shape) in SHAPES.iter().enumerate() {
        for (k, kinds) in ALL_KINDS.iter().enumerate() {
            let x = random_field(*shape, (10 * s + k) as u64);
            for threads in [1, 2, 3] {
                let mut t = Transform::new(*shape, *kinds, threads);
                let reference = naive_forward(&x, *kinds, t.index_shape());
                let err = max_diff_c(&indexed_forward_of(&mut t, &x), &reference);
                assert!(err < 1e-12, "{shape:?} {kinds:?} threads {threads}: {err}");
            }
        }
    }
}

#[test]
fn forward_leaves_input_untouched_and_is_repeatable() {
    let x = random_field([5, 6, 7], 3);
    let copy = x.clone();
    let mut t = Transform::new([5, 6, 7], [M, P, P], 2);
    let first = forward_of(&mut t, &x);
    let second = forward_of(&mut t, &x);
    assert_eq!(x, copy);
    assert_eq!(first, second);
}

#[test]
fn round_trip_restores_the_field() {
    let mut shapes = SHAPES.to_vec();
    shapes.extend([[16, 12, 10], [7, 9, 11], [32, 1, 33]]);
    for (s, shape) in shapes.iter().enumerate() {
        for kinds in ALL_KINDS {
            let x = random_field(*shape, 100 + s as u64);
            for threads in [1, 2, 4] {
                let mut t = Transform::new(*shape, kinds, threads);
                let spectrum = forward_of(&mut t, &x);
                let back = inverse_of(&mut t, &spectrum);
                let err = max_diff(&back, &x);
                assert!(err < 1e-13, "{shape:?} {kinds:?} threads {threads}: {err}");
            }
        }
    }
}

#[test]
fn large_round_trip_in_parallel() {
    let shape = [40, 36, 64];
    for kinds in [[P, P, P], [M, M, M], [M, P, M]] {
        let x = random_field(shape, 7);
        let mut serial = Transform::new(shape, kinds, 1);
        let mut parallel = Transform::new(shape, kinds, 2);
        let a = forward_of(&mut serial, &x);
        let b = forward_of(&mut parallel, &x);
        assert!(max_diff_c(&a, &b) < 1e-12, "{kinds:?}");
        assert!(
            max_diff(&inverse_of(&mut parallel, &b), &x) < 1e-13,
            "{kinds:?}"
        );
    }
}

/// Boxes whose every axis longer than 1 is a mirror axis, and only those, store their real
/// spectra packed: ⌈n2/2⌉ values a row, two reals each, the padding of an odd row exactly 0,
/// and packing the index layout gives the stored spectrum back exactly.
#[test]
fn all_mirror_spectra_are_packed() {
    for shape in [[6, 5, 7], [1, 8, 9], [4, 3, 8], [1, 1, 5]] {
        for kinds in ALL_KINDS {
            let mut t = Transform::new(shape, kinds, 1);
            let all_mirror = (0..3).all(|a| shape[a] == 1 || kinds[a] == M);
            assert_eq!(t.packed(), all_mirror, "{shape:?} {kinds:?}");
            if !all_mirror {
                continue;
            }
            let [n0, n1, n2] = shape;
            assert_eq!(t.spectral_shape(), [n0, n1, n2.div_ceil(2)]);
            assert_eq!(t.index_shape(), shape);
            let y = forward_of(&mut t, &random_field(shape, 11));
            if n2 % 2 == 1 {
                assert!(y.slice(ndarray::s![.., .., -1]).iter().all(|z| z.im == 0.0));
            }
            let indexed = t.unpacked(y.view());
            assert!(indexed.iter().all(|z| z.im == 0.0));
            assert_eq!(t.packed_from(indexed.view()), y, "{shape:?} {kinds:?}");
        }
    }
}

#[test]
fn parseval_weights_give_sums_of_squares_and_inner_products() {
    for (s, shape) in SHAPES.iter().enumerate() {
        for kinds in ALL_KINDS {
            let mut t = Transform::new(*shape, kinds, 1);
            let u = random_field(*shape, 200 + s as u64);
            let v = random_field(*shape, 300 + s as u64);
            let (fu, fv) = (
                indexed_forward_of(&mut t, &u),
                indexed_forward_of(&mut t, &v),
            );
            let w = t.parseval_weights();
            let spectral_sum = |f: &dyn Fn(Complex64, Complex64) -> f64| {
                fu.indexed_iter()
                    .zip(fv.iter())
                    .map(|(((a, b, c), &x), &y)| w[0][a] * w[1][b] * w[2][c] * f(x, y))
                    .sum::<f64>()
            };
            let uu: f64 = u.iter().map(|x| x * x).sum();
            let uv: f64 = u.iter().zip(&v).map(|(x, y)| x * y).sum();
            let uu_k = spectral_sum(&|x, _| x.norm_sqr());
            let uv_k = spectral_sum(&|x, y| (x * y.conj()).re);
            assert!((uu - uu_k).abs() < 1e-12 * uu, "{shape:?} {kinds:?}");
            assert!((uv - uv_k).abs() < 1e-12 * uu, "{shape:?} {kinds:?}");
        }
    }
}

/// On a mirror axis of `m` points the reduced transform relates to the periodic transform of the
/// mirror-unfolded `2m`-point data by `F_k = 2 (−1)^k e^{iπk/(2m)} X_k` (k = 0..m−1): the factor 2
/// counts both halves, `e^{iπk/(2m)}` is the half-sample shift of the mirror plane and `(−1)^k`
/// the full box starting `m` points below the kept half.
#[test]
fn mirror_transform_equals_unfolded_periodic_transform() {
    for shape in [[3, 4, 5], [1, 6, 4], [2, 3, 3]] {
        for kinds in ALL_KINDS.iter().skip(1) {
            let grid = Grid {
                dim: 3,
                shape,
                kinds: *kinds,
                h: 1.0,
                walls: [false; 3],
            };
            let reduced = random_field(shape, 17);
            let full = grid.unfold(&reduced);
            let fs = grid.full_shape();
            let x = indexed_forward_of(&mut Transform::new(shape, *kinds, 1), &reduced);
            let f = forward_of(&mut Transform::new(fs, [P; 3], 1), &full);
            let phase = |a: usize, k: usize| match kinds[a] {
                P => Complex64::new(1.0, 0.0),
                M => {
                    let sign = if k.is_multiple_of(2) { 2.0 } else { -2.0 };
                    sign * Complex64::from_polar(1.0, PI * k as f64 / (2 * shape[a]) as f64)
                }
            };
            for ((k0, k1, k2), &xk) in x.indexed_iter() {
                let expected = phase(0, k0) * phase(1, k1) * phase(2, k2) * xk;
                let err = (f[(k0, k1, k2)] - expected).norm();
                assert!(err < 1e-12, "{shape:?} {kinds:?} {k0} {k1} {k2}: {err}");
            }
        }
    }
}

/// `inverse(−|k|² forward(u))` against the analytic Laplacian of a band-limited field.
fn check_laplacian(grid: &Grid, u: impl Fn([f64; 3]) -> f64, lap: impl Fn([f64; 3]) -> f64) {
    let mut t = Transform::new(grid.shape, grid.kinds, 2);
    let k = t.wavenumbers(grid.h);
    let mut spectrum = indexed_forward_of(&mut t, &grid.field_from(u));
    for ((a, b, c), z) in spectrum.indexed_iter_mut() {
        *z *= -(k[0][a].powi(2) + k[1][b].powi(2) + k[2][c].powi(2));
    }
    let stored = t.packed_from(spectrum.view());
    let err = max_diff(&inverse_of(&mut t, &stored), &grid.field_from(lap));
    assert!(err < 1e-10, "{:?}: {err}", grid.kinds);
}

#[test]
fn spectral_laplacian_matches_analytic() {
    let h = 0.1;
    // Full box lengths are L = N h along every axis.
    let full = [16usize, 12, 20];
    let l = full.map(|n| n as f64 * h);
    let q = [2.0 * PI / l[0], 4.0 * PI / l[1], 6.0 * PI / l[2]];
    let even = |p: [f64; 3]| (q[0] * p[0]).cos() * (q[1] * p[1]).cos() * (q[2] * p[2]).cos();
    let q2 = q.iter().map(|v| v * v).sum::<f64>();
    for kinds in ALL_KINDS {
        let mirror = kinds.map(|k| k == M);
        let grid = Grid::new(&full, h, &mirror);
        check_laplacian(&grid, even, |p| -q2 * even(p));
    }
    // A field that is not even about the centre on the periodic axes.
    let grid = Grid::new(&full, h, &[false; 3]);
    let odd = |p: [f64; 3]| (q[0] * p[0]).sin() * (q[2] * p[2]).sin() + (q[1] * p[1]).sin();
    let odd_lap = |p: [f64; 3]| {
        -(q[0] * q[0] + q[2] * q[2]) * (q[0] * p[0]).sin() * (q[2] * p[2]).sin()
            - q[1] * q[1] * (q[1] * p[1]).sin()
    };
    check_laplacian(&grid, odd, odd_lap);
}

#[test]
fn wavenumbers_follow_the_index_conventions() {
    let h = 0.5;
    let t = Transform::new([4, 5, 6], [P, M, P], 1);
    let k = t.wavenumbers(h);
    let unit = |n: f64| 2.0 * PI / (n * h);
    let expect0: Vec<f64> = [0.0, 1.0, 2.0, -1.0]
        .iter()
        .map(|m| m * unit(4.0))
        .collect();
    let expect1: Vec<f64> = (0..5).map(|j| PI * j as f64 / (5.0 * h)).collect();
    let expect2: Vec<f64> = (0..4).map(|j| j as f64 * unit(6.0)).collect();
    assert_eq!(k, [expect0, expect1, expect2]);
    let odd = Transform::new([5, 1, 1], [P, P, P], 1).wavenumbers(1.0);
    let m: Vec<f64> = odd[0].iter().map(|k| k * 5.0 / (2.0 * PI)).collect();
    assert_eq!(
        m.iter().map(|v| v.round()).collect::<Vec<_>>(),
        [0.0, 1.0, 2.0, -2.0, -1.0]
    );
    assert_eq!(odd[2], [0.0]);
}

/// The spectrum of a real field is left as it is (to round-off), on every layout.
#[test]
fn hermitian_symmetrize_keeps_real_field_spectra() {
    for shape in [[4, 6, 8], [3, 5, 7], [1, 6, 4]] {
        for kinds in ALL_KINDS {
            let mut t = Transform::new(shape, kinds, 1);
            let x = random_field(shape, 23);
            let spectrum = forward_of(&mut t, &x);
            let mut sym = spectrum.clone();
            t.hermitian_symmetrize(&mut sym);
            assert!(max_diff_c(&sym, &spectrum) < 1e-12, "{shape:?} {kinds:?}");
            let err = max_diff(&inverse_of(&mut t, &sym), &inverse_of(&mut t, &spectrum));
            assert!(err < 1e-14, "{shape:?} {kinds:?}");
        }
    }
}

/// A random complex spectrum (a seeded "invisible" part that no real field has) is projected
/// onto the spectra of real fields on every mirror/periodic layout, 2D and 3D: the projection is
/// idempotent and inverse-then-forward gives it back to round-off, so nothing is left that the
/// inverse transform would drop. (Before every plane was projected on a mirror last axis, the
/// layouts [·, P, M] failed here: their whole spectrum is self-conjugate.)
#[test]
fn hermitian_symmetrize_projects_onto_real_field_spectra() {
    for shape in [[4, 6, 8], [3, 5, 7], [1, 6, 4], [1, 5, 6]] {
        for kinds in ALL_KINDS {
            let mut t = Transform::new(shape, kinds, 1);
            let mut rng = Lcg(5);
            let mut y = Array3::from_shape_simple_fn(t.spectral_shape(), || {
                Complex64::new(rng.next(), rng.next())
            });
            t.hermitian_symmetrize(&mut y);
            let mut twice = y.clone();
            t.hermitian_symmetrize(&mut twice);
            assert!(
                max_diff_c(&twice, &y) < 1e-15,
                "idempotent {shape:?} {kinds:?}"
            );
            let field = inverse_of(&mut t, &y);
            let again = forward_of(&mut t, &field);
            assert!(max_diff_c(&again, &y) < 1e-12, "{shape:?} {kinds:?}");
        }
    }
}

/// The projection is the pairwise mean X(k) ← (X(k) + conj X(−k))/2, X(−k) ← its conjugate,
/// bit for bit, on 1, 2 and 3 threads (the slabs of k0 and −k0 go to one task; a slab paired
/// with the wrong partner, or a pair visited twice, would differ), on every layout, with odd and
/// even n0 and n2 and in 2D.
#[test]
fn hermitian_symmetrize_is_the_pairwise_mean_on_any_thread_count() {
    for shape in [[4, 6, 8], [5, 7, 6], [6, 5, 9], [1, 6, 4], [1, 5, 5]] {
        for kinds in ALL_KINDS {
            let t0 = Transform::new(shape, kinds, 1);
            let mut rng = Lcg(9);
            let y = Array3::from_shape_simple_fn(t0.spectral_shape(), || {
                Complex64::new(rng.next(), rng.next())
            });
            let mut expect = y.clone();
            let [s0, s1, s2] = t0.spectral_shape();
            if t0.packed() {
                // Reals only: an odd row's padding is zeroed, nothing else changes.
                if shape[2] % 2 == 1 {
                    expect
                        .slice_mut(ndarray::s![.., .., -1])
                        .map_inplace(|z| z.im = 0.0);
                }
            }
            let neg = |i: usize, a: usize| match kinds[a] {
                P => (shape[a] - i) % shape[a],
                M => i,
            };
            let conjugate_planes: Vec<usize> = match kinds[2] {
                _ if t0.packed() => Vec::new(),
                M => (0..s2).collect(),
                P => [0, shape[2] / 2]
                    .into_iter()
                    .filter(|&j| j == 0 || shape[2] % 2 == 0)
                    .collect(),
            };
            for &j2 in &conjugate_planes {
                for i0 in 0..s0 {
                    for i1 in 0..s1 {
                        let q = (neg(i0, 0), neg(i1, 1));
                        if q < (i0, i1) {
                            continue;
                        }
                        let mean = 0.5 * (expect[[i0, i1, j2]] + expect[[q.0, q.1, j2]].conj());
                        expect[[i0, i1, j2]] = mean;
                        expect[[q.0, q.1, j2]] = mean.conj();
                    }
                }
            }
            for threads in [1, 2, 3] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let t = Transform::new(shape, kinds, threads);
                let mut got = y.clone();
                pool.install(|| t.hermitian_symmetrize(&mut got));
                assert_eq!(got, expect, "{shape:?} {kinds:?} {threads} threads");
            }
        }
    }
}

#[test]
fn serial_transforms_do_not_allocate() {
    for kinds in [[P, P, P], [M, M, M], [M, P, M]] {
        let shape = [8, 10, 12];
        let mut t = Transform::new(shape, kinds, 1);
        let mut x = random_field(shape, 1);
        let mut spectrum = Array3::zeros(t.spectral_shape());
        let mut back = Array3::zeros(shape);
        t.forward(&mut x, &mut spectrum);
        let before = ALLOCATIONS.with(Cell::get);
        t.forward(&mut x, &mut spectrum);
        t.inverse(&mut spectrum, &mut back);
        assert_eq!(ALLOCATIONS.with(Cell::get), before, "{kinds:?}");
    }
}

/// The slab-by-slab round trip through real space equals two inverse transforms, the same
/// pointwise work over the box and two forward transforms, for every wall kind, on 1 and 2
/// threads and an odd number of slabs (the threads' shares unequal): the spectra to 1e-12 of
/// their largest value (round-off of a transform pair), the real field and the slabs' sums to
/// round-off. The work depends on each value's index (`first` placed wrong would show) and
/// mixes the two fields (their order swapped would show). With fewer slabs than threads the
/// round trip declines and leaves its inputs untouched.
#[test]
fn round_trip_by_slabs_equals_the_transforms_apart() {
    let shape = [5, 6, 8];
    // x_b ← x_b + x_a², y ← 1e-3 (index) x_a; the value is Σ x_a.
    let work = |first: usize, xa: &[f64], xb: &mut [f64], y: &mut [f64]| {
        for (i, ((&a, b), y)) in xa.iter().zip(xb.iter_mut()).zip(y.iter_mut()).enumerate() {
            *b += a * a;
            *y = 1e-3 * (first + i) as f64 * a;
        }
        xa.iter().sum::<f64>()
    };
    for kinds in ALL_KINDS {
        for threads in [1, 2] {
            let mut t = Transform::new(shape, kinds, threads);
            let a = forward_of(&mut t, &random_field(shape, 11));
            let b = forward_of(&mut t, &random_field(shape, 12));
            // Apart.
            let (xa, mut xb) = (inverse_of(&mut t, &a), inverse_of(&mut t, &b));
            let mut y = Array3::zeros(shape);
            let total = work(
                0,
                xa.as_slice().unwrap(),
                xb.as_slice_mut().unwrap(),
                y.as_slice_mut().unwrap(),
            );
            let (a_apart, b_apart) = (forward_of(&mut t, &y), forward_of(&mut t, &xb));
            // By slabs.
            let (mut a_slabs, mut b_slabs) = (a.clone(), b.clone());
            let mut real = Array3::zeros(shape);
            let sum = t
                .round_trip(
                    [&mut a_slabs, &mut b_slabs],
                    &mut real,
                    &mut Vec::new(),
                    work,
                    |p, q| p + q,
                )
                .expect("a slab per thread");
            let case = format!("{kinds:?}, {threads} threads");
            let scale = a_apart
                .iter()
                .chain(&b_apart)
                .map(|z| z.norm())
                .fold(0.0, f64::max);
            assert!(
                max_diff_c(&a_slabs, &a_apart) <= 1e-12 * scale,
                "{case}: first"
            );
            assert!(
                max_diff_c(&b_slabs, &b_apart) <= 1e-12 * scale,
                "{case}: second"
            );
            assert!(max_diff(&real, &xa) <= 1e-14, "{case}: real field");
            assert!(
                (sum - total).abs() <= 1e-12,
                "{case}: sum {sum} against {total}"
            );
        }
    }
    let flat = [1, 6, 8];
    let mut t = Transform::new(flat, [P, P, P], 2);
    let a = forward_of(&mut t, &random_field(flat, 13));
    let (mut a1, mut b1) = (a.clone(), a.clone());
    let mut real = Array3::zeros(flat);
    let declined = t.round_trip(
        [&mut a1, &mut b1],
        &mut real,
        &mut Vec::new(),
        work,
        |p, q| p + q,
    );
    assert!(declined.is_none() && a1 == a && b1 == a && real.iter().all(|&v| v == 0.0));
}
