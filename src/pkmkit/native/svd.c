/* pkmkit.native.kernels: batched singular values of small matrices by one-sided Jacobi
 * (Hestenes), the C twins of pkmkit.numerics.svd_kernel.singular_values and
 * pkmkit.numerics.svd_rates_kernel.singular_rates (issue 22 §3, §5: a fresh
 * `pkmkit workspace gough-stewart` then needs no Numba).
 *
 * The same statements in the same order as the Numba kernels (sequential sums, the same
 * rotation formulas, the same insertion sorts), compiled without FMA contraction and without
 * fast-math: the same bits (tests/native/test_svd.py).
 *
 * Python face (the Numba kernels' arguments, C-contiguous float64 arrays, run without the
 * GIL): singular_values(mats (N, r, c), out (N, min(r, c)));
 * singular_rates(mats (N, r, c) with r >= c, rates (N, r, c, d), sigma (N, c), out (N, c, d)). */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdlib.h>

#include "kernels.h"

/* svd_kernel.MAX_SWEEPS, svd_rates_kernel.MAX_SWEEPS */
#define PK_SVD_SWEEPS 60
#define PK_EPS 2.220446049250313e-16

/* ------------------------------------------------------------------ kernels */

/* One Jacobi rotation of the working columns wi, wj (length p) with squared norms
 * norms[i], norms[j]: 0 where they are orthogonal to tol (nothing done), else 1 with the
 * columns rotated, the norms updated and the rotation (cs, sn) out for V. Both sweep orders'
 * operations, in the Numba kernels' order. */
static inline int rotate_pair(double *wi, double *wj, ptrdiff_t p, double *norm_i,
                              double *norm_j, double tol, double *cs_out, double *sn_out) {
    double alpha = *norm_i, beta = *norm_j, gamma = 0.0;
    for (ptrdiff_t t = 0; t < p; t++) gamma += wi[t] * wj[t];
    if (gamma == 0.0 || fabs(gamma) <= tol * sqrt(alpha) * sqrt(beta)) return 0;
    double zeta = (beta - alpha) / (2.0 * gamma);
    double tn = copysign(1.0, zeta) / (fabs(zeta) + sqrt(1.0 + zeta * zeta));
    double cs = 1.0 / sqrt(1.0 + tn * tn);
    double sn = cs * tn;
    for (ptrdiff_t t = 0; t < p; t++) {
        double a = wi[t], b = wj[t];
        wi[t] = cs * a - sn * b;
        wj[t] = sn * a + cs * b;
    }
    *norm_i = alpha - tn * gamma;
    *norm_j = beta + tn * gamma;
    *cs_out = cs;
    *sn_out = sn;
    return 1;
}

/* svd_rates_kernel.jacobi_sweeps (and svd_kernel's sweeps with vmat NULL): one-sided Jacobi
 * on the k working columns of length p in work (k, p); each rotation also applied to V, whose
 * entry (i, t), t < v_len, is vmat[i * v_row + t * v_col] (V by rows: v_row = v_len,
 * v_col = 1; by columns: v_row = 1, v_col = v_len). Shared by svd.c, chain_velocity.c and
 * pose_velocity.c: one copy of the sweeps, the operations of the Numba kernels in their order. */
void pk_jacobi_sweeps(double *work, ptrdiff_t k, ptrdiff_t p, double *vmat, ptrdiff_t v_row,
                      ptrdiff_t v_col, ptrdiff_t v_len, double *norms, double tol) {
    for (int sweep = 0; sweep < PK_SVD_SWEEPS; sweep++) {
        for (ptrdiff_t i = 0; i < k; i++) {
            double s = 0.0;
            for (ptrdiff_t t = 0; t < p; t++) s += work[i * p + t] * work[i * p + t];
            norms[i] = s;
        }
        int rotated = 0;
        for (ptrdiff_t i = 0; i < k - 1; i++) {
            for (ptrdiff_t j = i + 1; j < k; j++) {
                double cs, sn;
                if (!rotate_pair(work + i * p, work + j * p, p, &norms[i], &norms[j], tol, &cs,
                                 &sn))
                    continue;
                rotated = 1;
                if (vmat) {
                    for (ptrdiff_t t = 0; t < v_len; t++) {
                        double *vi = vmat + i * v_row + t * v_col;
                        double *vj = vmat + j * v_row + t * v_col;
                        double a = *vi, b = *vj;
                        *vi = cs * a - sn * b;
                        *vj = sn * a + cs * b;
                    }
                }
            }
        }
        if (!rotated) break;
    }
}

