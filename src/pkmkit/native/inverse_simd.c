/* The full-pose inverse model four poses at a time (AVX2), for machines whose rods are all
 * slides or struts (no cranks, so no angular actuators): issue 22 §2.
 *
 * The same operations as pk_inverse_poses_scalar (inverse.c), in the same order, lane by lane:
 * each lane of a vector operation is the IEEE operation of the scalar kernel (+, -, *, /, sqrt
 * are correctly rounded whatever the width; no FMA: AVX2 alone does not enable it and the
 * extension builds with -ffp-contract=off), the branches become selections computed both
 * ways, and sin/cos stay libm's, called per lane (a vectorised sincos would not give libm's
 * bits). So the results are bit for bit those of the scalar C and Numba kernels
 * (tests/native/test_inverse_simd.py).
 *
 * x86-64 with GCC or Clang only: the AVX2 function is compiled with a target attribute and
 * chosen at run time (__builtin_cpu_supports), so the extension runs on any x86-64; elsewhere
 * (other architectures, MSVC) this file only forwards to the scalar kernel. */
#include "kernels.h"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define PK_HAVE_AVX2_PATH 1
#include <immintrin.h>
#else
#define PK_HAVE_AVX2_PATH 0
#endif

/* pkmkit.native.kernels.simd(): the tests switch the vectorised path off to compare. */
static int pk_simd_enabled = 1;

#if PK_HAVE_AVX2_PATH

#define PK_LANES 4
/* Rods (and actuators) the vectorised kernel takes, at most: slides and struts only. */
#define PK_SIMD_RODS 64
#define PK_AVX2 __attribute__((target("avx2")))

typedef double vd __attribute__((vector_size(32)));
typedef int64_t vi __attribute__((vector_size(32)));

/* mask ? a : b, mask lanes all ones or all zeros (C has no vector ?:). */
static inline PK_AVX2 vd pk_select(vi mask, vd a, vd b) {
    return (vd)((mask & (vi)a) | (~mask & (vi)b));
}

static inline PK_AVX2 vd pk_vsqrt(vd v) { return (vd)_mm256_sqrt_pd((__m256d)v); }

static inline PK_AVX2 vd pk_vabs(vd v) {
    const vi magnitude = {INT64_MAX, INT64_MAX, INT64_MAX, INT64_MAX};
    return (vd)((vi)v & magnitude);
}

/* pk_max (b when b compares greater) lane by lane. */
static inline PK_AVX2 vd pk_vmax(vd a, vd b) { return pk_select(b > a, b, a); }

static inline PK_AVX2 vd pk_splat(double v) { return (vd){v, v, v, v}; }

/* (lo[0], lo[1], hi[0], hi[1]) (_mm256_loadu2_m128d, which older GCCs lack). */
static inline PK_AVX2 __m256d pk_load_pairs(const double *lo, const double *hi) {
    return _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(lo)), _mm_loadu_pd(hi), 1);
}

/* Poses x (4, 6) (rows k..k+3 of the batch) into q (4, n), status (4,); rod_q: scratch of m
 * vectors. */
