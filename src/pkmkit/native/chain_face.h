/* The module face shared by chain_velocity.c and chain_linearise.c: arguments taken as
 * C-contiguous native-order buffers and checked (types, shapes, indices) before a kernel runs
 * without the GIL. Static: each file has its copy. */
#ifndef PKMKIT_CHAIN_FACE_H
#define PKMKIT_CHAIN_FACE_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdlib.h>
#include <string.h>

#include "kernels.h"

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

#endif
