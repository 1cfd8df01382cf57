/* The vectorised full-pose inverse model, one block of PK_W poses: a template included by
 * inverse_simd.c once per width (PK_W 4 with AVX2, 8 with AVX-512), with
 *   PK_W        poses per block (lanes),
 *   PK_TGT      the function attribute (target("avx2") / target("avx512f,avx512dq")),
 *   PK_FN(name) the width's name of a function,
 *   vd, vi      PK_W doubles / int64 (GCC vector extensions),
 *   PK_SQRT(v)  the width's correctly rounded square root,
 *   PK_COLUMNS(x, cols) the block's rows x (PK_W, 6) to one vector per coordinate,
 *   PK_STORE_ROWS(v, n, q) the n vectors v (one per actuator) to the block's rows q (PK_W, n),
 *   PK_ALL(mask) whether every lane of a mask is set.
 *
 * Lane by lane the operations of pk_inverse_poses_scalar (inverse.c), in the same order
 * (+, -, *, /, sqrt correctly rounded at any width; no FMA: -ffp-contract=off), the branches
 * turned into selections, EXCEPT sin and cos: a vectorised sincos (PK_FN(sincos) below) in
 * place of libm's, and up to 1 rad the Taylor series of sin/theta and cos (PK_FN(series)),
 * so q may differ from the scalar, Numba and NumPy paths in its last bits
 * (the bound: tests/native/test_inverse_simd.py, docs/benchmarks.md "Six-axis kernels"). */

/* mask ? a : b, mask lanes all ones or all zeros (C has no vector ?:). */
static inline PK_TGT vd PK_FN(select)(vi mask, vd a, vd b) {
    return (vd)((mask & (vi)a) | (~mask & (vi)b));
}

static inline PK_TGT vd PK_FN(splat)(double v) { return (vd){0} + v; }

static inline PK_TGT vd PK_FN(sqrt)(vd v) { return PK_SQRT(v); }

static inline PK_TGT vd PK_FN(abs)(vd v) { return (vd)((vi)v & (INT64_MAX + (vi){0})); }

/* pk_max (b when b compares greater) lane by lane. */
static inline PK_TGT vd PK_FN(max)(vd a, vd b) { return PK_FN(select)(b > a, b, a); }

/* sin and cos of t (lanes >= 0, NaN-free): Cody-Waite reduction by pi/2 (fdlibm's pio2_1 and
 * pio2_2 of 33 bits, whose products by n < 2^20 are exact, then the rounded tail pio2_2t),
 * the quadrant from the rounding of t * 2/pi, and fdlibm's minimax kernels __kernel_sin and
 * __kernel_cos on |r| <= pi/4 (polynomial error below 2^-58) without their tail term. Lanes
 * beyond PK_TRIG_MAX take libm's sin and cos. Lane for lane the same operations at any width,
 * so both widths give the same bits. Against mpmath (tests/native/test_inverse_simd.py): at
 * most 1 ulp on [0, 2pi], 2.05 ulp up to PK_TRIG_MAX, never more than 1.4e-16 absolute. */
static inline PK_TGT void PK_FN(sincos)(vd t, vd *sin_out, vd *cos_out) {
    const vd magic = PK_FN(splat)(0x1.8p52); /* adding it rounds to an integer */
    vd k = t * 0x1.45f306dc9c883p-1 + magic; /* t * 2/pi */
    vd n = k - magic;
    vi quadrant = (vi)k & 3;
    vd r = ((t - n * 0x1.921fb544p+0) - n * 0x1.0b4611a6p-34) - n * 0x1.3198a2e037073p-69;
    vd z = r * r;
    vd sp = r + z * r * (-0x1.5555555555549p-3 + z * (0x1.111111110f8a6p-7 + z * (
        -0x1.a01a019c161d5p-13 + z * (0x1.71de357b1fe7dp-19 + z * (-0x1.ae5e68a2b9cebp-26 +
        z * 0x1.5d93a5acfd57cp-33)))));
    vd poly = z * (0x1.555555555554cp-5 + z * (-0x1.6c16c16c15177p-10 + z * (
        0x1.a01a019cb159p-16 + z * (-0x1.27e4f809c52adp-22 + z * (0x1.1ee9ebdb4b1c4p-29 +
        z * -0x1.8fae9be8838d4p-37)))));
    vd hz = 0.5 * z;
    vd w = 1.0 - hz;
    vd cp = w + (((1.0 - w) - hz) + z * poly);
    vi swap = (quadrant & 1) != 0;
    const vi sign = INT64_MIN + (vi){0};
    vi sin_sign = ((quadrant & 2) != 0) & sign, cos_sign = (((quadrant + 1) & 2) != 0) & sign;
    vd s = (vd)((vi)PK_FN(select)(swap, cp, sp) ^ sin_sign);
    vd c = (vd)((vi)PK_FN(select)(swap, sp, cp) ^ cos_sign);
    vi far = t > PK_TRIG_MAX;
    for (int l = 0; l < PK_W; l++) {
        if (far[l]) {
            s[l] = sin(t[l]);
            c[l] = cos(t[l]);
        }
    }
    *sin_out = s;
    *cos_out = c;
}

