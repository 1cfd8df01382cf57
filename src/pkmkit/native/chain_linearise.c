/* The identification's kernels of joint-chain machines: the C twins of
 * pkmkit.solve.chain_kernel._linearise_rows (C_U, the defect columns C_d, the tool frame and
 * its defect twists at solved configurations) and pkmkit.solve.chain_linalg._absorb_rows
 * (dU = -C_U^+ C_d by the normal equations), statement for statement and in the same order
 * of operations (the same bits with the same libm). Matrices are row-major. */
#include "chain_face.h"

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
        pk_chain_joint_move(rot, pos, t, q);
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
