/* pkmkit.native.kernels: the module face of the C kernels (inverse.c, direct.c).
 *
 * Each function takes the same positional arguments as its Numba twin, as C-contiguous
 * buffers (float64, int64, bool), checks their types and shapes (TypeError / ValueError
 * otherwise: never a read out of bounds), then runs with the GIL released. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdlib.h>
#include <string.h>

#include "kernels.h"

#define MAX_BUFFERS 24

typedef struct {
    Py_buffer views[MAX_BUFFERS];
    int count;
} buffers;

static void release(buffers *held) {
    for (int i = 0; i < held->count; i++) PyBuffer_Release(&held->views[i]);
    held->count = 0;
}

/* The format letter of a native-order buffer ('d', 'l', 'q', '?'), or 0. */
static char format_letter(const Py_buffer *view) {
    const char *f = view->format ? view->format : "B";
    if (f[0] == '@' || f[0] == '=' || f[0] == '<') {
#if PY_LITTLE_ENDIAN
        f++;
#else
        if (f[0] == '<') return 0;
        f++;
#endif
    }
    return (f[0] && !f[1]) ? f[0] : 0;
}

/* Acquire argument `name` as a C-contiguous buffer of `type` ('d' float64, 'i' int64, '?'
 * bool) with `ndim` dimensions; d0, d1 the expected sizes (-1: any). NULL on error. */
static void *take(buffers *held, PyObject *obj, const char *name, char type, int writable,
                  int ndim, Py_ssize_t d0, Py_ssize_t d1) {
    Py_buffer *view = &held->views[held->count];
    int flags = PyBUF_C_CONTIGUOUS | PyBUF_FORMAT | (writable ? PyBUF_WRITABLE : 0);
    if (PyObject_GetBuffer(obj, view, flags) < 0) {
        PyErr_Format(PyExc_TypeError, "%s: a C-contiguous%s array is needed", name,
                     writable ? " writable" : "");
        return NULL;
    }
    held->count++;
    char letter = format_letter(view);
    int typed = type == 'd' ? (letter == 'd' && view->itemsize == 8)
              : type == 'i' ? ((letter == 'l' || letter == 'q') && view->itemsize == 8)
              : (letter == '?' && view->itemsize == 1);
    if (!typed) {
        PyErr_Format(PyExc_TypeError, "%s: %s array expected (format %s)", name,
                     type == 'd' ? "float64" : type == 'i' ? "int64" : "bool",
                     view->format ? view->format : "B");
        return NULL;
    }
    if (view->ndim != ndim || (d0 >= 0 && view->shape[0] != d0)
        || (ndim > 1 && d1 >= 0 && view->shape[1] != d1)) {
        PyErr_Format(PyExc_ValueError, "%s: wrong shape (%d dimensions)", name, view->ndim);
        return NULL;
    }
    return view->buf;
}

static Py_ssize_t dim(const buffers *held, int which, int axis) {
    return held->views[which].shape[axis];
}

static int check_args(Py_ssize_t nargs, Py_ssize_t expected, const char *name) {
    if (nargs != expected) {
        PyErr_Format(PyExc_TypeError, "%s() takes %zd positional arguments (%zd given)", name,
                     expected, nargs);
        return -1;
    }
    return 0;
}

PyDoc_STRVAR(inverse_doc,
"inverse_poses(x, kind, base, platform, axis, pivot, e1, e2, length_sq, length,\n"
"              crank_radius, crank_offset, sigma, boundary_tol, groups, counts, angular,\n"
"              consistency_tol, q, status)\n\n"
"The C twin of pkmkit.machines.full_pose_kernels.inverse_poses: q (N, n) and status (N,)\n"
"of pose rows x (N, 6); float64, int64 (kind, groups, counts, status) and bool (angular)\n"
"C-contiguous arrays. Runs without the GIL.");