/* sin(theta) / theta and cos(theta) from z = theta^2 <= 1 by their Taylor series (to z^8 and
 * z^9: the next terms, 1/19! and 1/20!, are below 2^-55 of the values), in Horner's order: no
 * square root, no argument reduction, no division. Against mpmath:
 * tests/native/test_inverse_simd.py. */
static inline PK_TGT void PK_FN(series)(vd z, vd *sinc, vd *cosine) {
    *sinc = 1.0 + z * (-1.0 / 6.0 + z * (1.0 / 120.0 + z * (-1.0 / 5040.0 + z * (1.0 / 362880.0 +
        z * (-1.0 / 39916800.0 + z * (1.0 / 6227020800.0 + z * (-1.0 / 1307674368000.0 +
        z * (1.0 / 355687428096000.0))))))));
    *cosine = 1.0 + z * (-1.0 / 2.0 + z * (1.0 / 24.0 + z * (-1.0 / 720.0 + z * (1.0 / 40320.0 +
        z * (-1.0 / 3628800.0 + z * (1.0 / 479001600.0 + z * (-1.0 / 87178291200.0 +
        z * (1.0 / 20922789888000.0 + z * (-1.0 / 6402373705728000.0)))))))));
}

/* Poses x (PK_W, 6) into q (PK_W, n), status (PK_W,); rod_q: scratch of m vectors. */
static PK_TGT void PK_FN(block)(const double *x, const pk_rods *g, const pk_actuators *act,
                                double *q, int64_t *status, vd *rod_q) {
    const ptrdiff_t m = g->m, n = act->n;
    vd cols[6]; /* one vector per coordinate: rows to columns */
    PK_COLUMNS(x, cols);
    vi valid = PK_FN(abs)(cols[0]) <= 1e9;
    for (int i = 1; i < 6; i++) valid &= PK_FN(abs)(cols[i]) <= 1e9;
    for (int i = 0; i < 6; i++) cols[i] = PK_FN(select)(valid, cols[i], PK_FN(splat)(0.0));
    vd px = cols[0], py = cols[1], pz = cols[2], wx = cols[3], wy = cols[4], wz = cols[5];

    /* pk_rotation: a = sin(theta) / theta, b = (1 - cos(theta)) / theta^2 — below 1e-8 rad
     * their series' first two terms, as pk_rotation; up to 1 rad (z <= PK_SERIES_MAX) sin /
     * theta and cos by PK_FN(series), b by pk_rotation's formula (1 - cos) / theta^2 with
     * theta^2 = z (its cancellation kept: q stays within a few ulps of the libm-based paths);
     * beyond, the sincos and the divisions. */
    vd z = wx * wx + wy * wy + wz * wz;
    vi near = z <= PK_SERIES_MAX;
    vi tiny = z < 1e-16;
    vd a, cosine;
    PK_FN(series)(z, &a, &cosine);
    vd b = PK_FN(select)(tiny, 0.5 - z / 24.0,
                         (1.0 - cosine) / PK_FN(select)(tiny, PK_FN(splat)(1.0), z));
    if (!PK_ALL(near)) { /* some lane beyond 1 rad */
        vd theta = PK_FN(sqrt)(z);
        vi small = theta < 1e-8;
        vd vsn, vcs;
        PK_FN(sincos)(theta, &vsn, &vcs);
        vd safe = PK_FN(select)(small, PK_FN(splat)(1.0), theta); /* no 0/0 in unused lanes */
        vd a_far = PK_FN(select)(small, 1.0 - theta * theta / 6.0, vsn / safe);
        vd b_far = PK_FN(select)(small, 0.5 - theta * theta / 24.0, (1.0 - vcs) / (safe * safe));
        a = PK_FN(select)(near, a, a_far);
        b = PK_FN(select)(near, b, b_far);
    }
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
    vi ok = (vi){0} == 0;
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
            out = PK_FN(sqrt)(dist_sq) - g->length[j];
        } else {
            const double *ax = g->axis + 3 * j;
            vd s = wxr * ax[0] + wyr * ax[1] + wzr * ax[2];
            vd radicand = g->length_sq[j] - dist_sq + s * s;
            vi negative = radicand < 0.0;
            vi clamped = negative & (radicand > -g->boundary_tol * g->length_sq[j]);
            radicand = PK_FN(select)(clamped, PK_FN(splat)(0.0), radicand);
            out = s + g->sigma[j] * PK_FN(sqrt)(radicand);
            ok &= ~(negative & ~clamped);
        }
        ok &= out == out;
        rod_q[j] = out;
    }

    /* the actuators: the rods of each combined, their spread against the tolerance */
    vd spread = PK_FN(splat)(0.0);
    vd value[PK_SIMD_RODS];
    for (ptrdiff_t a = 0; a < n; a++) {
        const int64_t *grp = act->groups + act->width * a;
        int64_t count = act->counts[a];
        vd first = rod_q[grp[0]];
        if (count == 1) { /* mean = 0 / 1 = +0, the spread unchanged: no division */
            value[a] = first + 0.0;
            continue;
        }
        vd total = PK_FN(splat)(0.0);
        for (int64_t c = 1; c < count; c++) total += rod_q[grp[c]] - first;
        /* a power of two: the reciprocal's product is the quotient, exactly */
        vd mean = (count & (count - 1)) == 0 ? total * (1.0 / (double)count)
                                             : total / (double)count;
        spread = PK_FN(max)(spread, PK_FN(abs)(mean));
        for (int64_t c = 1; c < count; c++)
            spread = PK_FN(max)(spread, PK_FN(abs)(rod_q[grp[c]] - first - mean));
        value[a] = first + mean;
    }
    ok &= spread <= act->consistency_tol;
    ok &= valid;
    const vd nan = PK_FN(splat)(NAN);
    for (ptrdiff_t a = 0; a < n; a++) value[a] = PK_FN(select)(ok, value[a], nan);
    PK_STORE_ROWS(value, n, q);
    /* 0 OK, 1 unreachable, 4 invalid input */
    vi code = (~ok & valid & 1) | (~valid & 4);
    memcpy(status, &code, sizeof code);
}

