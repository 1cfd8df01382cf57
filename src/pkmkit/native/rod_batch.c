/* Batched closed-form inverse model of translational rod-leg machines (slides and struts):
 * the C twins of pkmkit.machines.kernels.inverse and reach_and_det (issue 22 §5: statuses and
 * modes at the cost of the kernel in a fresh process, which does not import Numba).
 *
 * The same operations in the same order as the Numba kernels and their NumPy reference
 * (RodClosedForm._inverse_numpy, _det_rows), compiled without FMA contraction or fast-math
 * (setup.py), so the same bits. Poses x (N, dims) C-ordered; per-leg outputs (n, N). The
 * inverse's out and the q rod_reach_det reads are (n, N) C-ordered or the transpose of a
 * C-ordered (N, n) array: a caller's ik(X, out=Q) (pkmkit.machines.out_arrays) written in
 * place, row by row, instead of into a temporary then copied.
 *
 * Python faces (arrays through the buffer protocol, C-contiguous float64 / bool; run without
 * the GIL):
 *   rod_inverse_rows(x, basis, offset, length, slide, branch, boundary_tol, out) -> bad
 *   rod_reach_det(x, q, basis, offset, centre, axis, length, slide, short_out, det_out)
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>
#include <stddef.h>

#include "kernels.h"

#define RB_MAX_LEGS 6

/* kernels.inverse: q of every leg into out (n, N); the number of non-finite outputs. */
static Py_ssize_t rb_inverse(const double *x, Py_ssize_t size, int dims, int n,
                             const double *basis, const double *offset, const double *length,
                             const char *slide, const double *branch, double tol, double *out,
                             ptrdiff_t leg_step, ptrdiff_t row_step) {
    Py_ssize_t bad = 0;
    for (int i = 0; i < n; i++) {
        const double *b = basis + (ptrdiff_t)i * dims * dims, *o = offset + i * dims;
        double u0 = b[0], u1 = b[1], v0 = b[dims], v1 = b[dims + 1];
        double u2 = 0.0, v2 = 0.0, w0 = 0.0, w1 = 0.0, w2 = 0.0, o2 = 0.0;
        if (dims == 3) {
            u2 = b[2];
            v2 = b[5];
            w0 = b[6];
            w1 = b[7];
            w2 = b[8];
            o2 = o[2];
        }
        double o0 = o[0], o1 = o[1];
        double *row = out + (ptrdiff_t)i * leg_step;
        if (slide[i] && dims == 2) {
            double length_sq = length[i] * length[i], limit = -tol * length_sq;
            double sign = branch[i];
            for (Py_ssize_t k = 0; k < size; k++) {
                double c0 = x[2 * k], c1 = x[2 * k + 1];
                double s = u0 * c0 + u1 * c1 - o0;
                double p = v0 * c0 + v1 * c1 - o1;
                double radicand = length_sq - p * p;
                radicand = (radicand < 0.0 && radicand > limit) ? 0.0 : radicand;
                double value = s + sign * sqrt(radicand);
                row[k * row_step] = value;
                bad += value - value == 0.0 ? 0 : 1;
            }
        } else if (slide[i]) {
            double length_sq = length[i] * length[i], limit = -tol * length_sq;
            double sign = branch[i];
            for (Py_ssize_t k = 0; k < size; k++) {
                double c0 = x[3 * k], c1 = x[3 * k + 1], c2 = x[3 * k + 2];
                double s = u0 * c0 + u1 * c1 + u2 * c2 - o0;
                double p = v0 * c0 + v1 * c1 + v2 * c2 - o1;
                double r = w0 * c0 + w1 * c1 + w2 * c2 - o2;
                double radicand = length_sq - (p * p + r * r);
                radicand = (radicand < 0.0 && radicand > limit) ? 0.0 : radicand;
                double value = s + sign * sqrt(radicand);
                row[k * row_step] = value;
                bad += value - value == 0.0 ? 0 : 1;
            }
        } else {
            double rod = length[i];
            for (Py_ssize_t k = 0; k < size; k++) {
                double c0 = x[dims * k], c1 = x[dims * k + 1];
                double c2 = dims == 3 ? x[3 * k + 2] : 0.0;
                double s = u0 * c0 + u1 * c1 + u2 * c2 - o0;
                double p = v0 * c0 + v1 * c1 + v2 * c2 - o1;
                double r = w0 * c0 + w1 * c1 + w2 * c2 - o2;
                double value = sqrt((p * p + r * r) + s * s) - rod; /* the reference's order */
                row[k * row_step] = value;
                bad += value - value == 0.0 ? 0 : 1;
            }
        }
    }
    return bad;
}

