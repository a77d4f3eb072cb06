//! The fused, plane-pipelined FD step: one sweep along the streamed axis reads φⁿ and μⁿ once
//! and writes φ^{n+1} once and μ^{n+1} over μⁿ, with the measures of φ^{n+1} and the sums of the
//! residual reduced on the way (the C reference's `fused` variant, `shared/bench/fd_limit.c`).
//!
//! Three stages run plane by plane, each a plane behind the one before:
//!
//! ```text
//! 1. φ' = φⁿ + Δt ∇²_h μⁿ                                      (plane z + 2)
//! 2. L = ∇²_h φ',  Φ = f(φ') − ε² L,  q = 2 f'(φ') Φ − (3/√2) ε σ L   (plane z + 1)
//! 3. μ' = q − 2ε² ∇²_h Φ                                        (plane z)
//! ```
//!
//! Stage 1 writes the slab's planes of φ^{n+1}, stage 2 keeps Φ in a ring of three planes and
//! writes q over the slab's planes of μⁿ, which stage 3 completes into μ^{n+1}. Each thread owns
//! a contiguous slab of planes. Stage 2 at a slab's ends needs φ' two planes beyond them, so
//! stage 1 runs first on every slab's edges (its first two and last two planes), into buffers
//! every slab reads; the pipeline then copies its own edges and computes stage 1 only on the
//! planes between. Each slab recomputes the plane of Φ on either side of it into its own ring.
//!
//! μ is updated in place: stage 1 at plane z + 2 reads μⁿ on planes z + 1 to z + 3 before stage
//! 2 overwrites plane z + 1, and stage 1 on the edges, the only one that reads a neighbour's
//! μⁿ, has finished on every slab before any pipeline starts. So no second μ array is written
//! (writing one costs a read of each of its cache lines before the write).
//!
//! The streamed axis is axis 0, or axis 1 for a 2D scene (n0 = 1): the planes are then rows.
//! Planes outside the box are those of the periodic or mirror (even) extension: with the mirror
//! ghost φ_{−1} = φ_0 every stage's field is even about the wall, so the extension evaluates the
//! same stencil as [`crate::engines::stencil`]'s ghosts.

use super::lanes::{in_lanes, largest, total, Acc, Kernel, Lane, Lanes, LANES};
use crate::engines::stencil::{above, below};
use crate::problem::grid::{AxisKind, Grid};
use crate::problem::model::{bulk, bulk_at_zero_c0, bulk_derivative, bulk_derivative_at_zero_c0};
use rayon::prelude::*;
use vesicle_transforms::Private;

/// The box as planes × rows × row length along the streamed axis, with the axes' walls.
#[derive(Clone, Copy, Debug)]
struct Layout {
    planes: usize,
    rows: usize,
    len: usize,
    kinds: [AxisKind; 3],
}

impl Layout {
    /// Stream along axis 0, or along axis 1 when axis 0 has length 1 (2D): same memory order.
    fn of(grid: &Grid) -> Self {
        let [n0, n1, n2] = grid.shape;
        let k = grid.kinds;
        if n0 == 1 {
            Layout {
                planes: n1,
                rows: 1,
                len: n2,
                kinds: [k[1], k[0], k[2]],
            }
        } else {
            Layout {
                planes: n0,
                rows: n1,
                len: n2,
                kinds: k,
            }
        }
    }

    /// Points per plane.
    fn plane(&self) -> usize {
        self.rows * self.len
    }

    /// The stored plane equal to plane `z` of the extended box: periodic wrap, or the even
    /// reflection about the mirror walls (z = −1 − i ↦ i, z = m + i ↦ m − 1 − i).
    fn stored(&self, z: isize) -> usize {
        let n = self.planes as isize;
        let s = match self.kinds[0] {
            AxisKind::Periodic => z.rem_euclid(n),
            AxisKind::Mirror => {
                let p = z.rem_euclid(2 * n);
                if p < n {
                    p
                } else {
                    2 * n - 1 - p
                }
            }
        };
        s as usize
    }