static PyObject *inverse_poses(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (check_args(nargs, 20, "inverse_poses") < 0) return NULL;
    buffers held = {.count = 0};
    pk_rods rods;
    pk_actuators act;
    const double *x = take(&held, args[0], "x", 'd', 0, 2, -1, 6);
    if (!x) goto fail;
    Py_ssize_t rows = dim(&held, 0, 0);
    rods.kind = take(&held, args[1], "kind", 'i', 0, 1, -1, -1);
    if (!rods.kind) goto fail;
    rods.m = dim(&held, 1, 0);
    const double **vectors[] = {&rods.base, &rods.platform, &rods.axis, &rods.pivot,
                                &rods.e1, &rods.e2};
    const char *vector_names[] = {"base", "platform", "axis", "pivot", "e1", "e2"};
    for (int i = 0; i < 6; i++) {
        *vectors[i] = take(&held, args[2 + i], vector_names[i], 'd', 0, 2, rods.m, 3);
        if (!*vectors[i]) goto fail;
    }
    const double **scalars[] = {&rods.length_sq, &rods.length, &rods.crank_radius,
                                &rods.crank_offset, &rods.sigma};
    const char *scalar_names[] = {"length_sq", "length", "crank_radius", "crank_offset",
                                  "sigma"};
    for (int i = 0; i < 5; i++) {
        *scalars[i] = take(&held, args[8 + i], scalar_names[i], 'd', 0, 1, rods.m, -1);
        if (!*scalars[i]) goto fail;
    }
    rods.boundary_tol = PyFloat_AsDouble(args[13]);
    if (rods.boundary_tol == -1.0 && PyErr_Occurred()) goto fail;
    act.groups = take(&held, args[14], "groups", 'i', 0, 2, -1, -1);
    if (!act.groups) goto fail;
    act.n = dim(&held, held.count - 1, 0);
    act.width = dim(&held, held.count - 1, 1);
    act.counts = take(&held, args[15], "counts", 'i', 0, 1, act.n, -1);
    if (!act.counts) goto fail;
    act.angular = take(&held, args[16], "angular", '?', 0, 1, act.n, -1);
    if (!act.angular) goto fail;
    act.consistency_tol = PyFloat_AsDouble(args[17]);
    if (act.consistency_tol == -1.0 && PyErr_Occurred()) goto fail;
    double *q = take(&held, args[18], "q", 'd', 1, 2, rows, act.n);
    if (!q) goto fail;
    int64_t *status = take(&held, args[19], "status", 'i', 1, 1, rows, -1);
    if (!status) goto fail;
    for (Py_ssize_t a = 0; a < act.n; a++) {
        int64_t count = act.counts[a];
        int bad = count < 1 || count > act.width;
        for (int64_t c = 0; !bad && c < count; c++) {
            int64_t rod = act.groups[act.width * a + c];
            bad = rod < 0 || rod >= rods.m;
        }
        if (bad) {
            PyErr_Format(PyExc_ValueError, "actuator %zd: rod group out of range", a);
            goto fail;
        }
    }
    for (Py_ssize_t j = 0; j < rods.m; j++) {
        if (rods.kind[j] < 0 || rods.kind[j] > 2) {
            PyErr_Format(PyExc_ValueError, "rod %zd: kind must be 0, 1 or 2", j);
            goto fail;
        }
    }
    double *rod_q = malloc(sizeof(double) * (size_t)(rods.m > 0 ? rods.m : 1));
    if (!rod_q) {
        PyErr_NoMemory();
        goto fail;
    }
    Py_BEGIN_ALLOW_THREADS
    pk_inverse_poses(x, rows, &rods, &act, q, status, rod_q);
    Py_END_ALLOW_THREADS
    free(rod_q);
    release(&held);
    Py_RETURN_NONE;
fail:
    release(&held);
    return NULL;
}