/* rows poses (any count: the last partial block through a padded copy, so that every row
 * gets the vectorised arithmetic wherever it falls in the batch). */
static PK_TGT void PK_FN(rows)(const double *x, ptrdiff_t rows, const pk_rods *rods,
                               const pk_actuators *act, double *q, int64_t *status) {
    vd scratch[PK_SIMD_RODS];
    const ptrdiff_t n = act->n;
    ptrdiff_t k = 0;
    for (; k + PK_W <= rows; k += PK_W)
        PK_FN(block)(x + 6 * k, rods, act, q + n * k, status + k, scratch);
    if (k < rows) {
        double xs[6 * PK_W] = {0}, qs[PK_SIMD_RODS * PK_W];
        int64_t ss[PK_W];
        ptrdiff_t left = rows - k;
        memcpy(xs, x + 6 * k, sizeof(double) * 6 * (size_t)left);
        PK_FN(block)(xs, rods, act, qs, ss, scratch);
        memcpy(q + n * k, qs, sizeof(double) * (size_t)(n * left));
        memcpy(status + k, ss, sizeof(int64_t) * (size_t)left);
    }
}

/* PK_FN(sincos) over t (count,) into s, c (tests: its accuracy against an oracle). */
static PK_TGT void PK_FN(sincos_rows)(const double *t, ptrdiff_t count, double *s, double *c) {
    for (ptrdiff_t k = 0; k < count; k += PK_W) {
        vd tv = PK_FN(splat)(0.0), sv, cv;
        ptrdiff_t left = count - k < PK_W ? count - k : PK_W;
        memcpy(&tv, t + k, sizeof(double) * (size_t)left);
        PK_FN(sincos)(tv, &sv, &cv);
        memcpy(s + k, &sv, sizeof(double) * (size_t)left);
        memcpy(c + k, &cv, sizeof(double) * (size_t)left);
    }
}