    /// Plane `z` of the extended box in the field `u` (a stored plane).
    fn plane_of<'a>(&self, u: &'a [f64], z: isize) -> &'a [f64] {
        let p = self.plane();
        &u[self.stored(z) * p..][..p]
    }
}

/// The scalars of one step.
#[derive(Clone, Copy, Debug)]
pub(super) struct Coefficients {
    /// Δt.
    pub dt: f64,
    /// 1/h².
    pub inv_h2: f64,
    /// ε².
    pub e2: f64,
    /// (3/√2) ε σ^{n+1}.
    pub tension: f64,
    /// εC0 where uniform (0 with a field), ramped to t^{n+1}.
    pub uniform: f64,
    /// Ramp factor of a εC0 field at t^{n+1}.
    pub ramp: f64,
    /// Shift c of the residual sums Σ(μ − c), Σ(μ − c)²: the previous mean of μ.
    pub shift: f64,
}

/// The fields the sweep reads only (μ it reads and overwrites).
#[derive(Clone, Copy, Debug)]
pub(super) struct Fields<'a> {
    /// φⁿ.
    pub phi: &'a [f64],
    /// Unramped εC0 field, if C0 is a field.
    pub c0: Option<&'a [f64]>,
}

/// The reductions of one sweep over the computed box (plain sums, no h^d).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Sums {
    /// Σ Φ_h(φ^{n+1})².
    pub energy: f64,
    /// Σ φ^{n+1} ∇²_h φ^{n+1} (= −Σ_axes (φ_{i+e} − φ_i)²/h², the area's sum).
    pub phi_lap: f64,
    /// Σ φ^{n+1}.
    pub phi: f64,
    /// max |φ^{n+1}|.
    pub max_phi: f64,
    /// max |∇²_h μⁿ| (the rate max|∂φ/∂t|).
    pub max_lap_mu: f64,
    /// Σ (μ^{n+1} − c).
    pub dev: f64,
    /// Σ (μ^{n+1} − c)².
    pub dev_sq: f64,
}

impl Sums {
    /// Sums of two disjoint parts of the box.
    fn add(self, o: Sums) -> Sums {
        Sums {
            energy: self.energy + o.energy,
            phi_lap: self.phi_lap + o.phi_lap,
            phi: self.phi + o.phi,
            max_phi: self.max_phi.max(o.max_phi),
            max_lap_mu: self.max_lap_mu.max(o.max_lap_mu),
            dev: self.dev + o.dev,
            dev_sq: self.dev_sq + o.dev_sq,
        }
    }
}

/// Stage 1's results on one plane: φ' is written; the lanes and tails of Σφ', max|φ'|,
/// max|∇²_h μⁿ| ([`Acc::finish`]).
type Advanced = (Lanes<3>, [f64; 3]);

/// One thread's buffers: the ring of three Φ planes and one row of a Laplacian, each
/// [`Private`] to the thread; stage 1's results on the slab's edge planes, and the sums of each
/// of the slab's planes (added over the box in plane order, so that the totals do not depend on
/// how the planes are cut into slabs, that is on the thread count).
#[derive(Debug)]
struct Pipe {
    big: Private<f64>,
    row: Private<f64>,
    edge_sums: [Advanced; 4],
    planes: Vec<Sums>,
}

/// The planes of the box cut into slabs of `per` consecutive planes (the last may be shorter).
#[derive(Clone, Copy, Debug)]
struct Slabs {
    planes: usize,
    per: usize,
}

impl Slabs {
    /// Number of slabs.
    fn count(&self) -> usize {
        self.planes.div_ceil(self.per)
    }

    /// Planes z0..z1 of slab `i`.
    fn bounds(&self, i: usize) -> (usize, usize) {
        (i * self.per, ((i + 1) * self.per).min(self.planes))
    }