/* kernels.reach_and_det: the shortfalls (n, N) (-inf for struts) and det A (N,) of a square
 * machine (n = dims = 2 or 3) from its inverse q (n, N). */
static void rb_reach_det(const double *x, Py_ssize_t size, int n, const double *q,
                        ptrdiff_t leg_step, ptrdiff_t row_step, const double *basis, const double *offset, const double *centre,
                        const double *axis, const double *length, const char *slide,
                        double *short_out, double *det_out) {
    int dims = n;
    for (int i = 0; i < n; i++) {
        const double *b = basis + (ptrdiff_t)i * dims * dims, *o = offset + i * dims;
        double v0 = b[dims], v1 = b[dims + 1], v2 = 0.0, w0 = 0.0, w1 = 0.0, w2 = 0.0;
        double o2 = 0.0, o1 = o[1], rod = length[i];
        if (dims == 3) {
            v2 = b[5];
            w0 = b[6];
            w1 = b[7];
            w2 = b[8];
            o2 = o[2];
        }
        double *sh = short_out + (ptrdiff_t)i * size;
        if (!slide[i]) {
            for (Py_ssize_t k = 0; k < size; k++) sh[k] = -INFINITY;
        } else if (dims == 2) {
            for (Py_ssize_t k = 0; k < size; k++) {
                double p = v0 * x[2 * k] + v1 * x[2 * k + 1] - o1;
                sh[k] = sqrt(p * p) - rod;
            }
        } else {
            for (Py_ssize_t k = 0; k < size; k++) {
                double c0 = x[3 * k], c1 = x[3 * k + 1], c2 = x[3 * k + 2];
                double p = v0 * c0 + v1 * c1 + v2 * c2 - o1;
                double r = w0 * c0 + w1 * c1 + w2 * c2 - o2;
                sh[k] = sqrt(p * p + r * r) - rod;
            }
        }
    }
    for (Py_ssize_t k = 0; k < size; k++) {
        double a[3][3];
        for (int i = 0; i < n; i++) {
            double qi = q[(ptrdiff_t)i * leg_step + (ptrdiff_t)k * row_step];
            for (int d = 0; d < dims; d++) {
                double centre_d = centre[i * dims + d], axis_d = axis[i * dims + d];
                a[i][d] = x[dims * k + d] - (centre_d + (slide[i] ? qi : 0.0) * axis_d);
            }
        }
        if (dims == 2)
            det_out[k] = a[0][0] * a[1][1] - a[0][1] * a[1][0];
        else
            det_out[k] = (a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
                          - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
                          + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]));
    }
}

/* ------------------------------------------------------------------ Python face */

typedef struct {
    const char *name;
    char type;
    int writable, ndim;
    Py_ssize_t shape[3];
    int strided; /* a float64 (n, N) either C-ordered or the transpose of a C-ordered one */
} rb_spec;

/* A strided (n, N) float64 buffer (spec->strided): its steps in doubles between legs and
 * between rows into steps[0], steps[1]; -1 with an exception set. */