static PK_AVX2 void pk_block(const double *x, const pk_rods *g, const pk_actuators *act,
                             double *q, int64_t *status, vd *rod_q) {
    const ptrdiff_t m = g->m, n = act->n;
    /* rows k..k+3 (AoS) to one vector per coordinate: (x0 x1) pairs of rows 0|2 and 1|3,
     * interleaved */
    vd cols[6];
    for (int i = 0; i < 3; i++) {
        __m256d even = pk_load_pairs(x + 2 * i, x + 12 + 2 * i);
        __m256d odd = pk_load_pairs(x + 6 + 2 * i, x + 18 + 2 * i);
        cols[2 * i] = (vd)_mm256_unpacklo_pd(even, odd);
        cols[2 * i + 1] = (vd)_mm256_unpackhi_pd(even, odd);
    }
    vi valid = pk_vabs(cols[0]) <= 1e9;
    for (int i = 1; i < 6; i++) valid &= pk_vabs(cols[i]) <= 1e9;
    for (int i = 0; i < 6; i++) cols[i] = pk_select(valid, cols[i], pk_splat(0.0)); /* dropped */
    vd px = cols[0], py = cols[1], pz = cols[2], wx = cols[3], wy = cols[4], wz = cols[5];

    /* pk_rotation */
    vd theta = pk_vsqrt(wx * wx + wy * wy + wz * wz);
    vi small = theta < 1e-8;
    double sn[PK_LANES], cs[PK_LANES];
    for (int l = 0; l < PK_LANES; l++) {
        double t = theta[l];
        sn[l] = t < 1e-8 ? 0.0 : sin(t);
        cs[l] = t < 1e-8 ? 1.0 : cos(t);
    }
    vd vsn = {sn[0], sn[1], sn[2], sn[3]}, vcs = {cs[0], cs[1], cs[2], cs[3]};
    vd safe = pk_select(small, pk_splat(1.0), theta); /* no 0/0 in the unused lanes */
    vd a = pk_select(small, 1.0 - theta * theta / 6.0, vsn / safe);
    vd b = pk_select(small, 0.5 - theta * theta / 24.0, (1.0 - vcs) / (safe * safe));
    vd r0 = 1.0 - b * (wy * wy + wz * wz);
    vd r4 = 1.0 - b * (wx * wx + wz * wz);
    vd r8 = 1.0 - b * (wx * wx + wy * wy);
    vd r1 = b * wx * wy - a * wz;
    vd r3 = b * wx * wy + a * wz;
    vd r2 = b * wx * wz + a * wy;
    vd r6 = b * wx * wz - a * wy;
    vd r5 = b * wy * wz - a * wx;
    vd r7 = b * wy * wz + a * wx;

    /* pose_rods, slides and struts */
    vi ok = {-1, -1, -1, -1};
    for (ptrdiff_t j = 0; j < m; j++) {
        const double *bp = g->platform + 3 * j;
        double bx = bp[0], by = bp[1], bz = bp[2];
        vd qx = px + r0 * bx + r1 * by + r2 * bz;
        vd qy = py + r3 * bx + r4 * by + r5 * bz;
        vd qz = pz + r6 * bx + r7 * by + r8 * bz;
        const double *a0 = g->base + 3 * j;
        vd wxr = qx - a0[0], wyr = qy - a0[1], wzr = qz - a0[2];
        vd dist_sq = wxr * wxr + wyr * wyr + wzr * wzr;
        vd out;
        if (g->kind[j] == 1) { /* strut */
            out = pk_vsqrt(dist_sq) - g->length[j];
        } else {
            const double *ax = g->axis + 3 * j;
            vd s = wxr * ax[0] + wyr * ax[1] + wzr * ax[2];
            vd radicand = g->length_sq[j] - dist_sq + s * s;
            vi negative = radicand < 0.0;
            vi clamped = negative & (radicand > -g->boundary_tol * g->length_sq[j]);
            radicand = pk_select(clamped, pk_splat(0.0), radicand);
            out = s + g->sigma[j] * pk_vsqrt(radicand);
            ok &= ~(negative & ~clamped);
        }
        ok &= out == out;
        rod_q[j] = out;
    }

    /* the actuators: the rods of each combined, their spread against the tolerance */
    vd spread = pk_splat(0.0);
    vd value[PK_SIMD_RODS];
    for (ptrdiff_t a = 0; a < n; a++) {
        const int64_t *grp = act->groups + act->width * a;
        int64_t count = act->counts[a];
        vd first = rod_q[grp[0]];
        vd total = pk_splat(0.0);
        for (int64_t c = 1; c < count; c++) total += rod_q[grp[c]] - first;
        vd mean = total / (double)count;
        spread = pk_vmax(spread, pk_vabs(mean));
        for (int64_t c = 1; c < count; c++)
            spread = pk_vmax(spread, pk_vabs(rod_q[grp[c]] - first - mean));
        value[a] = first + mean;
    }
    ok &= spread <= act->consistency_tol;
    ok &= valid;
    const vd nan = pk_splat(NAN);
    for (ptrdiff_t a = 0; a < n; a++) {
        vd v = pk_select(ok, value[a], nan);
        for (int l = 0; l < PK_LANES; l++) q[n * l + a] = v[l];
    }
    /* 0 OK, 1 unreachable, 4 invalid input */
    vi one = {1, 1, 1, 1}, four = {4, 4, 4, 4};
    vi code = (~ok & valid & one) | (~valid & four);
    _mm256_storeu_si256((__m256i *)status, (__m256i)code);
}

static PK_AVX2 void pk_inverse_poses_avx2(const double *x, ptrdiff_t rows, const pk_rods *rods,
                                          const pk_actuators *act, double *q, int64_t *status,
                                          vd *rod_q) {
    for (ptrdiff_t k = 0; k < rows; k += PK_LANES)
        pk_block(x + 6 * k, rods, act, q + act->n * k, status + k, rod_q);
}

static int pk_simd_fits(const pk_rods *rods, const pk_actuators *act) {
    if (rods->m > PK_SIMD_RODS || act->n > PK_SIMD_RODS) return 0;
    for (ptrdiff_t j = 0; j < rods->m; j++)
        if (rods->kind[j] != 0 && rods->kind[j] != 1) return 0;
    for (ptrdiff_t a = 0; a < act->n; a++)
        if (act->angular[a]) return 0;
    return 1;
}

int pk_simd_lanes(void) {
    __builtin_cpu_init();
    return pk_simd_enabled && __builtin_cpu_supports("avx2") ? PK_LANES : 0;
}

#else

int pk_simd_lanes(void) { return 0; }

#endif

int pk_simd_set(int enabled) {
    int before = pk_simd_enabled;
    pk_simd_enabled = enabled;
    return before;
}

void pk_inverse_poses(const double *x, ptrdiff_t rows, const pk_rods *rods,
                      const pk_actuators *act, double *q, int64_t *status, double *rod_q) {
#if PK_HAVE_AVX2_PATH
    if (rows >= PK_LANES && pk_simd_lanes() && pk_simd_fits(rods, act)) {
        vd scratch[PK_SIMD_RODS];
        ptrdiff_t blocks = rows - rows % PK_LANES;
        pk_inverse_poses_avx2(x, blocks, rods, act, q, status, scratch);
        x += 6 * blocks;
        q += act->n * blocks;
        status += blocks;
        rows -= blocks;
    }
#endif
    pk_inverse_poses_scalar(x, rows, rods, act, q, status, rod_q);
}