    /// Slab and slot (0, 1: its first two planes; 2, 3: its last two) of stored plane `p`, if
    /// `p` is an edge of its slab. In a slab of fewer than four planes a plane has one slot.
    fn edge(&self, p: usize) -> Option<(usize, usize)> {
        let i = p / self.per;
        let (z0, z1) = self.bounds(i);
        if p - z0 < 2 {
            Some((i, p - z0))
        } else if z1 - p <= 2 {
            Some((i, 4 - (z1 - p)))
        } else {
            None
        }
    }
}

/// The planned sweep: layout and per-thread buffers (allocated once).
#[derive(Debug)]
pub(super) struct Sweep {
    layout: Layout,
    pipes: Vec<Pipe>,
    /// φ' on each slab's edge planes, four planes a slab (by [`Slabs::edge`]'s slot).
    edges: Vec<Private<f64>>,
    /// The CPU runs AVX2 (x86-64 only).
    avx2: bool,
}

impl Sweep {
    /// Buffers for `threads` slabs (at most one per plane).
    pub fn new(grid: &Grid, threads: usize) -> Self {
        let layout = Layout::of(grid);
        let plane = layout.plane();
        let count = threads.clamp(1, layout.planes);
        let pipes = (0..count)
            .map(|_| Pipe {
                big: Private::new(3 * plane, 0.0),
                row: Private::new(layout.len, 0.0),
                edge_sums: [([[0.0; LANES]; 3], [0.0; 3]); 4],
                planes: Vec::new(),
            })
            .collect();
        let edges = (0..count).map(|_| Private::new(4 * plane, 0.0)).collect();
        let avx2 = crate::cpu::has_avx2();
        Sweep {
            layout,
            pipes,
            edges,
            avx2,
        }
    }

    /// One step: `phi_next` = φ^{n+1}, and `mu` from μ_h(φⁿ, σⁿ) to μ_h(φ^{n+1}, σ^{n+1});
    /// returns the sums.
    pub fn run(
        &mut self,
        f: &Fields,
        k: &Coefficients,
        phi_next: &mut [f64],
        mu: &mut [f64],
    ) -> Sums {
        let (l, avx2) = (self.layout, self.avx2);
        let slabs = Slabs {
            planes: l.planes,
            per: l.planes.div_ceil(self.pipes.len()),
        };
        let slab = slabs.per * l.plane();
        let n = slabs.count();
        let at = |i, edges| Slab::new(&l, slabs, i, f, k, edges);
        for (i, pipe) in self.pipes[..n].iter_mut().enumerate() {
            let (z0, z1) = slabs.bounds(i);
            pipe.planes.clear();
            pipe.planes.resize(z1 - z0, Sums::default());
        }
        if n == 1 {
            let pipe = &mut self.pipes[0];
            pipe.run(&at(0, &[]), avx2, Phase::Edges(&mut self.edges[0], mu));
            let s = at(0, &self.edges);
            pipe.run(&s, avx2, Phase::Pipeline(phi_next, mu));
        } else {
            let old_mu = &*mu;
            self.pipes[..n]
                .par_iter_mut()
                .zip(&mut self.edges[..n])
                .enumerate()
                .for_each(|(i, (pipe, edges))| {
                    pipe.run(&at(i, &[]), avx2, Phase::Edges(edges, old_mu));
                });
            let edges = &self.edges;
            phi_next
                .par_chunks_mut(slab)
                .zip(mu.par_chunks_mut(slab))
                .zip(self.pipes.par_iter_mut())
                .enumerate()
                .for_each(|(i, ((phi, mu), pipe))| {
                    pipe.run(&at(i, edges), avx2, Phase::Pipeline(phi, mu));
                });
        }
        self.pipes[..n]
            .iter()
            .flat_map(|p| &p.planes)
            .fold(Sums::default(), |a, p| a.add(*p))
    }
}

