// The GPU engine's kernels (compiled by NVRTC when the engine starts). Spectra are the
// real-to-complex half spectra of an n0 x n1 x n2 periodic box, shape n0 x n1 x s2 with
// s2 = n2/2 + 1, row-major; mode (i0, i1, i2) has |k|^2 = kx2[i0] + ky2[i1] + kz2[i2] and
// Parseval weight w = wx[i0] wy[i1] wz[i2] (cell volume included), so that the integral of
// u v over the box is the sum over modes of w Re(U conj V).
//
// Every kernel that sums runs a grid-stride loop on a fixed grid of BLOCKS x THREADS threads
// and writes one partial per block and per sum (partials[s * gridDim.x + block]); the host
// adds the partials in block order, so a sum does not depend on the scheduling.

#define THREADS 256

struct Tables {
    const double* kx2;
    const double* ky2;
    const double* kz2;
    const double* wx;
    const double* wy;
    const double* wz;
    int n0, n1, s2;
};

// The tables' kernel arguments, and the struct built from them.
#define TABLE_ARGS                                                                           \
    const double *kx2, const double *ky2, const double *kz2, const double *wx,              \
        const double *wy, const double *wz, int n0, int n1, int s2
#define TABLES Tables t = {kx2, ky2, kz2, wx, wy, wz, n0, n1, s2}

__device__ __forceinline__ double2 d2(double x, double y) {
    double2 r;
    r.x = x;
    r.y = y;
    return r;
}

// |k|^2 and the Parseval weight w of mode m (row-major over n0 x n1 x s2).
__device__ __forceinline__ void symbols(const Tables& t, long m, double* k, double* w) {
    int i2 = (int)(m % t.s2);
    long r = m / t.s2;
    int i1 = (int)(r % t.n1), i0 = (int)(r / t.n1);
    *k = t.kx2[i0] + t.ky2[i1] + t.kz2[i2];
    *w = t.wx[i0] * t.wy[i1] * t.wz[i2];
}

// Block sum of v into out[blockIdx.x] (all threads of the block must call it).
__device__ void block_sum(double v, double* out) {
    __shared__ double s[THREADS];
    s[threadIdx.x] = v;
    __syncthreads();
    for (int h = THREADS / 2; h > 0; h >>= 1) {
        if (threadIdx.x < h) s[threadIdx.x] += s[threadIdx.x + h];
        __syncthreads();
    }
    if (threadIdx.x == 0) out[blockIdx.x] = s[0];
    __syncthreads();
}

// Block maximum of v into out[blockIdx.x].
__device__ void block_max(double v, double* out) {
    __shared__ double s[THREADS];
    s[threadIdx.x] = v;
    __syncthreads();
    for (int h = THREADS / 2; h > 0; h >>= 1) {
        if (threadIdx.x < h) s[threadIdx.x] = fmax(s[threadIdx.x], s[threadIdx.x + h]);
        __syncthreads();
    }
    if (threadIdx.x == 0) out[blockIdx.x] = s[0];
    __syncthreads();
}

// X <- (X + conj X(-k0, -k1)) / 2 on the self-conjugate planes i2 = 0 and i2 = n2/2.
extern "C" __global__ void hermitian_planes(double2* a, int n0, int n1, int s2, int n2) {
    long pairs = (long)n0 * n1;
    int planes = (n2 % 2 == 0) ? 2 : 1;
    for (long t = blockIdx.x * (long)blockDim.x + threadIdx.x; t < planes * pairs;
         t += (long)gridDim.x * blockDim.x) {
        int plane = (int)(t / pairs);
        long r = t % pairs;
        int i0 = (int)(r / n1), i1 = (int)(r % n1);
        int p0 = (n0 - i0) % n0, p1 = (n1 - i1) % n1;
        long rp = (long)p0 * n1 + p1;
        int i2 = plane == 0 ? 0 : n2 / 2;
        if (r > rp) continue;
        long a_at = r * s2 + i2, b_at = rp * s2 + i2;
        double2 x = a[a_at], y = a[b_at];
        double re = (x.x + y.x) * 0.5, im = (x.y - y.y) * 0.5;
        a[a_at] = d2(re, im);
        a[b_at] = d2(re, -im);
    }
}

