/* The kinds' closed-form starts of the joint chains over rows (issue 22 §1, §6, session 35):
 * the batch entries of chain_one_tripteor.c and chain_one_trimule.c (the one-pose C call's
 * starts), for chain_starts.closed_starts / closed_direct_starts and the one-pose Numba path
 * (chain_starts.compiled_start): one compiled function for every path, no Numba import, the
 * same bits in every process. Each row its own (no row depends on another). */
#include "chain_one.h"

#include <math.h>

/* The constants: the family's code (PK_CLOSED_*), then the kind's (start.native(params)). */
static int family(const Py_buffer *k) {
    if (k->shape[0] < 2) return 0;
    double code = ((const double *)k->buf)[0];
    return code == PK_CLOSED_TRIMULE ? PK_CLOSED_TRIMULE
           : code == PK_CLOSED_TRIPTEOR ? PK_CLOSED_TRIPTEOR : 0;
}

static void nan_row(double *u, ptrdiff_t width) {
    for (ptrdiff_t j = 0; j < width; j++) u[j] = NAN;
}

const char pk_chain_closed_rows_doc[] =
    "chain_closed_rows(constants, targets, tools, branches, out)\n\n"
    "The kind's closed-form start of the inverse model on every row: targets (N, 6) (unit\n"
    "axes), tools (N,), branches (N,) (+1, -1; 0: the branch nearest home) into out (N, w);\n"
    "NaN rows where it declines. constants: start.native(params).";

PyObject *pk_py_chain_closed_rows(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 5) {
        PyErr_Format(PyExc_TypeError, "chain_closed_rows() takes 5 positional arguments "
                     "(%zd given)", nargs);
        return NULL;
    }
    PyObject *result = NULL;
    Py_buffer vk, vx, vt, vb, vo;
    if (pk_take(args[0], &vk, "constants", 'd', 0, 1, NULL) < 0) return NULL;
    if (pk_take(args[1], &vx, "targets", 'd', 0, 2, NULL) < 0) goto free_k;
    if (pk_take(args[2], &vt, "tools", 'd', 0, 1, NULL) < 0) goto free_x;
    if (pk_take(args[3], &vb, "branches", 'd', 0, 1, NULL) < 0) goto free_t;
    if (pk_take(args[4], &vo, "out", 'd', 1, 2, NULL) < 0) goto free_b;
    ptrdiff_t n = vx.shape[0], w = vo.shape[1];
    int fam = family(&vk);
    if (!fam || vx.shape[1] != 6 || vt.shape[0] != n || vb.shape[0] != n || vo.shape[0] != n
        || w != (fam == PK_CLOSED_TRIPTEOR ? 21 : 27)) {
        PyErr_SetString(PyExc_ValueError, "chain_closed_rows: shapes or constants do not fit");
        goto free_o;
    }
    const double *k = (const double *)vk.buf + 1, *x = vx.buf, *tool = vt.buf, *br = vb.buf;
    double *out = vo.buf;
    Py_BEGIN_ALLOW_THREADS
    for (ptrdiff_t i = 0; i < n; i++) {
        double *u = out + i * w;
        int ok = fam == PK_CLOSED_TRIPTEOR
                     ? pk_one_tripteor_start(k, tool[i], x + 6 * i, br[i], u)
                     : pk_one_trimule_start(k, tool[i], x + 6 * i, br[i], u);
        if (!ok) nan_row(u, w);
    }
    Py_END_ALLOW_THREADS
    result = Py_NewRef(Py_None);
free_o:
    PyBuffer_Release(&vo);
free_b:
    PyBuffer_Release(&vb);
free_t:
    PyBuffer_Release(&vt);
free_x:
    PyBuffer_Release(&vx);
free_k:
    PyBuffer_Release(&vk);
    return result;
}

const char pk_chain_closed_direct_rows_doc[] =
    "chain_closed_direct_rows(constants, q, out)\n\n"
    "The kind's closed-form start of the direct model on every row: q (N, 5) into out (N, w);\n"
    "NaN rows where it declines. constants: start.native(params).";

PyObject *pk_py_chain_closed_direct_rows(PyObject *self, PyObject *const *args,
                                         Py_ssize_t nargs) {
    (void)self;
    if (nargs != 3) {
        PyErr_Format(PyExc_TypeError, "chain_closed_direct_rows() takes 3 positional "
                     "arguments (%zd given)", nargs);
        return NULL;
    }
    PyObject *result = NULL;
    Py_buffer vk, vq, vo;
    if (pk_take(args[0], &vk, "constants", 'd', 0, 1, NULL) < 0) return NULL;
    if (pk_take(args[1], &vq, "q", 'd', 0, 2, NULL) < 0) goto free_k;
    if (pk_take(args[2], &vo, "out", 'd', 1, 2, NULL) < 0) goto free_q;
    ptrdiff_t n = vq.shape[0], w = vo.shape[1];
    int fam = family(&vk);
    if (!fam || vq.shape[1] != 5 || vo.shape[0] != n
        || w != (fam == PK_CLOSED_TRIPTEOR ? 21 : 27)) {
        PyErr_SetString(PyExc_ValueError,
                        "chain_closed_direct_rows: shapes or constants do not fit");
        goto free_o;
    }
    const double *k = (const double *)vk.buf + 1, *qs = vq.buf;
    double *out = vo.buf;
    Py_BEGIN_ALLOW_THREADS
    for (ptrdiff_t i = 0; i < n; i++) {
        double *u = out + i * w;
        int ok = fam == PK_CLOSED_TRIPTEOR ? pk_one_tripteor_direct(k, qs + 5 * i, u)
                                           : pk_one_trimule_direct(k, qs + 5 * i, u);
        if (!ok) nan_row(u, w);
    }
    Py_END_ALLOW_THREADS
    result = Py_NewRef(Py_None);
free_o:
    PyBuffer_Release(&vo);
free_q:
    PyBuffer_Release(&vq);
free_k:
    PyBuffer_Release(&vk);
    return result;
}