static int rb_take_strided(PyObject *obj, Py_buffer *view, const rb_spec *spec,
                           ptrdiff_t *steps) {
    int flags = PyBUF_STRIDES | PyBUF_FORMAT | (spec->writable ? PyBUF_WRITABLE : 0);
    if (PyObject_GetBuffer(obj, view, flags) < 0) {
        PyErr_Format(PyExc_TypeError, "%s: a C-contiguous%s float64 array (or the transpose "
                     "of one) is needed", spec->name, spec->writable ? " writable" : "");
        return -1;
    }
    const char *f = view->format ? view->format : "B";
    if (f[0] == '@' || f[0] == '=' || f[0] == '<') f++;
    Py_ssize_t n = spec->shape[0], size = spec->shape[1];
    int ok = f[0] == 'd' && !f[1] && view->itemsize == 8 && view->ndim == 2
             && view->shape[0] == n && view->shape[1] == size;
    if (ok) {
        Py_ssize_t s0 = view->strides[0], s1 = view->strides[1];
        int c = (n <= 1 || s0 == 8 * size) && (size <= 1 || s1 == 8);
        int t = (n <= 1 || s0 == 8) && (size <= 1 || s1 == 8 * n);
        ok = c || t;
        steps[0] = c ? size : 1;
        steps[1] = c ? 1 : n;
    }
    if (!ok) {
        PyErr_Format(PyExc_ValueError, "%s: wrong shape or layout (a float64 (n, N) array, "
                     "C-ordered or the transpose of a C-ordered (N, n) one)", spec->name);
        PyBuffer_Release(view);
        return -1;
    }
    return 0;
}

/* The buffers of args[...] per `spec` (`count` of them, args[skip] skipped: a float), held
 * in `views` (the steps of the one strided spec, if any, in `steps`); the number held, or -1
 * with an exception set. */
static int rb_take_all(PyObject *const *args, const rb_spec *spec, int count, int skip,
                       Py_buffer *views, ptrdiff_t *steps) {
    int held = 0;
    for (int j = 0; j < count; j++) {
        PyObject *obj = args[skip >= 0 && j >= skip ? j + 1 : j];
        int failed = spec[j].strided
                         ? rb_take_strided(obj, &views[held], &spec[j], steps)
                         : pk_take(obj, &views[held], spec[j].name, spec[j].type,
                                   spec[j].writable, spec[j].ndim, spec[j].shape);
        if (failed < 0) {
            for (int i = 0; i < held; i++) PyBuffer_Release(&views[i]);
            return -1;
        }
        held++;
    }
    return held;
}

/* x (N, 2 or 3) and the leg count n of basis (n, dims, dims); -1 with an exception set. */
static int rb_shape(PyObject *x_obj, PyObject *basis_obj, Py_ssize_t *size, int *dims, int *n) {
    Py_buffer view;
    Py_ssize_t any2[2] = {-1, -1}, any3[3] = {-1, -1, -1};
    if (pk_take(x_obj, &view, "x", 'd', 0, 2, any2) < 0) return -1;
    *size = view.shape[0];
    *dims = (int)view.shape[1];
    PyBuffer_Release(&view);
    if (pk_take(basis_obj, &view, "basis", 'd', 0, 3, any3) < 0) return -1;
    *n = (int)view.shape[0];
    PyBuffer_Release(&view);
    if ((*dims != 2 && *dims != 3) || *n < 1 || *n > RB_MAX_LEGS) {
        PyErr_SetString(PyExc_ValueError, "x: 2 or 3 columns and basis: 1 to 6 legs needed");
        return -1;
    }
    return 0;
}

const char pk_rod_inverse_rows_doc[] =
    "rod_inverse_rows(x, basis, offset, length, slide, branch, boundary_tol, out) -> bad\n\n"
    "The C twin of pkmkit.machines.kernels.inverse (slides and struts): x (N, dims), basis\n"
    "(n, dims, dims), offset (n, dims), length (n,), slide (n,) bool, branch (n,) +-1.0, out\n"
    "(n, N) filled (or the transpose of a C-contiguous (N, n) array); returns the number of\n"
    "non-finite outputs. C-contiguous arrays; runs\n"
    "without the GIL.";

