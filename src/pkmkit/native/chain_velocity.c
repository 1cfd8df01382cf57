/* The velocity model of joint-chain machines at many configurations: the C twins of
 * pkmkit.solve.chain_kernel._jacobian_rows (the closure's Jacobian, chain.c's evaluate) and
 * pkmkit.solve.chain_linalg._closure_rates_rows (dU = -C_U^+ C_q, the rank and the
 * singularity measure of C_U: Householder QR, else one-sided Jacobi), statement for statement
 * and in the same order of operations (the same ranks, ratios and, with the same libm, the
 * same bits). Matrices are row-major. The module face (argument checks) is at the end
 * (chain_face.h); the identification's kernels are in chain_linearise.c. */
#include "chain_face.h"

/* chain_kernel._jacobian_rows: out[k] (m, n) the closure's Jacobian at values[k] (n_var,) and
 * u[k] (n,); row (n_var,) scratch, r (m,) scratch. */
void pk_chain_jacobian_rows(const pk_chain *c, const double *values, const double *u,
                            ptrdiff_t rows, double *out, double *row, double *r,
                            pk_chain_work *w) {
    const ptrdiff_t n = c->n, m = w->m;
    for (ptrdiff_t k = 0; k < rows; k++) {
        memcpy(row, values + c->n_var * k, (size_t)c->n_var * sizeof(double));
        pk_chain_evaluate(c, row, u + n * k, r, out + m * n * k, w);
    }
}

/* chain_linalg._householder: QR of a (r, c) in place, applied to b (r, k); 0 where a column
 * is zero. */
static int householder(double *a, ptrdiff_t r, ptrdiff_t c, double *b, ptrdiff_t k) {
    for (ptrdiff_t j = 0; j < c; j++) {
        double norm = 0.0;
        for (ptrdiff_t i = j; i < r; i++) norm += a[i * c + j] * a[i * c + j];
        norm = sqrt(norm);
        if (norm == 0.0) return 0;
        double alpha = a[j * c + j] >= 0 ? -norm : norm;
        double v0 = a[j * c + j] - alpha;
        double vtv = v0 * v0;
        for (ptrdiff_t i = j + 1; i < r; i++) vtv += a[i * c + j] * a[i * c + j];
        a[j * c + j] = v0;
        for (ptrdiff_t col = j + 1; col < c; col++) {
            double s = 0.0;
            for (ptrdiff_t i = j; i < r; i++) s += a[i * c + j] * a[i * c + col];
            s *= 2.0 / vtv;
            for (ptrdiff_t i = j; i < r; i++) a[i * c + col] -= s * a[i * c + j];
        }
        for (ptrdiff_t col = 0; col < k; col++) {
            double s = 0.0;
            for (ptrdiff_t i = j; i < r; i++) s += a[i * c + j] * b[i * k + col];
            s *= 2.0 / vtv;
            for (ptrdiff_t i = j; i < r; i++) b[i * k + col] -= s * a[i * c + j];
        }
        a[j * c + j] = alpha;
    }
    return 1;
}

/* chain_linalg._qr_rates: du_m (c, k) = -R^-1 (Q' b)[:c] and the bound 1 / (|R|_F |R^-1|_F)
 * when it exceeds threshold, else -1. */
