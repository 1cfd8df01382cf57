/* plain_numbers.c: the one reader of "plain numbers" shared by the one-pose C entries
 * (rod_one.c, pose_one.c, chain_one.c), and the one new-array helper they (and velocity.c's
 * rod_field) answer with.
 *
 * The rule, the same for every machine family (docs/architecture.md, "plain numbers"):
 *   - a list or tuple (exact types) of `count` items, each a float (a float subclass too:
 *     NumPy's float64, the items of list(array), whose value NumPy reads the same way) or
 *     an exact int (not a bool): TAKEN. A huge int (beyond any double) is beyond max_abs:
 *     REFUSED. Any other item (bool, NumPy's int64/float32 scalars, a string) or another
 *     length: REFUSED;
 *   - an object with the buffer protocol of format float64 or int64 (native byte order),
 *     1-D of `count` entries and any stride: TAKEN (an int64 entry is rounded to the
 *     double NumPy's astype(float) gives); float64/int64 of another shape: REFUSED; any
 *     other buffer (float32, int32, big-endian, bytes): OTHER;
 *   - any other object (a string, None, a dict, a number): REFUSED;
 *   - a value not finite or beyond +-max_abs: REFUSED.
 * REFUSED: the caller answers None and the family's batch path decides (its typed error or
 * its answer); OTHER: the family's Python one-pose path (or the batch path) converts it. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdint.h>
#include <string.h>

#include "kernels.h"

PyObject *pk_numpy_empty(void); /* velocity.c */

static int in_range(double v, double max_abs) { return -max_abs <= v && v <= max_abs; }

static int read_items(PyObject *x, Py_ssize_t count, double max_abs, double *out) {
    if (PySequence_Fast_GET_SIZE(x) != count) return PK_PLAIN_REFUSED;
    PyObject **items = PySequence_Fast_ITEMS(x);
    for (Py_ssize_t i = 0; i < count; i++) {
        PyObject *v = items[i];
        if (PyFloat_Check(v)) { /* its C value, as numpy.asarray reads it */
            out[i] = PyFloat_AS_DOUBLE(v);
        } else if (PyLong_CheckExact(v)) { /* bool is a subclass: not exact */
            out[i] = PyLong_AsDouble(v);
            if (out[i] == -1.0 && PyErr_Occurred()) {
                if (!PyErr_ExceptionMatches(PyExc_OverflowError)) return -1;
                PyErr_Clear();
                return PK_PLAIN_REFUSED; /* beyond any double: beyond max_abs */
            }
        } else {
            return PK_PLAIN_REFUSED;
        }
        if (!in_range(out[i], max_abs)) return PK_PLAIN_REFUSED;
    }
    return PK_PLAIN_TAKEN;
}

int pk_plain_numbers(PyObject *x, Py_ssize_t count, double max_abs, double *out) {
    if (PyList_CheckExact(x) || PyTuple_CheckExact(x)) return read_items(x, count, max_abs, out);
    if (!PyObject_CheckBuffer(x)) return PK_PLAIN_REFUSED;
    Py_buffer view;
    if (PyObject_GetBuffer(x, &view, PyBUF_RECORDS_RO) < 0) {
        PyErr_Clear();
        return PK_PLAIN_OTHER;
    }
    const char *f = view.format ? view.format : "B";
    if (f[0] == '@' || f[0] == '=' || (PY_LITTLE_ENDIAN && f[0] == '<')
        || (!PY_LITTLE_ENDIAN && (f[0] == '>' || f[0] == '!')))
        f++;
    int integer = (f[0] == 'l' || f[0] == 'q') && !f[1] && view.itemsize == 8;
    int real = f[0] == 'd' && !f[1] && view.itemsize == 8;
    int status = PK_PLAIN_OTHER;
    if (integer || real) {
        status = PK_PLAIN_TAKEN;
        if (view.ndim != 1 || view.shape[0] != count) status = PK_PLAIN_REFUSED;
        for (Py_ssize_t i = 0; status == PK_PLAIN_TAKEN && i < count; i++) {
            const char *at = (const char *)view.buf + i * view.strides[0];
            if (integer) {
                int64_t v;
                memcpy(&v, at, sizeof v);
                out[i] = (double)v;
            } else {
                memcpy(&out[i], at, sizeof(double));
            }
            if (!in_range(out[i], max_abs)) status = PK_PLAIN_REFUSED;
        }
    }
    PyBuffer_Release(&view);
    return status;
}

/* The shapes (rows,) and (rows, cols) of up to 6 x 6, built once (kept for the process). */
static PyObject *shapes[7][7];

PyObject *pk_new_array(const double *values, Py_ssize_t rows, Py_ssize_t cols) {
    PyObject *empty = pk_numpy_empty();
    if (!empty) return NULL;
    int small = rows <= 6 && cols <= 6;
    PyObject *shape = small ? shapes[rows][cols] : NULL;
    if (!shape) {
        shape = cols ? Py_BuildValue("(nn)", rows, cols) : Py_BuildValue("(n)", rows);
        if (!shape) return NULL;
        if (small) { /* building may run the collector, hence Python code and another thread */
            if (shapes[rows][cols]) { /* that thread's shape, kept meanwhile: ours dropped */
                Py_DECREF(shape);
                shape = shapes[rows][cols];
            } else {
                shapes[rows][cols] = shape; /* the table's reference */
            }
        }
    }
    PyObject *out = PyObject_CallOneArg(empty, shape);
    if (!small) Py_DECREF(shape);
    if (!out) return NULL;
    Py_buffer view;
    if (PyObject_GetBuffer(out, &view, PyBUF_C_CONTIGUOUS | PyBUF_WRITABLE) < 0) {
        Py_DECREF(out);
        return NULL;
    }
    memcpy(view.buf, values, sizeof(double) * (size_t)(rows * (cols ? cols : 1)));
    PyBuffer_Release(&view);
    return out;
}

/* Argument `name` as a C-contiguous buffer of `type` ('d' float64, '?' bool) with `ndim`
 * dimensions and, where shape is not NULL, the sizes shape[0..ndim-1] (-1: any); 0, or -1 with
 * TypeError / ValueError set and nothing held. The one buffer check of rod_batch.c,
 * rod_velocity.c and svd.c. */
int pk_take(PyObject *obj, Py_buffer *view, const char *name, char type, int writable, int ndim,
            const Py_ssize_t *shape) {
    int flags = PyBUF_C_CONTIGUOUS | PyBUF_FORMAT | (writable ? PyBUF_WRITABLE : 0);
    if (PyObject_GetBuffer(obj, view, flags) < 0) {
        PyErr_Format(PyExc_TypeError, "%s: a C-contiguous%s array is needed", name,
                     writable ? " writable" : "");
        return -1;
    }
    const char *f = view->format ? view->format : "B";
    if (f[0] == '@' || f[0] == '=' || f[0] == '<') f++;
    if (!(f[0] == type && !f[1] && view->itemsize == (type == 'd' ? 8 : 1))) {
        PyErr_Format(PyExc_TypeError, "%s: %s array expected (format %s)", name,
                     type == 'd' ? "float64" : "bool", view->format ? view->format : "B");
        PyBuffer_Release(view);
        return -1;
    }
    int ok = view->ndim == ndim;
    for (int j = 0; ok && shape && j < ndim; j++) ok = shape[j] < 0 || view->shape[j] == shape[j];
    if (!ok) {
        PyErr_Format(PyExc_ValueError, "%s: wrong shape (%d dimensions, %d expected)", name,
                     view->ndim, ndim);
        PyBuffer_Release(view);
        return -1;
    }
    return 0;
}
