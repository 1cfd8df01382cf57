/* The velocity model of joint-chain machines at many configurations: the C twins of
 * pkmkit.solve.chain_kernel._jacobian_rows (the closure's Jacobian, chain.c's evaluate) and
 * pkmkit.solve.chain_linalg._closure_rates_rows (dU = -C_U^+ C_q, the rank and the
 * singularity measure of C_U: Householder QR, else one-sided Jacobi), statement for statement
 * and in the same order of operations (the same ranks, ratios and, with the same libm, the
 * same bits). Matrices are row-major. The module face (argument checks) is at the end. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdlib.h>
#include <string.h>

#include "kernels.h"

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

/* svd_rates_kernel.jacobi_sweeps on work (c, r) (rows: the columns of M), each rotation
 * applied to V held by columns in vmat (c, c): V's column i is vmat[., i]. */
#define MAX_SWEEPS 60
static void jacobi_sweeps(double *work, ptrdiff_t c, ptrdiff_t r, double *vmat, double *norms,
                          double tol) {
    for (int sweep = 0; sweep < MAX_SWEEPS; sweep++) {
        for (ptrdiff_t i = 0; i < c; i++) {
            double s = 0.0;
            for (ptrdiff_t t = 0; t < r; t++) s += work[i * r + t] * work[i * r + t];
            norms[i] = s;
        }
        int rotated = 0;
        for (ptrdiff_t i = 0; i < c - 1; i++) {
            for (ptrdiff_t j = i + 1; j < c; j++) {
                double alpha = norms[i];
                double beta = norms[j];
                double gamma = 0.0;
                for (ptrdiff_t t = 0; t < r; t++) gamma += work[i * r + t] * work[j * r + t];
                if (gamma == 0.0 || fabs(gamma) <= tol * sqrt(alpha) * sqrt(beta)) continue;
                rotated = 1;
                double zeta = (beta - alpha) / (2.0 * gamma);
                double tan_ = copysign(1.0, zeta) / (fabs(zeta) + sqrt(1.0 + zeta * zeta));
                double cos_ = 1.0 / sqrt(1.0 + tan_ * tan_);
                double sin_ = cos_ * tan_;
                for (ptrdiff_t t = 0; t < r; t++) {
                    double a = work[i * r + t];
                    double b = work[j * r + t];
                    work[i * r + t] = cos_ * a - sin_ * b;
                    work[j * r + t] = sin_ * a + cos_ * b;
                }
                for (ptrdiff_t t = 0; t < c; t++) { /* vmat.T[i, t] = vmat[t, i] */
                    double a = vmat[t * c + i];
                    double b = vmat[t * c + j];
                    vmat[t * c + i] = cos_ * a - sin_ * b;
                    vmat[t * c + j] = sin_ * a + cos_ * b;
                }
                norms[i] = alpha - tan_ * gamma;
                norms[j] = beta + tan_ * gamma;
            }
        }
        if (!rotated) break;
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
    jacobi_sweeps(work, c, r, vmat, norms, tol);
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

/* ---------------------------------------------------------------- linearisation */

/* chain_kernel._defect_twists: the spatial twists of element e's defects at (rot, pos),
 * appended to twists (., 6) / ids from count; the new count. */
static ptrdiff_t defect_twists(const pk_defects *d, ptrdiff_t e, const double *rot,
                               const double *pos, double *twists, int64_t *ids,
                               ptrdiff_t count) {
    for (int64_t s = d->starts[e]; s < d->starts[e + 1]; s++) {
        int64_t j = d->order[s];
        const double *l = d->local + 6 * j;
        double w0 = rot[0] * l[3] + rot[1] * l[4] + rot[2] * l[5];
        double w1 = rot[3] * l[3] + rot[4] * l[4] + rot[5] * l[5];
        double w2 = rot[6] * l[3] + rot[7] * l[4] + rot[8] * l[5];
        double v0 = rot[0] * l[0] + rot[1] * l[1] + rot[2] * l[2];
        double v1 = rot[3] * l[0] + rot[4] * l[1] + rot[5] * l[2];
        double v2 = rot[6] * l[0] + rot[7] * l[1] + rot[8] * l[2];
        double *t = twists + 6 * count;
        t[0] = v0 + (pos[1] * w2 - pos[2] * w1);
        t[1] = v1 + (pos[2] * w0 - pos[0] * w2);
        t[2] = v2 + (pos[0] * w1 - pos[1] * w0);
        t[3] = w0;
        t[4] = w1;
        t[5] = w2;
        ids[count] = j;
        count += 1;
    }
    return count;
}

/* chain_kernel._walk: (rot, pos) moved along the elements chain (n_chain,), the defects'
 * twists collected; their count. */
static ptrdiff_t walk(const pk_chain *c, const pk_defects *d, const double *values,
                      const int64_t *chain, ptrdiff_t n_chain, double *rot, double *pos,
                      double *twists, int64_t *ids) {
    double tmp[9];
    ptrdiff_t count = 0;
    for (ptrdiff_t idx = 0; idx < n_chain; idx++) {
        int64_t e = chain[idx];
        count = defect_twists(d, e, rot, pos, twists, ids, count);
        pk_chain_apply_frame(rot, pos, c->frames + 16 * e, tmp);
        int64_t t = c->types[e];
        if (t == 0) continue;
        double q = values[c->evar[e]];
        if (t == 1) {
            double cq = cos(q), sq = sin(q);
            for (int i = 0; i < 3; i++) {
                double x = rot[3 * i], y = rot[3 * i + 1];
                rot[3 * i] = cq * x + sq * y;
                rot[3 * i + 1] = cq * y - sq * x;
            }
        } else {
            for (int i = 0; i < 3; i++) pos[i] += q * rot[3 * i + 2];
        }
    }
    return count;
}

/* chain_kernel._linearise_rows over rows configurations: cu (rows, m, n) written, cd
 * (rows, m, D) and tool_tw (rows, 6, D) written at the defect columns only (the caller
 * zeroes them), tool_r (rows, 3, 3), tool_p (rows, 3). Scratch: row (n_var,), r (m,),
 * twists (D, 6), ids (D,). */
void pk_chain_linearise_rows(const pk_chain *c, const pk_defects *d, const double *values,
                             const double *u, ptrdiff_t rows, double *cu, double *cd,
                             double *tool_r, double *tool_p, double *tool_tw, double *row,
                             double *r, double *twists, int64_t *ids, pk_chain_work *w) {
    const ptrdiff_t n = c->n, m = w->m, nd = d->n_defects;
    double rx[9], rot[9], mm[9], rws[9], pos[3];
    for (ptrdiff_t k = 0; k < rows; k++) {
        const double *uk = u + n * k;
        memcpy(row, values + c->n_var * k, (size_t)c->n_var * sizeof(double));
        pk_chain_evaluate(c, row, uk, r, cu + m * n * k, w);
        pk_chain_rotvec_matrix(uk[3], uk[4], uk[5], rx);
        double *cdk = cd + m * nd * k;
        for (ptrdiff_t leg = 0; leg < c->n_legs; leg++) {
            ptrdiff_t base = 6 * leg;
            for (int i = 0; i < 3; i++) {
                pos[i] = 0.0;
                for (int j = 0; j < 3; j++) rot[3 * i + j] = i == j ? 1.0 : 0.0;
            }
            ptrdiff_t count = walk(c, d, row, c->elements + c->offsets[leg],
                                   c->offsets[leg + 1] - c->offsets[leg], rot, pos, twists,
                                   ids);
            for (int i = 0; i < 3; i++)
                for (int j = 0; j < 3; j++)
                    mm[3 * i + j] = (rot[3 * i] * rx[3 * j] + rot[3 * i + 1] * rx[3 * j + 1]
                                     + rot[3 * i + 2] * rx[3 * j + 2]);
            pk_chain_rotation_rows(mm, c->length, 1.0, rws);
            for (ptrdiff_t a = 0; a < count; a++) {
                int64_t col = ids[a];
                const double *t = twists + 6 * a;
                double w0 = t[3], w1 = t[4], w2 = t[5];
                cdk[(base + 0) * nd + col] = t[0] + (w1 * pos[2] - w2 * pos[1]);
                cdk[(base + 1) * nd + col] = t[1] + (w2 * pos[0] - w0 * pos[2]);
                cdk[(base + 2) * nd + col] = t[2] + (w0 * pos[1] - w1 * pos[0]);
                for (int i = 0; i < 3; i++)
                    cdk[(base + 3 + i) * nd + col] = (rws[3 * i] * w0 + rws[3 * i + 1] * w1
                                                      + rws[3 * i + 2] * w2);
            }
        }
        memcpy(rot, rx, sizeof rot);
        for (int i = 0; i < 3; i++) pos[i] = uk[i];
        ptrdiff_t count = walk(c, d, row, c->head, c->n_head, rot, pos, twists, ids);
        memcpy(tool_r + 9 * k, rot, sizeof rot);
        memcpy(tool_p + 3 * k, pos, sizeof pos);
        for (ptrdiff_t a = 0; a < count; a++)
            for (int i = 0; i < 6; i++) tool_tw[(6 * k + i) * nd + ids[a]] = twists[6 * a + i];
    }
}

/* chain_linalg._absorb_rows: du (n, u, d) = -C_U^+ C_d by the normal equations and rest
 * (n, r, d) = C_d + C_U du; ok[k] 0 (du, rest NaN) where a Cholesky pivot falls below
 * RANK_PIVOT of the largest diagonal entry. Scratch: h, low (u, u), g (u, d). */
#define RANK_PIVOT 1e-10
void pk_absorb_rows(const double *cu, const double *cd, ptrdiff_t n, ptrdiff_t r,
                    ptrdiff_t u, ptrdiff_t d, double *du, double *rest, unsigned char *ok,
                    double *h, double *low, double *g) {
    for (ptrdiff_t k = 0; k < n; k++) {
        const double *c_u = cu + r * u * k, *c_d = cd + r * d * k;
        double *x = du + u * d * k, *rk = rest + r * d * k;
        for (ptrdiff_t i = 0; i < u * u; i++) h[i] = 0.0;
        for (ptrdiff_t i = 0; i < u * d; i++) g[i] = 0.0;
        for (ptrdiff_t i = 0; i < r; i++) {
            for (ptrdiff_t a = 0; a < u; a++) {
                double v = c_u[i * u + a];
                for (ptrdiff_t cc = 0; cc < a + 1; cc++) h[a * u + cc] += v * c_u[i * u + cc];
                for (ptrdiff_t col = 0; col < d; col++) g[a * d + col] -= v * c_d[i * d + col];
            }
        }
        double biggest = 0.0;
        for (ptrdiff_t a = 0; a < u; a++) biggest = pk_max(biggest, h[a * u + a]);
        int good = biggest > 0.0;
        for (ptrdiff_t j = 0; j < u; j++) {
            double s = h[j * u + j];
            for (ptrdiff_t p = 0; p < j; p++) s -= low[j * u + p] * low[j * u + p];
            if (!(s > RANK_PIVOT * biggest)) {
                good = 0;
                break;
            }
            low[j * u + j] = sqrt(s);
            for (ptrdiff_t i = j + 1; i < u; i++) {
                double t = h[i * u + j];
                for (ptrdiff_t p = 0; p < j; p++) t -= low[i * u + p] * low[j * u + p];
                low[i * u + j] = t / low[j * u + j];
            }
        }
        ok[k] = (unsigned char)good;
        if (!good) {
            for (ptrdiff_t i = 0; i < u * d; i++) x[i] = NAN;
            for (ptrdiff_t i = 0; i < r * d; i++) rk[i] = NAN;
            continue;
        }
        for (ptrdiff_t i = 0; i < u; i++) {
            for (ptrdiff_t p = 0; p < i; p++) {
                double f = low[i * u + p];
                for (ptrdiff_t col = 0; col < d; col++) g[i * d + col] -= f * g[p * d + col];
            }
            double f = 1.0 / low[i * u + i];
            for (ptrdiff_t col = 0; col < d; col++) g[i * d + col] *= f;
        }
        for (ptrdiff_t i = u - 1; i >= 0; i--) {
            for (ptrdiff_t p = i + 1; p < u; p++) {
                double f = low[p * u + i];
                for (ptrdiff_t col = 0; col < d; col++) g[i * d + col] -= f * x[p * d + col];
            }
            double f = 1.0 / low[i * u + i];
            for (ptrdiff_t col = 0; col < d; col++) x[i * d + col] = g[i * d + col] * f;
        }
        for (ptrdiff_t i = 0; i < r; i++) {
            for (ptrdiff_t col = 0; col < d; col++) rk[i * d + col] = c_d[i * d + col];
            for (ptrdiff_t a = 0; a < u; a++) {
                double v = c_u[i * u + a];
                for (ptrdiff_t col = 0; col < d; col++) rk[i * d + col] += v * x[a * d + col];
            }
        }
    }
}

/* ---------------------------------------------------------------- module face */

#define HELD 20

typedef struct {
    Py_buffer views[HELD];
    int count;
} held_buffers;

static void let_go(held_buffers *held) {
    for (int i = 0; i < held->count; i++) PyBuffer_Release(&held->views[i]);
    held->count = 0;
}

/* Argument `name` as a C-contiguous native-order buffer of float64 ('d'), int64 ('i') or bool ('?') with
 * `ndim` dimensions; NULL (TypeError / ValueError set) otherwise. */
static void *grab(held_buffers *held, PyObject *obj, const char *name, char type, int writable,
                  int ndim) {
    Py_buffer *view = &held->views[held->count];
    int flags = PyBUF_C_CONTIGUOUS | PyBUF_FORMAT | (writable ? PyBUF_WRITABLE : 0);
    if (PyObject_GetBuffer(obj, view, flags) < 0) {
        PyErr_Format(PyExc_TypeError, "%s: a C-contiguous%s array is needed", name,
                     writable ? " writable" : "");
        return NULL;
    }
    held->count++;
    const char *f = view->format ? view->format : "B";
    if (f[0] == '@' || f[0] == '=' || (PY_LITTLE_ENDIAN && f[0] == '<')) f++;
    char letter = (f[0] && !f[1]) ? f[0] : 0;
    int typed = type == '?' ? (letter == '?' && view->itemsize == 1)
                : view->itemsize == 8
                  && (type == 'd' ? letter == 'd' : (letter == 'l' || letter == 'q'));
    if (!typed) {
        PyErr_Format(PyExc_TypeError, "%s: %s array expected", name,
                     type == 'd' ? "float64" : type == 'i' ? "int64" : "bool");
        return NULL;
    }
    if (view->ndim != ndim) {
        PyErr_Format(PyExc_ValueError, "%s: %d dimensions expected, not %d", name, ndim,
                     view->ndim);
        return NULL;
    }
    return view->buf;
}

static Py_ssize_t extent(const held_buffers *held, int which, int axis) {
    return held->views[which].shape[axis];
}

static int in_range(const int64_t *a, Py_ssize_t count, int64_t low, int64_t high,
                    const char *name) {
    for (Py_ssize_t i = 0; i < count; i++) {
        if (a[i] < low || a[i] >= high) {
            PyErr_Format(PyExc_ValueError, "%s[%zd] = %lld out of range [%lld, %lld)", name, i,
                         (long long)a[i], (long long)low, (long long)high);
            return -1;
        }
    }
    return 0;
}

/* The model arrays args[0..5] (chain_kernel.model_arrays: frames, types, evar, elements,
 * offsets, position) into c, checked: shapes, indices within range (position against
 * columns, known later: checked by the caller); -1 on error. */
static int take_chain(held_buffers *held, PyObject *const *args, pk_chain *c,
                      Py_ssize_t *n_elem, Py_ssize_t *n_leg_elements) {
    memset(c, 0, sizeof *c);
    c->frames = grab(held, args[0], "frames", 'd', 0, 3);
    if (!c->frames) return -1;
    *n_elem = extent(held, 0, 0);
    if (extent(held, 0, 1) != 4 || extent(held, 0, 2) != 4) {
        PyErr_SetString(PyExc_ValueError, "frames: (E, 4, 4) expected");
        return -1;
    }
    c->types = grab(held, args[1], "types", 'i', 0, 1);
    if (!c->types) return -1;
    c->evar = grab(held, args[2], "evar", 'i', 0, 1);
    if (!c->evar) return -1;
    c->elements = grab(held, args[3], "elements", 'i', 0, 1);
    if (!c->elements) return -1;
    *n_leg_elements = extent(held, 3, 0);
    c->offsets = grab(held, args[4], "offsets", 'i', 0, 1);
    if (!c->offsets) return -1;
    c->n_legs = extent(held, 4, 0) - 1;
    c->position = grab(held, args[5], "position", 'i', 0, 1);
    if (!c->position) return -1;
    c->n_var = extent(held, 5, 0);
    if (extent(held, 1, 0) != *n_elem || extent(held, 2, 0) != *n_elem || c->n_legs < 0) {
        PyErr_SetString(PyExc_ValueError, "types, evar (E,) and offsets (L + 1,) expected");
        return -1;
    }
    if (in_range(c->types, *n_elem, 0, 3, "types") < 0
        || in_range(c->elements, *n_leg_elements, 0, *n_elem, "elements") < 0
        || in_range(c->offsets, c->n_legs + 1, 0, *n_leg_elements + 1, "offsets") < 0)
        return -1;
    for (Py_ssize_t e = 0; e < *n_elem; e++) {
        if (c->types[e] != 0 && (c->evar[e] < 0 || c->evar[e] >= c->n_var)) {
            PyErr_Format(PyExc_ValueError, "evar[%zd] out of range", e);
            return -1;
        }
    }
    for (Py_ssize_t leg = 0; leg < c->n_legs; leg++) {
        if (c->offsets[leg + 1] < c->offsets[leg]) {
            PyErr_SetString(PyExc_ValueError, "offsets must not decrease");
            return -1;
        }
    }
    return 0;
}

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

const char pk_chain_linearise_rows_doc[] =
    "chain_linearise_rows(frames, types, evar, elements, offsets, position, local, order,\n"
    "                     starts, head, values, u, length, cu, cd, tool_r, tool_p, tool_tw)\n\n"
    "The C twin of pkmkit.solve.chain_kernel._linearise_rows: C_U cu (N, 6L, n), the defect\n"
    "columns cd (N, 6L, D) and the tool frame tool_r (N, 3, 3), tool_p (N, 3), its defect\n"
    "twists tool_tw (N, 6, D) at values (N, n_var) and u (N, n); cd and tool_tw are written at\n"
    "the defects' columns only (pass zeros). Runs without the GIL.";

PyObject *pk_py_chain_linearise_rows(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 18) {
        PyErr_Format(PyExc_TypeError, "chain_linearise_rows() takes 18 positional arguments "
                     "(%zd given)", nargs);
        return NULL;
    }
    held_buffers held = {.count = 0};
    pk_chain c;
    pk_defects d;
    Py_ssize_t n_elem, n_leg_elements;
    if (take_chain(&held, args, &c, &n_elem, &n_leg_elements) < 0) goto fail;
    d.local = grab(&held, args[6], "local", 'd', 0, 2);
    if (!d.local) goto fail;
    d.n_defects = extent(&held, 6, 0);
    d.order = grab(&held, args[7], "order", 'i', 0, 1);
    if (!d.order) goto fail;
    d.starts = grab(&held, args[8], "starts", 'i', 0, 1);
    if (!d.starts) goto fail;
    c.head = grab(&held, args[9], "head", 'i', 0, 1);
    if (!c.head) goto fail;
    c.n_head = extent(&held, 9, 0);
    const double *values = grab(&held, args[10], "values", 'd', 0, 2);
    if (!values) goto fail;
    Py_ssize_t rows = extent(&held, 10, 0);
    const double *u = grab(&held, args[11], "u", 'd', 0, 2);
    if (!u) goto fail;
    c.n = extent(&held, 11, 1);
    c.length = PyFloat_AsDouble(args[12]);
    if (c.length == -1.0 && PyErr_Occurred()) goto fail;
    double *cu = grab(&held, args[13], "cu", 'd', 1, 3);
    if (!cu) goto fail;
    double *cd = grab(&held, args[14], "cd", 'd', 1, 3);
    if (!cd) goto fail;
    double *tool_r = grab(&held, args[15], "tool_r", 'd', 1, 3);
    if (!tool_r) goto fail;
    double *tool_p = grab(&held, args[16], "tool_p", 'd', 1, 2);
    if (!tool_p) goto fail;
    double *tool_tw = grab(&held, args[17], "tool_tw", 'd', 1, 3);
    if (!tool_tw) goto fail;
    Py_ssize_t m = 6 * c.n_legs, nd = d.n_defects;
    if (extent(&held, 6, 1) != 6 || extent(&held, 7, 0) != nd
        || extent(&held, 8, 0) != n_elem + 1 || extent(&held, 10, 1) != c.n_var
        || extent(&held, 11, 0) != rows || c.n < 6
        || extent(&held, 12, 0) != rows || extent(&held, 12, 1) != m
        || extent(&held, 12, 2) != c.n || extent(&held, 13, 0) != rows
        || extent(&held, 13, 1) != m || extent(&held, 13, 2) != nd
        || extent(&held, 14, 0) != rows || extent(&held, 14, 1) != 3
        || extent(&held, 14, 2) != 3 || extent(&held, 15, 0) != rows
        || extent(&held, 15, 1) != 3 || extent(&held, 16, 0) != rows
        || extent(&held, 16, 1) != 6 || extent(&held, 16, 2) != nd) {
        PyErr_SetString(PyExc_ValueError, "chain_linearise_rows: local (D, 6), order (D,), "
                        "starts (E + 1,), values (N, n_var), u (N, n >= 6), cu (N, 6L, n), cd "
                        "(N, 6L, D), tool_r (N, 3, 3), tool_p (N, 3), tool_tw (N, 6, D) "
                        "expected");
        goto fail;
    }
    if (in_range(c.position, c.n_var, -1, c.n, "position") < 0
        || in_range(c.head, c.n_head, 0, n_elem, "head") < 0
        || in_range(d.order, nd, 0, nd, "order") < 0
        || in_range(d.starts, n_elem + 1, 0, nd + 1, "starts") < 0)
        goto fail;
    for (Py_ssize_t e = 0; e < n_elem; e++) {
        if (d.starts[e + 1] < d.starts[e]) {
            PyErr_SetString(PyExc_ValueError, "starts must not decrease");
            goto fail;
        }
    }
    /* the twists of one walk: at most the defects of its elements, counted with repeats */
    size_t most = 0;
    for (Py_ssize_t chain = 0; chain <= c.n_legs; chain++) {
        const int64_t *list = chain < c.n_legs ? c.elements + c.offsets[chain] : c.head;
        Py_ssize_t len = chain < c.n_legs ? c.offsets[chain + 1] - c.offsets[chain] : c.n_head;
        size_t count = 0;
        for (Py_ssize_t i = 0; i < len; i++)
            count += (size_t)(d.starts[list[i] + 1] - d.starts[list[i]]);
        if (count > most) most = count;
    }
    pk_chain_work w;
    memset(&w, 0, sizeof w);
    w.m = m;
    size_t twists = (size_t)n_leg_elements + 1;
    double *memory = malloc(sizeof(double) * ((size_t)c.n_var + 1 + (size_t)m + 6 * twists
                                              + 6 * (most + 1)));
    int64_t *indices = malloc(sizeof(int64_t) * (twists + most + 1));
    if (!memory || !indices) {
        free(memory);
        free(indices);
        PyErr_NoMemory();
        goto fail;
    }
    double *row = memory, *r = memory + c.n_var + 1;
    w.tw = r + m;
    double *defect_tw = w.tw + 6 * twists;
    w.tw_col = indices;
    Py_BEGIN_ALLOW_THREADS
    pk_chain_linearise_rows(&c, &d, values, u, rows, cu, cd, tool_r, tool_p, tool_tw, row, r,
                            defect_tw, indices + twists, &w);
    Py_END_ALLOW_THREADS
    free(memory);
    free(indices);
    let_go(&held);
    Py_RETURN_NONE;
fail:
    let_go(&held);
    return NULL;
}

const char pk_absorb_doc[] =
    "absorb(cu, cd, du, rest, ok)\n\n"
    "The C twin of pkmkit.solve.chain_linalg._absorb_rows: du (N, u, d) = -C_U^+ C_d by the\n"
    "normal equations, rest (N, r, d) = C_d + C_U du and ok (N,) bool (False: a Cholesky pivot\n"
    "below 1e-10 of the largest, du and rest NaN) of cu (N, r, u) and cd (N, r, d). Runs\n"
    "without the GIL.";

PyObject *pk_py_absorb(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 5) {
        PyErr_Format(PyExc_TypeError, "absorb() takes 5 positional arguments (%zd given)",
                     nargs);
        return NULL;
    }
    held_buffers held = {.count = 0};
    const double *cu = grab(&held, args[0], "cu", 'd', 0, 3);
    if (!cu) goto fail;
    const double *cd = grab(&held, args[1], "cd", 'd', 0, 3);
    if (!cd) goto fail;
    double *du = grab(&held, args[2], "du", 'd', 1, 3);
    if (!du) goto fail;
    double *rest = grab(&held, args[3], "rest", 'd', 1, 3);
    if (!rest) goto fail;
    unsigned char *ok = grab(&held, args[4], "ok", '?', 1, 1);
    if (!ok) goto fail;
    Py_ssize_t n = extent(&held, 0, 0), r = extent(&held, 0, 1), u = extent(&held, 0, 2);
    Py_ssize_t d = extent(&held, 1, 2);
    if (extent(&held, 1, 0) != n || extent(&held, 1, 1) != r || extent(&held, 2, 0) != n
        || extent(&held, 2, 1) != u || extent(&held, 2, 2) != d || extent(&held, 3, 0) != n
        || extent(&held, 3, 1) != r || extent(&held, 3, 2) != d || extent(&held, 4, 0) != n) {
        PyErr_SetString(PyExc_ValueError, "absorb: cu (N, r, u), cd (N, r, d), du (N, u, d), "
                        "rest (N, r, d), ok (N,) expected");
        goto fail;
    }
    double *scratch = malloc(sizeof(double) * (size_t)(2 * u * u + u * d + 1));
    if (!scratch) {
        PyErr_NoMemory();
        goto fail;
    }
    Py_BEGIN_ALLOW_THREADS
    pk_absorb_rows(cu, cd, n, r, u, d, du, rest, ok, scratch, scratch + u * u,
                   scratch + 2 * u * u);
    Py_END_ALLOW_THREADS
    free(scratch);
    let_go(&held);
    Py_RETURN_NONE;
fail:
    let_go(&held);
    return NULL;
}
