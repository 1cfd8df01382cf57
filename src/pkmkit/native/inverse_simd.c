/* The full-pose inverse model several poses at a time — four with AVX2, eight with AVX-512 —
 * for machines whose rods are all slides or struts (no cranks, so no angular actuators):
 * issue 22 §2.
 *
 * inverse_block.h holds the block kernel, included here once per width: each lane does the
 * operations of pk_inverse_poses_scalar (inverse.c) in the same order (+, -, *, /, sqrt are
 * correctly rounded at any width; no FMA: the extension builds with -ffp-contract=off), the
 * branches become selections computed both ways — except sin and cos, which are a vectorised
 * sincos (Cody-Waite reduction, fdlibm's polynomials; at most 1 ulp from libm's) instead of
 * libm's called lane by lane, which cost half the kernel; and for rotations up to 1 rad not even
 * that: sin(theta)/theta and cos(theta) by their Taylor series in theta^2 (no square root,
 * reduction or sincos; b = (1 - cos)/theta^2 as pk_rotation has it). So q may differ from the
 * scalar C, Numba and NumPy paths in its last bits (the bound is tested: tests/native/
 * test_inverse_simd.py); both widths give the same bits, and every row of a batch, the
 * last partial block included, takes the vectorised arithmetic.
 *
 * x86-64 with GCC or Clang only: each width is compiled with a target attribute and chosen at
 * run time (__builtin_cpu_supports), so the extension runs on any x86-64 (never -march=native);
 * elsewhere (other architectures, MSVC) this file only forwards to the scalar kernel. */
#include <string.h>

#include "kernels.h"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define PK_HAVE_SIMD_PATH 1
#include <immintrin.h>
#else
#define PK_HAVE_SIMD_PATH 0
#endif

/* pkmkit.native.kernels.simd(): 1 the widest the CPU has, 4 or 8 that width, 0 none. */
static int pk_simd_choice = 1;

#if PK_HAVE_SIMD_PATH

/* Rods (and actuators) the vectorised kernel takes, at most: slides and struts only. */
#define PK_SIMD_RODS 64
/* Rotation angles beyond this take libm's sin and cos (the reduction's n < 2^20). */
#define PK_TRIG_MAX 1e5
/* Rotation vectors of squared norm up to this take the Taylor series of Rodrigues'
 * coefficients (inverse_block.h: rodrigues_series), the others the sincos and two divisions. */
#define PK_SERIES_MAX 1.0

/* (lo[0], lo[1], hi[0], hi[1]) (_mm256_loadu2_m128d, which older GCCs lack). */
static inline __attribute__((target("avx2"))) __m256d pk_load_pairs(const double *lo,
                                                                    const double *hi) {
    return _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(lo)), _mm_loadu_pd(hi), 1);
}

/* Rows x (4, 6) to columns: (x0 x1) pairs of rows 0|2 and 1|3, interleaved. */
static inline __attribute__((target("avx2"))) void pk_columns4(const double *x, __m256d *cols) {
    for (int i = 0; i < 3; i++) {
        __m256d even = pk_load_pairs(x + 2 * i, x + 12 + 2 * i);
        __m256d odd = pk_load_pairs(x + 6 + 2 * i, x + 18 + 2 * i);
        cols[2 * i] = _mm256_unpacklo_pd(even, odd);
        cols[2 * i + 1] = _mm256_unpackhi_pd(even, odd);
    }
}

/* Rows x (8, 6) to columns: rows 0-3 in the low halves, 4-7 in the high ones. */
static inline __attribute__((target("avx512f,avx512dq"))) void pk_columns8(const double *x,
                                                                          __m512d *cols) {
    __m256d lo[6], hi[6];
    pk_columns4(x, lo);
    pk_columns4(x + 24, hi);
    for (int i = 0; i < 6; i++)
        cols[i] = _mm512_insertf64x4(_mm512_castpd256_pd512(lo[i]), hi[i], 1);
}

/* Vectors v[a] (4 lanes, one per actuator a < n) to rows q (4, n): one store per value. */
static inline __attribute__((target("avx2"))) void pk_rows4(const __m256d *v, ptrdiff_t n,
                                                           double *q) {
    for (ptrdiff_t a = 0; a < n; a++)
        for (int l = 0; l < 4; l++) q[n * l + a] = v[a][l];
}

/* Vectors v[a] (8 lanes, one per actuator a < n) to rows q (8, n): for n <= 8 an 8 x 8
 * transposition by unpacks and 128-bit lane shuffles (the missing vectors zero) and one
 * masked store of n values per row; wider, one store per value. */