/// What a slab's thread runs: stage 1 on the slab's edge planes into its edge buffer (from the
/// whole of μⁿ), or the pipeline into its planes of φ^{n+1} and over its planes of μ.
enum Phase<'a> {
    Edges(&'a mut [f64], &'a [f64]),
    Pipeline(&'a mut [f64], &'a mut [f64]),
}

impl Pipe {
    /// `phase` of slab `s`: the AVX2 build of [`Self::phase`] when the CPU has AVX2 (`avx2`),
    /// else the baseline build.
    fn run(&mut self, s: &Slab, avx2: bool, phase: Phase) {
        #[cfg(target_arch = "x86_64")]
        if avx2 {
            // SAFETY: `avx2` is true only when `crate::cpu::has_avx2()` found the
            // instructions on this CPU (`Sweep::new`). Measured on the full-box bench, one
            // thread, interleaved runs: 2.3–3.0 ms against 3.0–4.5 ms (SSE2 build) at 64³,
            // 21–25 ms against 27–28 ms at 128³.
            unsafe { self.phase_avx2(s, phase) };
            return;
        }
        let _ = avx2;
        self.phase(s, phase);
    }

    /// [`Self::phase`] compiled for AVX2 (the same operations, no FMA contraction: the results
    /// are those of the baseline build bit for bit).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn phase_avx2(&mut self, s: &Slab, phase: Phase) {
        self.phase(s, phase);
    }

    /// [`Self::edge_planes`] or [`Self::stages`].
    #[inline(always)]
    fn phase(&mut self, s: &Slab, phase: Phase) {
        match phase {
            Phase::Edges(edges, mu) => self.edge_planes(s, edges, mu),
            Phase::Pipeline(phi, mu) => self.stages(s, phi, mu),
        }
    }

    /// Stage 1 on each edge plane of slab `s`, from μⁿ (`mu`, the whole box), written to its
    /// slot of `edges`, its sums kept for the pipeline to add in plane order.
    #[inline(always)]
    fn edge_planes(&mut self, s: &Slab, edges: &mut [f64], mu: &[f64]) {
        let (l, p) = (s.l, s.l.plane());
        for z in s.z0..s.z1 {
            if let Some((_, slot)) = s.slabs.edge(z as usize) {
                let out = &mut edges[slot * p..][..p];
                let mu = [
                    l.plane_of(mu, z - 1),
                    l.plane_of(mu, z),
                    l.plane_of(mu, z + 1),
                ];
                let old = l.plane_of(s.f.phi, z);
                self.edge_sums[slot] = advance(l, s.k, mu, old, out, &mut self.row);
            }
        }
    }

    /// The three stages over slab `s`, a plane apart: prologue up to stage 2 at z0, then per
    /// plane z: stage 1 at z + 2, stage 2 at z + 1, stage 3 at z. Stage 1 runs on the slab's
    /// planes only (its neighbours' edges are read from the edge buffers). Each plane's sums go
    /// to its own entry of `self.planes` (a plane outside the slab adds none).
    #[inline(always)]
    fn stages(&mut self, s: &Slab, phi: &mut [f64], mu: &mut [f64]) {
        let (z0, z1) = (s.z0, s.z1);
        // Sized and zeroed by `Sweep::run`, outside this hot function.
        let mut planes = std::mem::take(&mut self.planes);
        // Each stage adds into a fresh local (kept in registers), then into its plane's entry.
        let mut add = |z: isize, local: Sums| {
            if s.owns(z) {
                let entry = &mut planes[(z - z0) as usize];
                *entry = entry.add(local);
            }
        };
        for z in z0..(z0 + 2).min(z1) {
            let mut sums = Sums::default();
            self.advance(s, z, phi, mu, &mut sums);
            add(z, sums);
        }
        self.potential(s, z0 - 1, phi, mu, &mut Sums::default());
        let mut sums = Sums::default();
        self.potential(s, z0, phi, mu, &mut sums);
        add(z0, sums);
        for z in z0..z1 {
            if z + 2 < z1 {
                let mut sums = Sums::default();
                self.advance(s, z + 2, phi, mu, &mut sums);
                add(z + 2, sums);
            }
            let mut sums = Sums::default();
            self.potential(s, z + 1, phi, mu, &mut sums);
            add(z + 1, sums);
            let mut sums = Sums::default();
            self.correct(s, z, mu, &mut sums);
            add(z, sums);
        }
        self.planes = planes;
    }

    /// Stage 1 on plane `z` of the slab, its sums added: an edge plane copied from its slot,
    /// another computed from the slab's planes of μⁿ in `mu` (an inner plane's neighbours are
    /// the slab's own, and stage 2 has not yet overwritten them).
    #[inline(always)]
    fn advance(&mut self, s: &Slab, z: isize, phi: &mut [f64], mu: &[f64], sums: &mut Sums) {
        let p = s.l.plane();
        let out = &mut phi[(z - s.z0) as usize * p..][..p];
        let ([sum, max_phi, max_lap], [sum_t, max_phi_t, max_lap_t]) =
            match s.slabs.edge(z as usize) {
                Some((i, slot)) => {
                    out.copy_from_slice(&s.edges[i][slot * p..][..p]);
                    self.edge_sums[slot]
                }
                None => {
                    let own = |z: isize| &mu[(z - s.z0) as usize * p..][..p];
                    let mu = [own(z - 1), own(z), own(z + 1)];
                    let old = s.l.plane_of(s.f.phi, z);
                    advance(s.l, s.k, mu, old, out, &mut self.row)
                }
            };
        sums.phi += total(sum, sum_t);
        sums.max_phi = largest(max_phi, max_phi_t, sums.max_phi);
        sums.max_lap_mu = largest(max_lap, max_lap_t, sums.max_lap_mu);
    }

    /// Stage 2 on plane `z`: Φ of φ' into the ring; in the slab also q = 2f'Φ − (3/√2)εσ∇²φ'
    /// into μ^{n+1} and the sums of F and A. f and f' take εC0 from the field, the uniform
    /// value, or drop it where C0 = 0.
    #[inline(always)]
    fn potential(&mut self, s: &Slab, z: isize, phi: &[f64], mu: &mut [f64], sums: &mut Sums) {
        match s.f.c0 {
            Some(c) => {
                let c0 = Some(s.l.plane_of(c, z));
                self.potential_with(s, z, phi, mu, sums, FieldBulk(s.k.ramp), c0);
            }
            None if s.k.uniform == 0.0 => self.potential_with(s, z, phi, mu, sums, ZeroBulk, None),
            None => {
                let bulk = UniformBulk(s.k.uniform);
                self.potential_with(s, z, phi, mu, sums, bulk, None);
            }
        }
    }

    /// [`Self::potential`] with f, f' from `bulk`, whose third input is the plane `c0` of the
    /// unramped εC0 field, or φ' where there is none.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn potential_with(
        &mut self,
        s: &Slab,
        z: isize,
        phi: &[f64],
        mu: &mut [f64],
        sums: &mut Sums,
        bulk: impl Bulk,
        c0: Option<&[f64]>,
    ) {
        let (l, p) = (s.l, s.l.plane());
        let phis = [s.phi(z - 1, phi), s.phi(z, phi), s.phi(z + 1, phi)];
        let big = &mut self.big[ring(z) * p..][..p];
        let third = c0.unwrap_or(phis[1]);
        let own = s.owns(z);
        let (kernel, mut acc) = (Potential { k: s.k, bulk }, Acc::zero());
        for j in 0..l.rows {
            laplacian_row(l, phis, j, s.k.inv_h2, &mut self.row);
            let r = j * l.len..(j + 1) * l.len;
            let ins = [&phis[1][r.clone()], &self.row[..], &third[r.clone()]];
            if own {
                let q = &mut mu[(z - s.z0) as usize * p..][..p][r.clone()];
                in_lanes(&kernel, ins, [&mut big[r], q], &mut acc);
            } else {
                bulk_row(&kernel, ins, &mut big[r]);
            }
        }
        if own {
            let ([energy, phi_lap], [energy_t, phi_lap_t]) = acc.finish();
            sums.energy += total(energy, energy_t);
            sums.phi_lap += total(phi_lap, phi_lap_t);
        }
    }

    /// Stage 3 on plane `z` of the slab: μ^{n+1} = q − 2ε² ∇²_h Φ, with the residual's sums.
    #[inline(always)]
    fn correct(&mut self, s: &Slab, z: isize, mu: &mut [f64], sums: &mut Sums) {
        let (l, p) = (s.l, s.l.plane());
        let at = |z| -> &[f64] { &self.big[ring(z) * p..][..p] };
        let big = [at(z - 1), at(z), at(z + 1)];
        let out = &mut mu[(z - s.z0) as usize * p..][..p];
        let kernel = Correct {
            e2x2: 2.0 * s.k.e2,
            shift: s.k.shift,
        };
        let mut acc = Acc::zero();
        for j in 0..l.rows {
            laplacian_row(l, big, j, s.k.inv_h2, &mut self.row);
            let r = j * l.len..(j + 1) * l.len;
            in_lanes(&kernel, [&self.row], [&mut out[r]], &mut acc);
        }
        let ([dev, dev_sq], [dev_t, dev_sq_t]) = acc.finish();
        sums.dev += total(dev, dev_t);
        sums.dev_sq += total(dev_sq, dev_sq_t);
    }
}