/* svd_kernel.singular_values of one matrix mat (r, c) row-major into out (min(r, c)),
 * decreasing (NaN for a non-finite entry); work (max(r, c) * min(r, c)), norms (min(r, c)). */
void pk_singular_values_one(const double *mat, ptrdiff_t r, ptrdiff_t c, double *out,
                            double *work, double *norms) {
    int tall = r >= c;
    ptrdiff_t p = tall ? r : c; /* length of a working column */
    ptrdiff_t k = tall ? c : r; /* working columns = singular values */
    double tol = (double)p * PK_EPS;
    int finite = 1;
    for (ptrdiff_t i = 0; i < r; i++) {
        for (ptrdiff_t j = 0; j < c; j++) {
            double v = mat[i * c + j];
            if (!isfinite(v)) finite = 0;
            if (tall) work[j * p + i] = v;
            else work[i * p + j] = v;
        }
    }
    if (!finite) {
        for (ptrdiff_t i = 0; i < k; i++) out[i] = NAN;
        return;
    }
    pk_jacobi_sweeps(work, k, p, NULL, 0, 0, 0, norms, tol);
    for (ptrdiff_t i = 0; i < k; i++) {
        double s = 0.0;
        for (ptrdiff_t t = 0; t < p; t++) s += work[i * p + t] * work[i * p + t];
        norms[i] = sqrt(s);
    }
    for (ptrdiff_t i = 1; i < k; i++) { /* insertion sort, decreasing */
        double v = norms[i];
        ptrdiff_t j = i - 1;
        while (j >= 0 && norms[j] < v) {
            norms[j + 1] = norms[j];
            j--;
        }
        norms[j + 1] = v;
    }
    for (ptrdiff_t i = 0; i < k; i++) out[i] = norms[i];
}

/* The singular values of one small matrix as pk_singular_values_one computes them, but with
 * the column pairs in round-robin (tournament) order: each round rotates k/2 disjoint pairs,
 * whose arithmetic the CPU overlaps, where the cyclic order's consecutive pairs share a
 * column. The same rotations and stopping test, a convergent ordering: the same accuracy
 * (≈ 1e-15 of σ_max against the cyclic order and LAPACK), ≈ 1.5× faster on 6 x 6 — not
 * the Numba kernel's bits. For the one-pose velocity kernels' J (pose_velocity.c,
 * pose_one.c: condition, singular values); k <= 6. */
void pk_singular_values_fast(const double *mat, ptrdiff_t r, ptrdiff_t c, double *out) {
    int tall = r >= c;
    ptrdiff_t p = tall ? r : c, k = tall ? c : r;
    double work[36], norms[6], tol = (double)p * PK_EPS;
    int finite = 1;
    for (ptrdiff_t i = 0; i < r; i++) {
        for (ptrdiff_t j = 0; j < c; j++) {
            double v = mat[i * c + j];
            if (!isfinite(v)) finite = 0;
            if (tall) work[j * p + i] = v;
            else work[i * p + j] = v;
        }
    }
    if (!finite) {
        for (ptrdiff_t i = 0; i < k; i++) out[i] = NAN;
        return;
    }
    int even = (int)(k + (k & 1)), slot[6];
    for (int sweep = 0; sweep < PK_SVD_SWEEPS; sweep++) {
        for (ptrdiff_t i = 0; i < k; i++) {
            double s = 0.0;
            for (ptrdiff_t t = 0; t < p; t++) s += work[i * p + t] * work[i * p + t];
            norms[i] = s;
        }
        for (int i = 0; i < even; i++) slot[i] = i;
        int rotated = 0;
        for (int round = 0; round < even - 1; round++) {
            for (int h = 0; h < even / 2; h++) {
                int i = slot[h], j = slot[even - 1 - h];
                if (i >= k || j >= k) continue; /* the odd count's empty seat */
                if (i > j) {
                    int swap = i;
                    i = j;
                    j = swap;
                }
                double cs, sn;
                if (rotate_pair(work + i * p, work + j * p, p, &norms[i], &norms[j], tol, &cs,
                                &sn))
                    rotated = 1;
            }
            int last = slot[even - 1]; /* the seats but the first move on by one */
            for (int h = even - 1; h > 1; h--) slot[h] = slot[h - 1];
            slot[1] = last;
        }
        if (!rotated) break;
    }
    for (ptrdiff_t i = 0; i < k; i++) {
        double s = 0.0;
        for (ptrdiff_t t = 0; t < p; t++) s += work[i * p + t] * work[i * p + t];
        norms[i] = sqrt(s);
    }
    for (ptrdiff_t i = 1; i < k; i++) { /* insertion sort, decreasing */
        double v = norms[i];
        ptrdiff_t j = i - 1;
        while (j >= 0 && norms[j] < v) {
            norms[j + 1] = norms[j];
            j--;
        }
        norms[j + 1] = v;
    }
    for (ptrdiff_t i = 0; i < k; i++) out[i] = norms[i];
}