/* The arguments common to solve_rows and solve_one; rows < 0 for one pose. */
static PyObject *solve(PyObject *const *args, Py_ssize_t nargs, int batch, const char *name) {
    if (check_args(nargs, 7, name) < 0) return NULL;
    buffers held = {.count = 0};
    int nd = batch ? 2 : 1;
    const double *q = take(&held, args[0], "q", 'd', 0, nd, -1, -1);
    if (!q) goto fail;
    Py_ssize_t rows = batch ? dim(&held, 0, 0) : 1;
    Py_ssize_t n = dim(&held, 0, batch ? 1 : 0);
    const double *u0 = batch ? take(&held, args[1], "u0", 'd', 0, 2, rows, 6)
                             : take(&held, args[1], "u0", 'd', 0, 1, 6, -1);
    if (!u0) goto fail;
    int has_guess = PyObject_IsTrue(args[2]);
    if (has_guess < 0) goto fail;
    const double *geom = take(&held, args[3], "geom", 'd', 0, 2, -1, 16);
    if (!geom) goto fail;
    Py_ssize_t m = dim(&held, held.count - 1, 0);
    const double *home = take(&held, args[4], "home", 'd', 0, 1, 6 + 7 * n, -1);
    if (!home) goto fail;
    const double *opts = take(&held, args[5], "opts", 'd', 0, 1, 7, -1);
    if (!opts) goto fail;
    double *out = batch ? take(&held, args[6], "out", 'd', 1, 2, rows, 9)
                        : take(&held, args[6], "out", 'd', 1, 1, 9, -1);
    if (!out) goto fail;
    for (Py_ssize_t j = 0; j < m; j++) {
        double actuator = geom[16 * j + 14], kind = geom[16 * j + 13];
        if (!(actuator >= 0.0 && actuator < (double)n) || !(kind >= 0.0 && kind <= 2.0)) {
            PyErr_Format(PyExc_ValueError, "rod %zd: actuator index or kind out of range", j);
            goto fail;
        }
    }
    size_t cells = (size_t)(m > 0 ? m : 1);
    double *memory = malloc(sizeof(double) * cells * 18);
    if (!memory) {
        PyErr_NoMemory();
        goto fail;
    }
    pk_work work = {memory, memory + 3 * cells, memory + 4 * cells, memory + 5 * cells,
                    memory + 6 * cells, memory + 12 * cells};
    Py_BEGIN_ALLOW_THREADS
    for (Py_ssize_t k = 0; k < rows; k++)
        pk_solve_row(q + n * k, n, u0 + 6 * k, has_guess, geom, m, home, opts, out + 9 * k,
                     &work);
    Py_END_ALLOW_THREADS
    free(memory);
    release(&held);
    Py_RETURN_NONE;
fail:
    release(&held);
    return NULL;
}

PyDoc_STRVAR(solve_rows_doc,
"solve_rows(q, u0, has_guess, geom, home, opts, out)\n\n"
"The C twin of pkmkit.machines.full_pose_direct_kernel.solve_rows: q (N, n), u0 (N, 6),\n"
"geom (m, 16), home (6 + 7n,), opts (7,), out (N, 9). Runs without the GIL.");

static PyObject *solve_rows(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    return solve(args, nargs, 1, "solve_rows");
}

PyDoc_STRVAR(solve_one_doc,
"solve_one(q, u0, has_guess, geom, home, opts, out)\n\n"
"solve_rows for one pose: q (n,), u0 (6,), out (9,).");

static PyObject *solve_one(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    return solve(args, nargs, 0, "solve_one");
}

/* velocity.c */
extern const char pk_rod_velocity_doc[], pk_rod_field_doc[], pk_rod_inverse_doc[];
PyObject *pk_py_rod_inverse(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
extern const char pk_pose_velocity_doc[], pk_pose_inverse_doc[], pk_state_array_doc[];
PyObject *pk_py_state_array(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
PyObject *pk_py_pose_inverse(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
PyObject *pk_py_pose_velocity(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
PyObject *pk_py_rod_velocity(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
PyObject *pk_py_rod_field(PyObject *self, PyObject *const *args, Py_ssize_t nargs);

static PyMethodDef methods[] = {
    {"inverse_poses", (PyCFunction)(void (*)(void))inverse_poses, METH_FASTCALL, inverse_doc},
    {"solve_rows", (PyCFunction)(void (*)(void))solve_rows, METH_FASTCALL, solve_rows_doc},
    {"solve_one", (PyCFunction)(void (*)(void))solve_one, METH_FASTCALL, solve_one_doc},
    {"rod_velocity", (PyCFunction)(void (*)(void))pk_py_rod_velocity, METH_FASTCALL,
     pk_rod_velocity_doc},
    {"rod_field", (PyCFunction)(void (*)(void))pk_py_rod_field, METH_FASTCALL, pk_rod_field_doc},
    {"rod_inverse", (PyCFunction)(void (*)(void))pk_py_rod_inverse, METH_FASTCALL,
     pk_rod_inverse_doc},
    {"pose_velocity", (PyCFunction)(void (*)(void))pk_py_pose_velocity, METH_FASTCALL,
     pk_pose_velocity_doc},
    {"pose_inverse", (PyCFunction)(void (*)(void))pk_py_pose_inverse, METH_FASTCALL,
     pk_pose_inverse_doc},
    {"state_array", (PyCFunction)(void (*)(void))pk_py_state_array, METH_FASTCALL,
     pk_state_array_doc},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "pkmkit.native.kernels",
    "Ahead-of-time (C) twins of pkmkit's full-pose Numba kernels (pkmkit.native).", -1,
    methods, NULL, NULL, NULL, NULL,
};

PyMODINIT_FUNC PyInit_kernels(void) { return PyModule_Create(&module); }