static double qr_rates(double *a, ptrdiff_t r, ptrdiff_t c, double *b, ptrdiff_t k,
                       double *rinv, double *du_m, double threshold) {
    if (!householder(a, r, c, b, k)) return -1.0;
    double frob = 0.0, frob_inv = 0.0;
    for (ptrdiff_t i = 0; i < c; i++)
        for (ptrdiff_t j = i; j < c; j++) frob += a[i * c + j] * a[i * c + j];
    for (ptrdiff_t j = 0; j < c; j++) {
        for (ptrdiff_t i = c - 1; i >= 0; i--) {
            double t = i == j ? 1.0 : 0.0;
            if (i > j) {
                rinv[i * c + j] = 0.0;
                continue;
            }
            for (ptrdiff_t p = i + 1; p < j + 1; p++) t -= a[i * c + p] * rinv[p * c + j];
            rinv[i * c + j] = t / a[i * c + i];
            frob_inv += rinv[i * c + j] * rinv[i * c + j];
        }
    }
    double bound = 1.0 / sqrt(frob * frob_inv);
    if (!(bound > threshold)) return -1.0;
    for (ptrdiff_t i = 0; i < c; i++) {
        for (ptrdiff_t col = 0; col < k; col++) {
            double s = 0.0;
            for (ptrdiff_t p = i; p < c; p++) s += rinv[i * c + p] * b[p * k + col];
            du_m[i * k + col] = -s;
        }
    }
    return bound;
}

/* chain_linalg._jacobi_rates: singular values sv (decreasing) and du_m = -C_U^+ C_q. */
static void jacobi_rates(const double *cu_m, const double *cq_m, ptrdiff_t r, ptrdiff_t c,
                         ptrdiff_t k, double rcond, double *work, double *vmat, double *norms,
                         double *sv, double *du_m) {
    double tol = (double)r * 2.220446049250313e-16;
    for (ptrdiff_t i = 0; i < r; i++)
        for (ptrdiff_t j = 0; j < c; j++) work[j * r + i] = cu_m[i * c + j];
    for (ptrdiff_t i = 0; i < c; i++)
        for (ptrdiff_t j = 0; j < c; j++) vmat[i * c + j] = i == j ? 1.0 : 0.0;
    /* svd_rates_kernel.jacobi_sweeps, V held by columns: V's column i is vmat[., i] */
    pk_jacobi_sweeps(work, c, r, vmat, 1, c, c, norms, tol);
    double biggest = 0.0;
    for (ptrdiff_t i = 0; i < c; i++) {
        double s = 0.0;
        for (ptrdiff_t t = 0; t < r; t++) s += work[i * r + t] * work[i * r + t];
        norms[i] = sqrt(s);
        biggest = pk_max(biggest, norms[i]);
        sv[i] = norms[i];
    }
    for (ptrdiff_t i = 1; i < c; i++) {
        double v = sv[i];
        ptrdiff_t j = i - 1;
        while (j >= 0 && sv[j] < v) {
            sv[j + 1] = sv[j];
            j -= 1;
        }
        sv[j + 1] = v;
    }
    for (ptrdiff_t i = 0; i < c * k; i++) du_m[i] = 0.0;
    double cutoff = rcond * biggest;
    for (ptrdiff_t a = 0; a < c; a++) {
        double s_a = norms[a];
        if (!(s_a > cutoff)) continue;
        double f = -1.0 / (s_a * s_a);
        for (ptrdiff_t col = 0; col < k; col++) {
            double g = 0.0;
            for (ptrdiff_t t = 0; t < r; t++) g += work[a * r + t] * cq_m[t * k + col];
            g *= f;
            for (ptrdiff_t i = 0; i < c; i++) du_m[i * k + col] += vmat[i * c + a] * g;
        }
    }
}

/* chain_linalg._closure_rates_rows over n rows of cu (n, r, c) and cq (n, r, k); scratch:
 * a (r, c), b (r, k), rinv (c, c), work (c, r), vmat (c, c), norms (c,), sv (c,). */