/* svd_kernel.singular_values over n matrices (r, c) row-major; out (n, min(r, c)). */
static void pk_singular_values(const double *mats, ptrdiff_t n, ptrdiff_t r, ptrdiff_t c,
                               double *out, double *work, double *norms) {
    ptrdiff_t k = r >= c ? c : r;
    for (ptrdiff_t m = 0; m < n; m++)
        pk_singular_values_one(mats + m * r * c, r, c, out + m * k, work, norms);
}

/* svd_rates_kernel.singular_rates over n tall matrices (r, c), rates (r, c, d). */
static void pk_singular_rates(const double *mats, const double *rates, ptrdiff_t n,
                              ptrdiff_t r, ptrdiff_t c, ptrdiff_t d, double *sigma, double *out,
                              double *work, double *vmat, double *norms, ptrdiff_t *order) {
    double tol = (double)r * PK_EPS;
    for (ptrdiff_t m = 0; m < n; m++) {
        const double *mat = mats + m * r * c;
        const double *rate = rates + m * r * c * d;
        double *sg = sigma + m * c, *o = out + m * c * d;
        int finite = 1; /* svd_rates_kernel._load */
        for (ptrdiff_t i = 0; i < r; i++) {
            for (ptrdiff_t j = 0; j < c; j++) {
                if (!isfinite(mat[i * c + j])) finite = 0;
                work[j * r + i] = mat[i * c + j];
                for (ptrdiff_t e = 0; e < d; e++)
                    if (!isfinite(rate[(i * c + j) * d + e])) finite = 0;
            }
        }
        if (!finite) {
            for (ptrdiff_t i = 0; i < c; i++) {
                sg[i] = NAN;
                for (ptrdiff_t e = 0; e < d; e++) o[i * d + e] = NAN;
            }
            continue;
        }
        for (ptrdiff_t i = 0; i < c; i++)
            for (ptrdiff_t j = 0; j < c; j++) vmat[i * c + j] = i == j ? 1.0 : 0.0;
        pk_jacobi_sweeps(work, c, r, vmat, c, 1, c, norms, tol);
        for (ptrdiff_t i = 0; i < c; i++) {
            double s = 0.0;
            for (ptrdiff_t t = 0; t < r; t++) s += work[i * r + t] * work[i * r + t];
            norms[i] = s;
            order[i] = i;
        }
        for (ptrdiff_t i = 1; i < c; i++) { /* insertion sort of the indices, decreasing */
            ptrdiff_t k = order[i], j = i - 1;
            while (j >= 0 && norms[order[j]] < norms[k]) {
                order[j + 1] = order[j];
                j--;
            }
            order[j + 1] = k;
        }
        for (ptrdiff_t slot = 0; slot < c; slot++) {
            ptrdiff_t i = order[slot];
            sg[slot] = sqrt(norms[i]);
            for (ptrdiff_t e = 0; e < d; e++) { /* σ̇ = w_i·(Ṁ v_i)/σ_i (_quadratic) */
                if (norms[i] > 0.0) {
                    const double *w = work + i * r, *v = vmat + i * c;
                    double acc = 0.0;
                    for (ptrdiff_t t = 0; t < r; t++) {
                        double mv = 0.0;
                        for (ptrdiff_t s = 0; s < c; s++) mv += rate[(t * c + s) * d + e] * v[s];
                        acc += w[t] * mv;
                    }
                    o[slot * d + e] = acc / sg[slot];
                } else {
                    o[slot * d + e] = NAN;
                }
            }
        }
    }
}

/* ------------------------------------------------------------------ Python face */