/// Stage 1 on one plane into `out`: φ' = φⁿ + Δt ∇²_h μⁿ, with its sums, from the plane `old`
/// of φⁿ and the planes `mu` of μⁿ around it; `row` is scratch for a row of ∇²_h μⁿ.
#[inline(always)]
fn advance(
    l: &Layout,
    k: &Coefficients,
    mu: [&[f64]; 3],
    old: &[f64],
    out: &mut [f64],
    row: &mut [f64],
) -> Advanced {
    let (kernel, mut acc) = (Advance { dt: k.dt }, Acc::zero());
    for j in 0..l.rows {
        laplacian_row(l, mu, j, k.inv_h2, row);
        let r = j * l.len..(j + 1) * l.len;
        in_lanes(&kernel, [&old[r.clone()], row], [&mut out[r]], &mut acc);
    }
    acc.finish()
}

/// Slot of plane `z` in a ring of three planes.
fn ring(z: isize) -> usize {
    z.rem_euclid(3) as usize
}

/// What a slab's stages share.
struct Slab<'a> {
    l: &'a Layout,
    slabs: Slabs,
    z0: isize,
    z1: isize,
    f: &'a Fields<'a>,
    k: &'a Coefficients,
    /// Every slab's edge planes of φ' (none while they are computed).
    edges: &'a [Private<f64>],
}