void pk_closure_rates_rows(const double *cu, const double *cq, ptrdiff_t n, ptrdiff_t r,
                           ptrdiff_t c, ptrdiff_t k, double rcond, double tol,
                           int64_t expected, double *du, int64_t *rank, double *ratio,
                           double *scratch) {
    double *a = scratch, *b = a + r * c, *rinv = b + r * k, *work = rinv + c * c;
    double *vmat = work + c * r, *norms = vmat + c * c, *sv = norms + c;
    double threshold = pk_max(tol, rcond);
    for (ptrdiff_t m = 0; m < n; m++) {
        const double *cu_m = cu + m * r * c, *cq_m = cq + m * r * k;
        double *du_m = du + m * c * k;
        int finite = 1;
        for (ptrdiff_t i = 0; i < r; i++) {
            for (ptrdiff_t j = 0; j < c; j++) finite = finite && isfinite(cu_m[i * c + j]);
            for (ptrdiff_t j = 0; j < k; j++) finite = finite && isfinite(cq_m[i * k + j]);
        }
        if (!finite) {
            for (ptrdiff_t i = 0; i < c * k; i++) du_m[i] = NAN;
            ratio[m] = NAN;
            rank[m] = 0;
            continue;
        }
        if (expected == c) {
            memcpy(a, cu_m, (size_t)(r * c) * sizeof(double));
            memcpy(b, cq_m, (size_t)(r * k) * sizeof(double));
            double bound = qr_rates(a, r, c, b, k, rinv, du_m, threshold);
            if (bound > 0.0) {
                rank[m] = c;
                ratio[m] = bound;
                continue;
            }
        }
        jacobi_rates(cu_m, cq_m, r, c, k, rcond, work, vmat, norms, sv, du_m);
        int64_t count = 0;
        for (ptrdiff_t i = 0; i < c; i++)
            if (sv[i] > rcond * sv[0]) count += 1;
        rank[m] = count;
        /* Numba's sv[expected - 1] wraps a negative index (expected 0: the last entry) */
        ptrdiff_t e = (ptrdiff_t)expected - 1;
        ratio[m] = sv[e < 0 ? e + c : e] / sv[0];
    }
}

/* ---------------------------------------------------------------- module face */

const char pk_chain_jacobian_rows_doc[] =
    "chain_jacobian_rows(frames, types, evar, elements, offsets, position, values, u, length,\n"
    "                    out)\n\n"
    "The C twin of pkmkit.solve.chain_kernel._jacobian_rows: out (N, 6L, n) the closure's\n"
    "Jacobian at values (N, n_var) and u (N, n) (platform increments, then the variables whose\n"
    "position (n_var,) is >= 6); frames (E, 4, 4), types, evar (E,), elements (K,), offsets\n"
    "(L + 1,) int64. Runs without the GIL.";

PyObject *pk_py_chain_jacobian_rows(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 10) {
        PyErr_Format(PyExc_TypeError, "chain_jacobian_rows() takes 10 positional arguments "
                     "(%zd given)", nargs);
        return NULL;
    }
    held_buffers held = {.count = 0};
    pk_chain c;
    Py_ssize_t n_elem, n_leg_elements;
    if (take_chain(&held, args, &c, &n_elem, &n_leg_elements) < 0) goto fail;
    const double *values = grab(&held, args[6], "values", 'd', 0, 2);
    if (!values) goto fail;
    Py_ssize_t rows = extent(&held, 6, 0);
    const double *u = grab(&held, args[7], "u", 'd', 0, 2);
    if (!u) goto fail;
    c.n = extent(&held, 7, 1);
    c.length = PyFloat_AsDouble(args[8]);
    if (c.length == -1.0 && PyErr_Occurred()) goto fail;
    double *out = grab(&held, args[9], "out", 'd', 1, 3);
    if (!out) goto fail;
    if (extent(&held, 6, 1) != c.n_var || extent(&held, 7, 0) != rows || c.n < 6
        || extent(&held, 8, 0) != rows || extent(&held, 8, 1) != 6 * c.n_legs
        || extent(&held, 8, 2) != c.n) {
        PyErr_SetString(PyExc_ValueError, "chain_jacobian_rows: values (N, n_var); u "
                        "(N, n >= 6); out (N, 6L, n) expected");
        goto fail;
    }
    if (in_range(c.position, c.n_var, -1, c.n, "position") < 0) goto fail;
    pk_chain_work w;
    memset(&w, 0, sizeof w);
    w.m = 6 * c.n_legs;
    size_t twists = (size_t)n_leg_elements + 1;
    double *memory = malloc(sizeof(double) * ((size_t)c.n_var + 1 + (size_t)w.m + 6 * twists));
    int64_t *indices = malloc(sizeof(int64_t) * twists);
    if (!memory || !indices) {
        free(memory);
        free(indices);
        PyErr_NoMemory();
        goto fail;
    }
    double *row = memory, *r = memory + c.n_var + 1;
    w.tw = r + w.m;
    w.tw_col = indices;
    Py_BEGIN_ALLOW_THREADS
    pk_chain_jacobian_rows(&c, values, u, rows, out, row, r, &w);
    Py_END_ALLOW_THREADS
    free(memory);
    free(indices);
    let_go(&held);
    Py_RETURN_NONE;