// copy = X, lap = -|k|^2 X (the inputs of the two inverse transforms); partial sums of the area
// A = sum of ap |k|^2 w |X|^2.
extern "C" __global__ void inverse_inputs(const double2* hat, double2* copy, double2* lap,
                                          TABLE_ARGS, double ap, double* partials) {
    TABLES;
    long len = (long)t.n0 * t.n1 * t.s2;
    double area = 0.0;
    for (long m = blockIdx.x * (long)blockDim.x + threadIdx.x; m < len;
         m += (long)gridDim.x * blockDim.x) {
        double k, w;
        symbols(t, m, &k, &w);
        double2 h = hat[m];
        copy[m] = h;
        lap[m] = d2(-(h.x * k), -(h.y * k));
        area += ap * k * w * (h.x * h.x + h.y * h.y);
    }
    block_sum(area, partials);
}

// The real-space pass. On entry phi and lap hold n * phi and n * lap(phi) (the unnormalised
// inverse transforms); phi <- phi, lap <- f(phi), fphi <- f'(phi) Phi with
// f = (phi + ec0)(phi^2 - 1), f' = 3 phi^2 - 1 + 2 ec0 phi, Phi = f - e2 lap(phi).
// Partials: sum Phi^2, sum phi, max |phi|, max |phi - old| (0 without old).
extern "C" __global__ void pointwise(double* phi, double* lap, double* fphi, const double* old,
                                     int has_old, double inv_n, double e2, double ec0, long len,
                                     double* partials) {
    double sq = 0.0, sum = 0.0, big = 0.0, change = 0.0;
    for (long i = blockIdx.x * (long)blockDim.x + threadIdx.x; i < len;
         i += (long)gridDim.x * blockDim.x) {
        double p = phi[i] * inv_n;
        double l = lap[i] * inv_n;
        double f = (p + ec0) * (p * p - 1.0);
        double df = 3.0 * p * p - 1.0 + 2.0 * ec0 * p;
        double big_phi = f - e2 * l;
        phi[i] = p;
        lap[i] = f;
        fphi[i] = df * big_phi;
        sq += big_phi * big_phi;
        sum += p;
        big = fmax(big, fabs(p));
        if (has_old) change = fmax(change, fabs(p - old[i]));
    }
    block_sum(sq, partials);
    block_sum(sum, partials + gridDim.x);
    block_max(big, partials + 2 * gridDim.x);
    block_max(change, partials + 3 * gridDim.x);
}

// The conserved flow's explicit term: nl holds FT[f'Phi] on entry and N = -2k FT[f'Phi]
// - 2 e2 k^2 FT[f] on exit (k = |k|^2), g = FT[f]. Partials: sum over k != 0 of w |mu|^2,
// mu = 2 FT[f'Phi] + 2 e2 k FT[f] + 2 e2^2 k^2 X + tension k X (when with_residual).
extern "C" __global__ void combine(const double2* hat, double2* nl, const double2* g,
                                   TABLE_ARGS, double e2, double tension, int with_residual,
                                   double* partials) {
    TABLES;
    long len = (long)t.n0 * t.n1 * t.s2;
    double res = 0.0;
    for (long m = blockIdx.x * (long)blockDim.x + threadIdx.x; m < len;
         m += (long)gridDim.x * blockDim.x) {
        double k, w;
        symbols(t, m, &k, &w);
        double fnl = -2.0 * k, fg = -2.0 * e2 * k * k;
        double gk = 2.0 * e2 * k, hk = 2.0 * e2 * e2 * k * k + tension * k;
        double2 n = nl[m], gv = g[m], h = hat[m];
        double mx = n.x * 2.0 + gv.x * gk + h.x * hk;
        double my = n.y * 2.0 + gv.y * gk + h.y * hk;
        nl[m] = d2(n.x * fnl + gv.x * fg, n.y * fnl + gv.y * fg);
        if (with_residual && k > 0.0) res += w * (mx * mx + my * my);
    }
    block_sum(res, partials);
}

// The SBDF update of one step (engines/spectral/update.rs, `Update`, laid out the same): the
// coefficients a0, a_1..a_L, b_1..b_L (history j = 1 the current step), dt and the implicit
// operator's constants.
#define MAX_LEVELS 2
struct Update {
    double a[MAX_LEVELS + 1], b[MAX_LEVELS], dt, s2, s4e2, e4x2, c_sigma;
};