impl<'a> Slab<'a> {
    /// Slab `i` of `slabs`.
    fn new(
        l: &'a Layout,
        slabs: Slabs,
        i: usize,
        f: &'a Fields<'a>,
        k: &'a Coefficients,
        edges: &'a [Private<f64>],
    ) -> Self {
        let (z0, z1) = slabs.bounds(i);
        Slab {
            l,
            slabs,
            z0: z0 as isize,
            z1: z1 as isize,
            f,
            k,
            edges,
        }
    }

    /// Plane `z` is the slab's own (else a neighbour's).
    fn owns(&self, z: isize) -> bool {
        (self.z0..self.z1).contains(&z)
    }

    /// Plane `z` of φ' (z0 − 2 ≤ z < z1 + 2): from the slab's own planes `slab`, or from the
    /// edge buffers (the plane of the periodic or mirror extension that `z` stands for is an
    /// edge of its slab).
    fn phi<'b>(&'b self, z: isize, slab: &'b [f64]) -> &'b [f64] {
        let p = self.l.plane();
        if self.owns(z) {
            return &slab[(z - self.z0) as usize * p..][..p];
        }
        let (i, slot) = self
            .slabs
            .edge(self.l.stored(z))
            .expect("a plane within two of a slab's end is an edge of its slab");
        &self.edges[i][slot * p..][..p]
    }
}