const char pk_singular_values_doc[] =
    "singular_values(mats, out)\n\n"
    "The C twin of pkmkit.numerics.svd_kernel.singular_values: out (N, min(r, c)), decreasing,\n"
    "of mats (N, r, c); NaN rows for matrices with a non-finite entry. C-contiguous float64\n"
    "arrays; runs without the GIL.";

PyObject *pk_py_singular_values(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 2) {
        PyErr_Format(PyExc_TypeError, "singular_values() takes 2 positional arguments "
                     "(%zd given)", nargs);
        return NULL;
    }
    Py_buffer vm, vo;
    if (pk_take(args[0], &vm, "mats", 'd', 0, 3, NULL) < 0) return NULL;
    if (pk_take(args[1], &vo, "out", 'd', 1, 2, NULL) < 0) {
        PyBuffer_Release(&vm);
        return NULL;
    }
    ptrdiff_t n = vm.shape[0], r = vm.shape[1], c = vm.shape[2];
    ptrdiff_t k = r < c ? r : c, p = r < c ? c : r;
    PyObject *result = NULL;
    if (vo.shape[0] != n || vo.shape[1] != k) {
        PyErr_SetString(PyExc_ValueError, "out: shape (N, min(r, c)) expected");
        goto done;
    }
    if (n > 0 && k > 0) {
        double *work = malloc(sizeof(double) * (size_t)(k * p + k));
        if (!work) {
            PyErr_NoMemory();
            goto done;
        }
        Py_BEGIN_ALLOW_THREADS
        pk_singular_values(vm.buf, n, r, c, vo.buf, work, work + k * p);
        Py_END_ALLOW_THREADS
        free(work);
    }
    result = Py_NewRef(Py_None);
done:
    PyBuffer_Release(&vm);
    PyBuffer_Release(&vo);
    return result;
}

const char pk_singular_rates_doc[] =
    "singular_rates(mats, rates, sigma, out)\n\n"
    "The C twin of pkmkit.numerics.svd_rates_kernel.singular_rates: sigma (N, c), decreasing,\n"
    "of tall mats (N, r, c) (r >= c) and their rates out (N, c, d) along rates (N, r, c, d);\n"
    "NaN rows for a non-finite matrix or derivative, NaN rates for a zero singular value.\n"
    "C-contiguous float64 arrays; runs without the GIL.";

PyObject *pk_py_singular_rates(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 4) {
        PyErr_Format(PyExc_TypeError, "singular_rates() takes 4 positional arguments "
                     "(%zd given)", nargs);
        return NULL;
    }
    Py_buffer v[4];
    const char *names[4] = {"mats", "rates", "sigma", "out"};
    const int ndims[4] = {3, 4, 2, 3};
    int held = 0;
    PyObject *result = NULL;
    for (; held < 4; held++)
        if (pk_take(args[held], &v[held], names[held], 'd', held >= 2, ndims[held], NULL) < 0)
            goto done;
    ptrdiff_t n = v[0].shape[0], r = v[0].shape[1], c = v[0].shape[2], d = v[1].shape[3];
    if (r < c || v[1].shape[0] != n || v[1].shape[1] != r || v[1].shape[2] != c
        || v[2].shape[0] != n || v[2].shape[1] != c || v[3].shape[0] != n
        || v[3].shape[1] != c || v[3].shape[2] != d) {
        PyErr_SetString(PyExc_ValueError, "singular_rates: mats (N, r, c) with r >= c, rates "
                        "(N, r, c, d), sigma (N, c), out (N, c, d) expected");
        goto done;
    }
    if (n > 0 && c > 0) {
        double *buf = malloc(sizeof(double) * (size_t)(c * r + c * c + c));
        ptrdiff_t *order = malloc(sizeof(ptrdiff_t) * (size_t)c);
        if (!buf || !order) {
            free(buf);
            free(order);
            PyErr_NoMemory();
            goto done;
        }
        Py_BEGIN_ALLOW_THREADS
        pk_singular_rates(v[0].buf, v[1].buf, n, r, c, d, v[2].buf, v[3].buf, buf,
                          buf + c * r, buf + c * r + c * c, order);
        Py_END_ALLOW_THREADS
        free(buf);
        free(order);
    }
    result = Py_NewRef(Py_None);
done:
    for (int i = 0; i < held; i++) PyBuffer_Release(&v[i]);
    return result;
}