// |k|^2, w, P and Q at mode m of the update u over `levels` levels of history (the current
// step's X, N and the previous step's X', N'):
// P = sum_j h_j X_j + n_j N_j,  Q = sum_j q_j X_j,  h_j = (-a_j + dt b_j S)/D, n_j = dt b_j/D,
// q_j = -dt c_sigma k^2 b_j/D,  D = a0 + dt (2 eps^4 k^3 + S),  S = s2 k + s4e2 k^2.
__device__ __forceinline__ void update_at(const Tables& t, const Update& u, long m,
                                          const double2* hat, const double2* nl,
                                          const double2* hat0, const double2* nl0, int levels,
                                          double* k, double* w, double2* p, double2* q) {
    symbols(t, m, k, w);
    double kk = *k;
    double s = u.s2 * kk + u.s4e2 * kk * kk;
    double inv = 1.0 / (u.a[0] + u.dt * (u.e4x2 * kk * kk * kk + s));
    double qc = -u.dt * u.c_sigma * kk * kk * inv;
    const double2* xs[MAX_LEVELS] = {hat, hat0};
    const double2* ns[MAX_LEVELS] = {nl, nl0};
    *p = d2(0.0, 0.0);
    *q = d2(0.0, 0.0);
    for (int j = 0; j < levels; ++j) {
        double h = (-u.a[j + 1] + u.dt * u.b[j] * s) * inv;
        double n = u.dt * u.b[j] * inv;
        double qj = u.b[j] * qc;
        double2 x = xs[j][m], y = ns[j][m];
        p->x += x.x * h + y.x * n;
        p->y += x.y * h + y.y * n;
        q->x += x.x * qj;
        q->y += x.y * qj;
    }
}

// Partials of (A_PP, A_PQ, A_QQ) = sums of a (|P|^2, Re P conj Q, |Q|^2), a = ap |k|^2 w.
extern "C" __global__ void area_quadratic(const double2* hat, const double2* nl,
                                          const double2* hat0, const double2* nl0, int levels,
                                          Update u, TABLE_ARGS, double ap, double* partials) {
    TABLES;
    long len = (long)t.n0 * t.n1 * t.s2;
    double pp = 0.0, pq = 0.0, qq = 0.0;
    for (long m = blockIdx.x * (long)blockDim.x + threadIdx.x; m < len;
         m += (long)gridDim.x * blockDim.x) {
        double k, w;
        double2 p, q;
        update_at(t, u, m, hat, nl, hat0, nl0, levels, &k, &w, &p, &q);
        double a = ap * k * w;
        pp += a * (p.x * p.x + p.y * p.y);
        pq += a * (p.x * q.x + p.y * q.y);
        qq += a * (q.x * q.x + q.y * q.y);
    }
    block_sum(pp, partials);
    block_sum(pq, partials + gridDim.x);
    block_sum(qq, partials + 2 * gridDim.x);
}

// The update X_new = P + sigma Q into out, with the inverse transforms' inputs (copy = X_new,
// lap = -|k|^2 X_new); partial sums of the new area.
extern "C" __global__ void write_update(const double2* hat, const double2* nl,
                                        const double2* hat0, const double2* nl0, int levels,
                                        Update u, TABLE_ARGS, double ap, double sigma,
                                        double2* out, double2* copy, double2* lap,
                                        double* partials) {
    TABLES;
    long len = (long)t.n0 * t.n1 * t.s2;
    double area = 0.0;
    for (long m = blockIdx.x * (long)blockDim.x + threadIdx.x; m < len;
         m += (long)gridDim.x * blockDim.x) {
        double k, w;
        double2 p, q;
        update_at(t, u, m, hat, nl, hat0, nl0, levels, &k, &w, &p, &q);
        double2 x = d2(p.x + sigma * q.x, p.y + sigma * q.y);
        out[m] = x;
        copy[m] = x;
        lap[m] = d2(-(x.x * k), -(x.y * k));
        area += ap * k * w * (x.x * x.x + x.y * x.y);
    }
    block_sum(area, partials);
}

// The mean mode: the real part of mode 0 of the update (out) and of its copy set to `value`
// (a volume ramp's target); one thread.
extern "C" __global__ void set_mean_mode(double2* out, double2* copy, double value) {
    if (blockIdx.x == 0 && threadIdx.x == 0) {
        out[0].x = value;
        copy[0].x = value;
    }
}