fail:
    let_go(&held);
    return NULL;
}

const char pk_closure_rates_doc[] =
    "closure_rates(cu, cq, rcond, tol, expected, du, rank, ratio)\n\n"
    "The C twin of pkmkit.solve.chain_linalg._closure_rates_rows: du (N, c, k) = -C_U^+ C_q,\n"
    "rank (N,) int64 and ratio (N,) of closure Jacobians cu (N, r, c) (r >= c) and cq\n"
    "(N, r, k). Runs without the GIL.";

PyObject *pk_py_closure_rates(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 8) {
        PyErr_Format(PyExc_TypeError, "closure_rates() takes 8 positional arguments "
                     "(%zd given)", nargs);
        return NULL;
    }
    held_buffers held = {.count = 0};
    const double *cu = grab(&held, args[0], "cu", 'd', 0, 3);
    if (!cu) goto fail;
    const double *cq = grab(&held, args[1], "cq", 'd', 0, 3);
    if (!cq) goto fail;
    Py_ssize_t n = extent(&held, 0, 0), r = extent(&held, 0, 1), c = extent(&held, 0, 2);
    Py_ssize_t k = extent(&held, 1, 2);
    double rcond = PyFloat_AsDouble(args[2]);
    if (rcond == -1.0 && PyErr_Occurred()) goto fail;
    double tol = PyFloat_AsDouble(args[3]);
    if (tol == -1.0 && PyErr_Occurred()) goto fail;
    long long expected = PyLong_AsLongLong(args[4]);
    if (expected == -1 && PyErr_Occurred()) goto fail;
    double *du = grab(&held, args[5], "du", 'd', 1, 3);
    if (!du) goto fail;
    int64_t *rank = grab(&held, args[6], "rank", 'i', 1, 1);
    if (!rank) goto fail;
    double *ratio = grab(&held, args[7], "ratio", 'd', 1, 1);
    if (!ratio) goto fail;
    if (extent(&held, 1, 0) != n || extent(&held, 1, 1) != r || r < c || c < 1
        || extent(&held, 2, 0) != n || extent(&held, 2, 1) != c || extent(&held, 2, 2) != k
        || extent(&held, 3, 0) != n || extent(&held, 4, 0) != n || expected > c
        || expected < -c + 1) {
        PyErr_SetString(PyExc_ValueError, "closure_rates: cu (N, r, c) with r >= c >= 1, cq "
                        "(N, r, k), du (N, c, k), rank and ratio (N,), expected <= c expected");
        goto fail;
    }
    double *scratch = malloc(sizeof(double) * (size_t)(2 * r * c + r * k + 2 * c * c + 2 * c));
    if (!scratch) {
        PyErr_NoMemory();
        goto fail;
    }
    Py_BEGIN_ALLOW_THREADS
    pk_closure_rates_rows(cu, cq, n, r, c, k, rcond, tol, (int64_t)expected, du, rank, ratio,
                          scratch);
    Py_END_ALLOW_THREADS
    free(scratch);
    let_go(&held);
    Py_RETURN_NONE;
fail:
    let_go(&held);
    return NULL;
}