static inline __attribute__((target("avx512f,avx512dq"))) void pk_rows8(const __m512d *v,
                                                                       ptrdiff_t n, double *q) {
    if (n > 8) {
        for (ptrdiff_t a = 0; a < n; a++)
            for (int l = 0; l < 8; l++) q[n * l + a] = v[a][l];
        return;
    }
    __m512d c[8], t[8], u[8];
    for (int a = 0; a < 8; a++) c[a] = a < n ? v[a] : _mm512_setzero_pd();
    for (int i = 0; i < 4; i++) { /* (c0[l], c1[l]) pairs: lanes 0,2,4,6 in lo, 1,3,5,7 in hi */
        t[2 * i] = _mm512_unpacklo_pd(c[2 * i], c[2 * i + 1]);
        t[2 * i + 1] = _mm512_unpackhi_pd(c[2 * i], c[2 * i + 1]);
    }
    for (int i = 0; i < 2; i++) { /* 128-bit blocks 0, 2 and 1, 3 of two pairs of actuators */
        for (int h = 0; h < 2; h++) {
            u[4 * i + h] = _mm512_shuffle_f64x2(t[4 * i + h], t[4 * i + 2 + h], 0x88);
            u[4 * i + 2 + h] = _mm512_shuffle_f64x2(t[4 * i + h], t[4 * i + 2 + h], 0xdd);
        }
    }
    const __mmask8 keep = (__mmask8)((1u << n) - 1u);
    for (int h = 0; h < 2; h++) {
        for (int j = 0; j < 2; j++) {
            __m512d lo = u[2 * j + h], hi = u[4 + 2 * j + h];
            /* rows l = h + 2 (j + 2 s) for s = 0, 1: 128-bit blocks s and s + 2 of lo, hi */
            _mm512_mask_storeu_pd(q + n * (h + 2 * j), keep, _mm512_shuffle_f64x2(lo, hi, 0x88));
            _mm512_mask_storeu_pd(q + n * (h + 2 * j + 4), keep,
                                  _mm512_shuffle_f64x2(lo, hi, 0xdd));
        }
    }
}

#define PK_W 4
#define PK_COLUMNS(x, cols) pk_columns4((x), (__m256d *)(cols))
#define PK_TGT __attribute__((target("avx2")))
#define PK_FN(name) pk_avx2_##name
typedef double vd __attribute__((vector_size(32)));
typedef int64_t vi __attribute__((vector_size(32)));
#define PK_SQRT(v) ((vd)_mm256_sqrt_pd((__m256d)(v)))
#define PK_ALL(mask) (_mm256_movemask_pd((__m256d)(mask)) == 0xF)
#define PK_STORE_ROWS(v, n, q) pk_rows4((const __m256d *)(v), (n), (q))
#include "inverse_block.h"
#undef PK_W
#undef PK_TGT
#undef PK_FN
#define vd vd8
#define vi vi8
#define PK_W 8
#undef PK_COLUMNS
#define PK_COLUMNS(x, cols) pk_columns8((x), (__m512d *)(cols))
#define PK_TGT __attribute__((target("avx512f,avx512dq")))
#define PK_FN(name) pk_avx512_##name
typedef double vd8 __attribute__((vector_size(64)));
typedef int64_t vi8 __attribute__((vector_size(64)));
#undef PK_SQRT
#define PK_SQRT(v) ((vd)_mm512_sqrt_pd((__m512d)(v)))
#undef PK_ALL
#define PK_ALL(mask) (_mm512_movepi64_mask((__m512i)(mask)) == 0xFF)
#undef PK_STORE_ROWS
#define PK_STORE_ROWS(v, n, q) pk_rows8((const __m512d *)(v), (n), (q))
#include "inverse_block.h"
#undef vd
#undef vi

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
    int avx512 = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq");
    int avx2 = __builtin_cpu_supports("avx2");
    if (pk_simd_choice == 8) return avx512 ? 8 : 0;
    if (pk_simd_choice == 4) return avx2 ? 4 : 0;
    if (pk_simd_choice == 1) return avx512 ? 8 : avx2 ? 4 : 0;
    return 0;
}

int pk_simd_sincos(const double *t, ptrdiff_t count, double *s, double *c) {
    int lanes = pk_simd_lanes();
    if (lanes == 8) pk_avx512_sincos_rows(t, count, s, c);
    if (lanes == 4) pk_avx2_sincos_rows(t, count, s, c);
    return lanes;
}

#else

int pk_simd_lanes(void) { return 0; }

int pk_simd_sincos(const double *t, ptrdiff_t count, double *s, double *c) {
    (void)t, (void)count, (void)s, (void)c;
    return 0;
}

#endif

int pk_simd_set(int choice) {
    int before = pk_simd_lanes();
    pk_simd_choice = choice;
    return before;
}

void pk_inverse_poses(const double *x, ptrdiff_t rows, const pk_rods *rods,
                      const pk_actuators *act, double *q, int64_t *status, double *rod_q) {
#if PK_HAVE_SIMD_PATH
    if (rows > 0 && pk_simd_fits(rods, act)) {
        int lanes = pk_simd_lanes();
        if (lanes == 8) {
            pk_avx512_rows(x, rows, rods, act, q, status);
            return;
        }
        if (lanes == 4) {
            pk_avx2_rows(x, rows, rods, act, q, status);
            return;
        }
    }
#endif
    pk_inverse_poses_scalar(x, rows, rods, act, q, status, rod_q);
}