PyObject *pk_py_rod_inverse_rows(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 8) {
        PyErr_Format(PyExc_TypeError, "rod_inverse_rows() takes 8 positional arguments "
                     "(%zd given)", nargs);
        return NULL;
    }
    Py_ssize_t size;
    int dims, n;
    if (rb_shape(args[0], args[1], &size, &dims, &n) < 0) return NULL;
    double tol = PyFloat_AsDouble(args[6]);
    if (tol == -1.0 && PyErr_Occurred()) return NULL;
    rb_spec spec[7] = {{"x", 'd', 0, 2, {size, dims}}, {"basis", 'd', 0, 3, {n, dims, dims}},
                       {"offset", 'd', 0, 2, {n, dims}}, {"length", 'd', 0, 1, {n}},
                       {"slide", '?', 0, 1, {n}}, {"branch", 'd', 0, 1, {n}},
                       {"out", 'd', 1, 2, {n, size}, 1}};
    Py_buffer v[7];
    ptrdiff_t steps[2] = {size, 1};
    int held = rb_take_all(args, spec, 7, 6, v, steps);
    if (held < 0) return NULL;
    Py_ssize_t bad;
    Py_BEGIN_ALLOW_THREADS
    bad = rb_inverse(v[0].buf, size, dims, n, v[1].buf, v[2].buf, v[3].buf, v[4].buf,
                     v[5].buf, tol, v[6].buf, steps[0], steps[1]);
    Py_END_ALLOW_THREADS
    for (int i = 0; i < held; i++) PyBuffer_Release(&v[i]);
    return PyLong_FromSsize_t(bad);
}

const char pk_rod_reach_det_doc[] =
    "rod_reach_det(x, q, basis, offset, centre, axis, length, slide, short_out, det_out)\n\n"
    "The C twin of pkmkit.machines.kernels.reach_and_det (square machines of slides and\n"
    "struts, n = dims = 2 or 3): x (N, n), q (n, N), basis (n, n, n), offset, centre, axis\n"
    "(n, n), length (n,), slide (n,) bool; short_out (n, N) and det_out (N,) filled.\n"
    "C-contiguous arrays; runs without the GIL.";

PyObject *pk_py_rod_reach_det(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 10) {
        PyErr_Format(PyExc_TypeError, "rod_reach_det() takes 10 positional arguments "
                     "(%zd given)", nargs);
        return NULL;
    }
    Py_ssize_t size;
    int dims, n;
    if (rb_shape(args[0], args[2], &size, &dims, &n) < 0) return NULL;
    if (n != dims) {
        PyErr_SetString(PyExc_ValueError, "rod_reach_det: a square machine is needed");
        return NULL;
    }
    rb_spec spec[10] = {{"x", 'd', 0, 2, {size, n}}, {"q", 'd', 0, 2, {n, size}, 1},
                        {"basis", 'd', 0, 3, {n, n, n}}, {"offset", 'd', 0, 2, {n, n}},
                        {"centre", 'd', 0, 2, {n, n}}, {"axis", 'd', 0, 2, {n, n}},
                        {"length", 'd', 0, 1, {n}}, {"slide", '?', 0, 1, {n}},
                        {"short_out", 'd', 1, 2, {n, size}}, {"det_out", 'd', 1, 1, {size}}};
    Py_buffer v[10];
    ptrdiff_t steps[2] = {size, 1};
    int held = rb_take_all(args, spec, 10, -1, v, steps);
    if (held < 0) return NULL;
    Py_BEGIN_ALLOW_THREADS
    rb_reach_det(v[0].buf, size, n, v[1].buf, steps[0], steps[1], v[2].buf, v[3].buf, v[4].buf, v[5].buf,
                 v[6].buf, v[7].buf, v[8].buf, v[9].buf);
    Py_END_ALLOW_THREADS
    for (int i = 0; i < held; i++) PyBuffer_Release(&v[i]);
    Py_RETURN_NONE;
}