/// `out` = row `j` of ∇²_h u on the middle of three consecutive planes `u`:
/// Σ_axes (u_{i+e} − 2u_i + u_{i−e}) / h², axes of length 1 skipped, summed in the order of
/// [`crate::engines::stencil::laplacian`] (transverse rows, then along the row, then the scale).
#[inline(always)]
fn laplacian_row(l: &Layout, u: [&[f64]; 3], j: usize, inv_h2: f64, out: &mut [f64]) {
    let n = l.len;
    fn row(plane: &[f64], j: usize, n: usize) -> &[f64] {
        &plane[j * n..][..n]
    }
    let c = row(u[1], j, n);
    let mut t = [c; 4];
    let mut m = 0;
    if l.planes > 1 {
        t = [row(u[0], j, n), row(u[2], j, n), c, c];
        m = 2;
    }
    if l.rows > 1 {
        t[m] = row(u[1], below(j, l.rows, l.kinds[1]), n);
        t[m + 1] = row(u[1], above(j, l.rows, l.kinds[1]), n);
        m += 2;
    }
    // Cut to the row's length here, so that the loop's bounds checks fold away whatever the
    // surrounding code (without it the FD step varied by 7–12% with changes elsewhere in the
    // sweep: measured).
    let [a, b, d, e] = t.map(|r| &r[..n]);
    match m {
        4 => along_row(c, l.kinds[2], inv_h2, out, |k| {
            (a[k] + b[k]) + (d[k] + e[k]) - 4.0 * c[k]
        }),
        2 => along_row(c, l.kinds[2], inv_h2, out, |k| a[k] + b[k] - 2.0 * c[k]),
        _ => along_row(c, l.kinds[2], inv_h2, out, |_| 0.0),
    }
}

/// `out_k = (transverse(k) + c_{k−1} − 2c_k + c_{k+1}) / h²` along the contiguous axis (its
/// walls at k = 0 and n − 1 apart from the vectorised interior), or `transverse(k)/h²` when the
/// row has one point.
#[inline(always)]
fn along_row(
    c: &[f64],
    kind: AxisKind,
    inv_h2: f64,
    out: &mut [f64],
    transverse: impl Fn(usize) -> f64,
) {
    let n = c.len();
    let out = &mut out[..n];
    if n == 1 {
        out[0] = transverse(0) * inv_h2;
        return;
    }
    for k in 1..n - 1 {
        out[k] = (transverse(k) + (c[k - 1] + c[k + 1] - 2.0 * c[k])) * inv_h2;
    }
    for k in [0, n - 1] {
        let (lo, hi) = (c[below(k, n, kind)], c[above(k, n, kind)]);
        out[k] = (transverse(k) + (lo + hi - 2.0 * c[k])) * inv_h2;
    }
}

/// Stage 1 at a point: φ' = φⁿ + Δt ∇²_h μⁿ; sums φ', maxima of |φ'| and |∇²_h μⁿ|.
struct Advance {
    dt: f64,
}

impl Kernel<2, 1, 3> for Advance {
    #[inline(always)]
    fn point<T: Lane>(&self, acc: &mut [T; 3], [old, lap]: [T; 2], _: [T; 1]) -> [T; 1] {
        let new = old + T::splat(self.dt) * lap;
        acc[0] = acc[0] + new;
        acc[1] = acc[1].larger(new.abs());
        acc[2] = acc[2].larger(lap.abs());
        [new]
    }
}

/// f(φ) and f'(φ) at a point of stage 2, from φ' and the kernel's third input.
trait Bulk: Copy {
    /// (f(φ), f'(φ)) lane by lane.
    fn pair<T: Lane>(&self, phi: T, third: T) -> (T, T);
}

/// εC0 = ramp × the unramped field (the third input).
#[derive(Clone, Copy)]
struct FieldBulk(f64);

impl Bulk for FieldBulk {
    #[inline(always)]
    fn pair<T: Lane>(&self, phi: T, c0: T) -> (T, T) {
        let c = T::splat(self.0) * c0;
        (phi.zip(c, bulk), phi.zip(c, bulk_derivative))
    }
}

/// The same εC0 ≠ 0 everywhere (the third input unread).
#[derive(Clone, Copy)]
struct UniformBulk(f64);

impl Bulk for UniformBulk {
    #[inline(always)]
    fn pair<T: Lane>(&self, phi: T, _: T) -> (T, T) {
        let c = T::splat(self.0);
        (phi.zip(c, bulk), phi.zip(c, bulk_derivative))
    }
}

/// C0 = 0: f and f' without their C0 terms (the third input unread).
#[derive(Clone, Copy)]
struct ZeroBulk;

impl Bulk for ZeroBulk {
    #[inline(always)]
    fn pair<T: Lane>(&self, phi: T, _: T) -> (T, T) {
        (
            phi.zip(phi, |u, _| bulk_at_zero_c0(u)),
            phi.zip(phi, |u, _| bulk_derivative_at_zero_c0(u)),
        )
    }
}

/// Φ_h = f(φ) − ε² ∇²_h φ on a row outside the slab (inputs as [`Potential`]'s, no sums).
#[inline(always)]
fn bulk_row<B: Bulk>(kernel: &Potential<B>, [phi, lap, third]: [&[f64]; 3], big: &mut [f64]) {
    let n = big.len();
    let (phi, lap, third) = (&phi[..n], &lap[..n], &third[..n]);
    for (((b, &u), &l), &c) in big.iter_mut().zip(phi).zip(lap).zip(third) {
        *b = kernel.bulk.pair(u, c).0 - kernel.k.e2 * l;
    }
}

/// Stage 2 at a point of φ' (inputs φ', L = ∇²_h φ' and `bulk`'s third): Φ and q; sums Φ²
/// and φ' L.
struct Potential<'a, B> {
    k: &'a Coefficients,
    bulk: B,
}

impl<B: Bulk> Kernel<3, 2, 2> for Potential<'_, B> {
    #[inline(always)]
    fn point<T: Lane>(&self, acc: &mut [T; 2], [phi, lap, third]: [T; 3], _: [T; 2]) -> [T; 2] {
        let (f, df) = self.bulk.pair(phi, third);
        let big = f - T::splat(self.k.e2) * lap;
        let q = T::splat(2.0) * (df * big) - T::splat(self.k.tension) * lap;
        acc[0] = acc[0] + big * big;
        acc[1] = acc[1] + phi * lap;
        [big, q]
    }
}

/// Stage 3 at a point (input ∇²_h Φ, output q becoming μ): μ = q − 2ε² ∇²_h Φ; sums μ − c and
/// (μ − c)².
struct Correct {
    /// 2ε².
    e2x2: f64,
    /// c.
    shift: f64,
}

impl Kernel<1, 1, 2> for Correct {
    #[inline(always)]
    fn point<T: Lane>(&self, acc: &mut [T; 2], [lap]: [T; 1], [q]: [T; 1]) -> [T; 1] {
        let mu = q - T::splat(self.e2x2) * lap;
        let d = mu - T::splat(self.shift);
        acc[0] = acc[0] + d;
        acc[1] = acc[1] + d * d;
        [mu]
    }
}
