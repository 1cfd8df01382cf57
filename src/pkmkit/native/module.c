/* pkmkit.native.kernels: the module face of the C kernels (inverse.c, direct.c,
 * position.c, chain.c).
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

/* inverse_poses (shared 0: 20 arguments) and inverse_poses_shared (shared 1: the same and
 * plan, wait; an empty status writes none). */
static PyObject *inverse_call(PyObject *const *args, Py_ssize_t nargs, int shared) {
    if (check_args(nargs, shared ? 22 : 20, shared ? "inverse_poses_shared" : "inverse_poses")
        < 0)
        return NULL;
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
    int64_t *status = take(&held, args[19], "status", 'i', 1, 1, shared ? -1 : rows, -1);
    if (!status) goto fail;
    if (shared && dim(&held, held.count - 1, 0) != rows) {
        if (dim(&held, held.count - 1, 0) != 0) {
            PyErr_SetString(PyExc_ValueError, "status: wrong shape (rows or 0 needed)");
            goto fail;
        }
        status = NULL;
    }
    unsigned char *plan = NULL;
    int wait = 0;
    if (shared) {
        plan = pk_take_plan(args[20], &held.views[held.count], rows);
        if (!plan) goto fail;
        held.count++;
        if ((wait = PyObject_IsTrue(args[21])) < 0) goto fail;
    }
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
    if (shared) {
        int failed = pk_run_shared(x, rows, &rods, &act, q, status, plan, wait, rod_q);
        if (failed) {
            free(rod_q);
            goto fail;
        }
    } else {
        Py_BEGIN_ALLOW_THREADS
        pk_inverse_poses(x, rows, &rods, &act, q, status, rod_q);
        Py_END_ALLOW_THREADS
    }
    free(rod_q);
    release(&held);
    Py_RETURN_NONE;
fail:
    release(&held);
    return NULL;
}

static PyObject *inverse_poses(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    return inverse_call(args, nargs, 0);
}

static PyObject *inverse_poses_shared(PyObject *self, PyObject *const *args,
                                      Py_ssize_t nargs) {
    (void)self;
    return inverse_call(args, nargs, 1);
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

PyDoc_STRVAR(simd_doc,
"simd(choice=None)\n\n"
"Poses per block of the vectorised inverse_poses in use (8 with AVX-512, 4 with AVX2, on\n"
"x86-64; 0: one pose at a time). simd(False) / simd(True) switch it off / back on (the\n"
"widest the CPU has) for the process, simd(4) / simd(8) ask for that width (0 returned\n"
"where the CPU lacks it); tests compare the paths. Both widths give the same bits; they\n"
"differ from the scalar kernel's in the last bits where sin and cos do (a vectorised\n"
"sincos, at most 1 ulp from the exact values on [0, 2pi], instead of libm's).");

static PyObject *simd(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs > 1) return PyErr_Format(PyExc_TypeError, "simd() takes at most 1 argument");
    if (nargs == 1 && args[0] != Py_None) {
        long choice = PyBool_Check(args[0]) ? (args[0] == Py_True) : PyLong_AsLong(args[0]);
        if (choice == -1 && PyErr_Occurred()) return NULL;
        if (choice != 0 && choice != 1 && choice != 4 && choice != 8)
            return PyErr_Format(PyExc_ValueError, "simd(): choice must be a bool, 4 or 8, "
                                "got %ld", choice);
        pk_simd_set((int)choice);
    }
    return PyLong_FromLong(pk_simd_lanes());
}

PyDoc_STRVAR(simd_sincos_doc,
"simd_sincos(t, s, c)\n\n"
"The vectorised inverse_poses' sin and cos of angles t (N,) >= 0 into s and c (N,), float64\n"
"C-contiguous, by the width simd() gives; returns it (0: nothing written). For tests.");

static PyObject *simd_sincos(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (check_args(nargs, 3, "simd_sincos") < 0) return NULL;
    buffers held = {.count = 0};
    const double *t = take(&held, args[0], "t", 'd', 0, 1, -1, -1);
    if (!t) goto fail;
    Py_ssize_t count = dim(&held, 0, 0);
    double *s = take(&held, args[1], "s", 'd', 1, 1, count, -1);
    if (!s) goto fail;
    double *c = take(&held, args[2], "c", 'd', 1, 1, count, -1);
    if (!c) goto fail;
    int lanes = pk_simd_sincos(t, count, s, c);
    release(&held);
    return PyLong_FromLong(lanes);
fail:
    release(&held);
    return NULL;
}

PyDoc_STRVAR(position_rows_doc,
"position_rows(p, u0, has_guess, skip, geom, home, jt_inv, opts, out)\n\n"
"The C twin of pkmkit.machines.full_pose_position_kernel.solve_rows (the position inverse\n"
"of a machine with three actuators whose rods set the orientation): p (N, 3), u0 (N, 6),\n"
"skip (N,) bool, geom (m, 16) with actuator indices 0..2, home (27,), jt_inv (3, 3),\n"
"opts (9,) or (10,) (opts[9] = 1: the paired Newton solve first, the rods' branches in\n"
"geom[:, 15]) or (10 + k,) (then opts[10:] its start table: position_start.pack), out\n"
"(N, 9) or (N, 10) (column 9: 1 where the paired solve answered).\n"
"Runs without the GIL.");

static PyObject *position_rows(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (check_args(nargs, 9, "position_rows") < 0) return NULL;
    buffers held = {.count = 0};
    const double *p = take(&held, args[0], "p", 'd', 0, 2, -1, 3);
    if (!p) goto fail;
    Py_ssize_t rows = dim(&held, 0, 0);
    const double *u0 = take(&held, args[1], "u0", 'd', 0, 2, rows, 6);
    if (!u0) goto fail;
    int has_guess = PyObject_IsTrue(args[2]);
    if (has_guess < 0) goto fail;
    const unsigned char *skip = take(&held, args[3], "skip", '?', 0, 1, rows, -1);
    if (!skip) goto fail;
    const double *geom = take(&held, args[4], "geom", 'd', 0, 2, -1, 16);
    if (!geom) goto fail;
    Py_ssize_t m = dim(&held, held.count - 1, 0);
    const double *home = take(&held, args[5], "home", 'd', 0, 1, 6 + 7 * 3, -1);
    if (!home) goto fail;
    const double *jt_inv = take(&held, args[6], "jt_inv", 'd', 0, 2, 3, 3);
    if (!jt_inv) goto fail;
    const double *opts = take(&held, args[7], "opts", 'd', 0, 1, -1, -1);
    if (!opts) goto fail;
    Py_ssize_t n_opts = dim(&held, held.count - 1, 0);
    double *out = take(&held, args[8], "out", 'd', 1, 2, rows, -1);
    if (!out) goto fail;
    Py_ssize_t n_out = dim(&held, held.count - 1, 1);
    if (n_opts < 9 || (n_out != 9 && n_out != 10)
        || (n_opts > 10 && (opts[9] != 1.0 || pk_start_table_size(opts + 10, n_opts - 10) < 0))) {
        PyErr_SetString(PyExc_ValueError, "position_rows: opts must be (9,), (10,) or (10 + "
                        "a start table,) with opts[9] = 1, and out (N, 9) or (N, 10)");
        goto fail;
    }
    if (n_opts >= 10 && opts[9] == 1.0) {
        for (Py_ssize_t j = 0; j < m; j++) {
            double kind = geom[16 * j + 13], sigma = geom[16 * j + 15];
            if (kind != 0.0 || (sigma != 1.0 && sigma != -1.0)) {
                PyErr_Format(PyExc_ValueError, "rod %zd: the paired solve needs slide rods "
                             "with a branch of +1 or -1 in geom[:, 15]", j);
                goto fail;
            }
        }
    }
    for (Py_ssize_t j = 0; j < m; j++) {
        double actuator = geom[16 * j + 14], kind = geom[16 * j + 13];
        if (!(actuator >= 0.0 && actuator < 3.0) || !(kind >= 0.0 && kind <= 2.0)) {
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
    pk_position_rows(p, rows, u0, has_guess, skip, geom, m, home, jt_inv, opts, n_opts, out,
                     n_out, &work);
    Py_END_ALLOW_THREADS
    free(memory);
    release(&held);
    Py_RETURN_NONE;
fail:
    release(&held);
    return NULL;
}

PyDoc_STRVAR(chain_rows_doc,
"chain_rows(frames, types, evar, elements, offsets, position, known, u, length, max_iter,\n"
"           xtol, atol, gtol, stall, residual_tol, damping, status, residual, iterations,\n"
"           head, targets, tools, inverse)\n\n"
"The C twin of pkmkit.solve.chain_kernel._solve_rows (the closure of joint-chain machines,\n"
"or with inverse the inverse model of a complete one): frames (E, 4, 4), types, evar (E,),\n"
"elements (K,), offsets (L + 1,), position (n_var,), head (H,) int64; known (1 or N, n_var),\n"
"u (N, n) solved in place, status, iterations (N,) int64, residual (N,), targets (T, 6),\n"
"tools (T,) with T >= N for the inverse, >= 1 else. Runs without the GIL.");

/* An int64 index array's entries within [low, high). */
static int indices_within(const int64_t *a, Py_ssize_t count, int64_t low, int64_t high,
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

static PyObject *chain_rows(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (check_args(nargs, 23, "chain_rows") < 0) return NULL;
    buffers held = {.count = 0};
    pk_chain c;
    pk_chain_options o;
    c.frames = take(&held, args[0], "frames", 'd', 0, 3, -1, 4);
    if (!c.frames) goto fail;
    Py_ssize_t n_elem = dim(&held, 0, 0);
    if (dim(&held, 0, 2) != 4) {
        PyErr_SetString(PyExc_ValueError, "frames: wrong shape (E, 4, 4 expected)");
        goto fail;
    }
    c.types = take(&held, args[1], "types", 'i', 0, 1, n_elem, -1);
    if (!c.types) goto fail;
    c.evar = take(&held, args[2], "evar", 'i', 0, 1, n_elem, -1);
    if (!c.evar) goto fail;
    c.elements = take(&held, args[3], "elements", 'i', 0, 1, -1, -1);
    if (!c.elements) goto fail;
    Py_ssize_t n_leg_elements = dim(&held, 3, 0);
    c.offsets = take(&held, args[4], "offsets", 'i', 0, 1, -1, -1);
    if (!c.offsets) goto fail;
    c.n_legs = dim(&held, 4, 0) - 1;
    c.position = take(&held, args[5], "position", 'i', 0, 1, -1, -1);
    if (!c.position) goto fail;
    c.n_var = dim(&held, 5, 0);
    const double *known = take(&held, args[6], "known", 'd', 0, 2, -1, c.n_var);
    if (!known) goto fail;
    Py_ssize_t known_rows = dim(&held, 6, 0);
    double *u = take(&held, args[7], "u", 'd', 1, 2, -1, -1);
    if (!u) goto fail;
    Py_ssize_t rows = dim(&held, 7, 0);
    c.n = dim(&held, 7, 1);
    c.length = PyFloat_AsDouble(args[8]);
    if (c.length == -1.0 && PyErr_Occurred()) goto fail;
    o.max_iter = PyLong_AsLongLong(args[9]);
    if (o.max_iter == -1 && PyErr_Occurred()) goto fail;
    double *floats[] = {&o.xtol, &o.atol, &o.gtol, &o.stall, &o.residual_tol, &o.damping};
    for (int i = 0; i < 6; i++) {
        *floats[i] = PyFloat_AsDouble(args[10 + i]);
        if (*floats[i] == -1.0 && PyErr_Occurred()) goto fail;
    }
    int64_t *status = take(&held, args[16], "status", 'i', 1, 1, rows, -1);
    if (!status) goto fail;
    double *residual = take(&held, args[17], "residual", 'd', 1, 1, rows, -1);
    if (!residual) goto fail;
    int64_t *iterations = take(&held, args[18], "iterations", 'i', 1, 1, rows, -1);
    if (!iterations) goto fail;
    c.head = take(&held, args[19], "head", 'i', 0, 1, -1, -1);
    if (!c.head) goto fail;
    c.n_head = held.views[held.count - 1].shape[0];
    const double *targets = take(&held, args[20], "targets", 'd', 0, 2, -1, 6);
    if (!targets) goto fail;
    Py_ssize_t n_targets = held.views[held.count - 1].shape[0];
    const double *tools = take(&held, args[21], "tools", 'd', 0, 1, -1, -1);
    if (!tools) goto fail;
    Py_ssize_t n_tools = held.views[held.count - 1].shape[0];
    c.inverse = PyObject_IsTrue(args[22]);
    if (c.inverse < 0) goto fail;
    Py_ssize_t need = c.inverse ? rows : 1;
    if (c.n < 6 || c.n_legs < 0 || known_rows < 1 || (known_rows > 1 && known_rows < rows)
        || n_targets < need || n_tools < need) {
        PyErr_SetString(PyExc_ValueError, "u needs at least 6 columns, offsets one entry, known "
                        "1 or N rows, targets and tools N rows (inverse) or 1");
        goto fail;
    }
    if (indices_within(c.types, n_elem, 0, 3, "types") < 0
        || indices_within(c.elements, n_leg_elements, 0, n_elem, "elements") < 0
        || indices_within(c.head, c.n_head, 0, n_elem, "head") < 0
        || indices_within(c.offsets, c.n_legs + 1, 0, n_leg_elements + 1, "offsets") < 0
        || indices_within(c.position, c.n_var, -1, c.n, "position") < 0)
        goto fail;
    for (Py_ssize_t e = 0; e < n_elem; e++) {
        if (c.types[e] != 0 && (c.evar[e] < 0 || c.evar[e] >= c.n_var)) {
            PyErr_Format(PyExc_ValueError, "evar[%zd] out of range", e);
            goto fail;
        }
    }
    for (Py_ssize_t leg = 0; leg < c.n_legs; leg++) {
        if (c.offsets[leg + 1] < c.offsets[leg]) {
            PyErr_SetString(PyExc_ValueError, "offsets must not decrease");
            goto fail;
        }
    }
    pk_chain_work w;
    w.m = 6 * c.n_legs + (c.inverse ? 6 : 0);
    size_t m = (size_t)w.m, n = (size_t)c.n, twists = (size_t)(n_leg_elements + c.n_head) + 1;
    size_t cells = (size_t)c.n_var + 1 + 2 * m + 2 * m * n + 3 * n + 2 * n * n + 6 * twists;
    double *memory = malloc(sizeof(double) * cells);
    int64_t *indices = malloc(sizeof(int64_t) * (n + twists));
    if (!memory || !indices) {
        free(memory);
        free(indices);
        PyErr_NoMemory();
        goto fail;
    }
    double *next = memory;
    w.values = next, next += c.n_var + 1;
    w.r = next, next += m;
    w.r_new = next, next += m;
    w.jac = next, next += m * n;
    w.j_new = next, next += m * n;
    w.u_new = next, next += n;
    w.step = next, next += n;
    w.grad = next, next += n;
    w.h = next, next += n * n;
    w.low = next, next += n * n;
    w.tw = next;
    w.nz = indices;
    w.tw_col = indices + n;
    Py_BEGIN_ALLOW_THREADS
    pk_chain_rows(&c, known, known_rows, u, rows, &o, status, residual, iterations, targets,
                  tools, &w);
    Py_END_ALLOW_THREADS
    free(memory);
    free(indices);
    release(&held);
    Py_RETURN_NONE;
fail:
    release(&held);
    return NULL;
}

/* velocity.c */
extern const char pk_rod_velocity_doc[], pk_rod_field_doc[], pk_rod_inverse_doc[];
PyObject *pk_py_rod_inverse(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
extern const char pk_pose_velocity_doc[], pk_state_array_doc[];
PyObject *pk_py_state_array(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
PyObject *pk_py_pose_velocity(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
/* pose_one.c: one-pose ik, fk, jacobian of a full-pose machine in one call each */
extern const char pk_pose_one_doc[];
PyObject *pk_py_pose_one(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
PyObject *pk_py_rod_velocity(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
PyObject *pk_py_rod_field(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
/* rod_one.c: one pose per call of the translational rod-leg machines */
extern const char pk_rod_ik_one_doc[], pk_rod_fk_one_doc[], pk_rod_jacobian_one_doc[];
PyObject *pk_py_rod_ik_one(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
PyObject *pk_py_rod_fk_one(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
PyObject *pk_py_rod_jacobian_one(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
/* svd.c, rod_velocity.c: batched SVD kernels and the rod-leg velocity summaries */
extern const char pk_singular_values_doc[], pk_singular_rates_doc[];
extern const char pk_rod_velocity3_doc[], pk_rod_velocity2_doc[];
PyObject *pk_py_singular_values(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
PyObject *pk_py_singular_rates(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
PyObject *pk_py_rod_velocity3(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
PyObject *pk_py_rod_velocity2(PyObject *self, PyObject *const *args, Py_ssize_t nargs);

/* chain_velocity.c, chain_linearise.c */
extern const char pk_chain_jacobian_rows_doc[], pk_closure_rates_doc[];
extern const char pk_chain_linearise_rows_doc[], pk_absorb_doc[];
PyObject *pk_py_chain_jacobian_rows(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
PyObject *pk_py_closure_rates(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
PyObject *pk_py_chain_linearise_rows(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
PyObject *pk_py_absorb(PyObject *self, PyObject *const *args, Py_ssize_t nargs);

/* chain_one_velocity.c: the one-pose velocity model of joint-chain machines */
extern const char pk_chain_velocity_pack_doc[], pk_chain_one_velocity_doc[];
PyObject *pk_py_chain_velocity_pack(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
PyObject *pk_py_chain_one_velocity(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
extern const char pk_chain_one_jacobian_doc[];
PyObject *pk_py_chain_one_jacobian(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
/* chain_one.c: joint-chain one pose per call (machines/chain_one_native.py) */
extern const char pk_chain_one_pack_doc[], pk_chain_one_ik_doc[], pk_chain_one_fk_doc[];
extern const char pk_chain_one_structured_doc[];
PyObject *pk_py_chain_one_pack(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
PyObject *pk_py_chain_one_ik(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
PyObject *pk_py_chain_one_fk(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
PyObject *pk_py_chain_one_structured(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
/* chain_one_closure.c: the one-pose solve's closure by blocks' panels (tests) */
extern const char pk_chain_one_closure_doc[];
PyObject *pk_py_chain_one_closure(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
extern const char pk_chain_one_ik_jacobian_doc[];  /* chain_one_velocity_doc.c */
PyObject *pk_py_chain_one_ik_jacobian(PyObject *self, PyObject *const *args, Py_ssize_t nargs);

/* rod_batch.c: the batched closed-form inverse of rod-leg machines (issue 22 §5) */
extern const char pk_rod_inverse_rows_doc[], pk_rod_reach_det_doc[];
PyObject *pk_py_rod_inverse_rows(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
PyObject *pk_py_rod_reach_det(PyObject *self, PyObject *const *args, Py_ssize_t nargs);

static PyMethodDef methods[] = {
    {"inverse_poses", (PyCFunction)(void (*)(void))inverse_poses, METH_FASTCALL, inverse_doc},
    {"inverse_poses_shared", (PyCFunction)(void (*)(void))inverse_poses_shared, METH_FASTCALL,
     pk_inverse_shared_doc},
    {"inverse_plan", (PyCFunction)(void (*)(void))pk_py_inverse_plan, METH_FASTCALL,
     pk_inverse_plan_doc},
    {"solve_rows", (PyCFunction)(void (*)(void))solve_rows, METH_FASTCALL, solve_rows_doc},
    {"solve_one", (PyCFunction)(void (*)(void))solve_one, METH_FASTCALL, solve_one_doc},
    {"simd", (PyCFunction)(void (*)(void))simd, METH_FASTCALL, simd_doc},
    {"simd_sincos", (PyCFunction)(void (*)(void))simd_sincos, METH_FASTCALL, simd_sincos_doc},
    {"position_rows", (PyCFunction)(void (*)(void))position_rows, METH_FASTCALL,
     position_rows_doc},
    {"chain_rows", (PyCFunction)(void (*)(void))chain_rows, METH_FASTCALL, chain_rows_doc},
    {"rod_velocity", (PyCFunction)(void (*)(void))pk_py_rod_velocity, METH_FASTCALL,
     pk_rod_velocity_doc},
    {"rod_field", (PyCFunction)(void (*)(void))pk_py_rod_field, METH_FASTCALL, pk_rod_field_doc},
    {"rod_inverse", (PyCFunction)(void (*)(void))pk_py_rod_inverse, METH_FASTCALL,
     pk_rod_inverse_doc},
    {"rod_ik_one", (PyCFunction)(void (*)(void))pk_py_rod_ik_one, METH_FASTCALL,
     pk_rod_ik_one_doc},
    {"rod_fk_one", (PyCFunction)(void (*)(void))pk_py_rod_fk_one, METH_FASTCALL,
     pk_rod_fk_one_doc},
    {"rod_jacobian_one", (PyCFunction)(void (*)(void))pk_py_rod_jacobian_one, METH_FASTCALL,
     pk_rod_jacobian_one_doc},
    {"pose_velocity", (PyCFunction)(void (*)(void))pk_py_pose_velocity, METH_FASTCALL,
     pk_pose_velocity_doc},
    {"state_array", (PyCFunction)(void (*)(void))pk_py_state_array, METH_FASTCALL,
     pk_state_array_doc},
    {"pose_one", (PyCFunction)(void (*)(void))pk_py_pose_one, METH_FASTCALL, pk_pose_one_doc},
    {"singular_values", (PyCFunction)(void (*)(void))pk_py_singular_values, METH_FASTCALL,
     pk_singular_values_doc},
    {"singular_rates", (PyCFunction)(void (*)(void))pk_py_singular_rates, METH_FASTCALL,
     pk_singular_rates_doc},
    {"rod_velocity3", (PyCFunction)(void (*)(void))pk_py_rod_velocity3, METH_FASTCALL,
     pk_rod_velocity3_doc},
    {"rod_velocity2", (PyCFunction)(void (*)(void))pk_py_rod_velocity2, METH_FASTCALL,
     pk_rod_velocity2_doc},
    {"chain_jacobian_rows", (PyCFunction)(void (*)(void))pk_py_chain_jacobian_rows,
     METH_FASTCALL, pk_chain_jacobian_rows_doc},
    {"closure_rates", (PyCFunction)(void (*)(void))pk_py_closure_rates, METH_FASTCALL,
     pk_closure_rates_doc},
    {"chain_linearise_rows", (PyCFunction)(void (*)(void))pk_py_chain_linearise_rows,
     METH_FASTCALL, pk_chain_linearise_rows_doc},
    {"absorb", (PyCFunction)(void (*)(void))pk_py_absorb, METH_FASTCALL, pk_absorb_doc},
    {"chain_velocity_pack", (PyCFunction)(void (*)(void))pk_py_chain_velocity_pack,
     METH_FASTCALL, pk_chain_velocity_pack_doc},
    {"chain_one_velocity", (PyCFunction)(void (*)(void))pk_py_chain_one_velocity,
     METH_FASTCALL, pk_chain_one_velocity_doc},
    {"chain_one_jacobian", (PyCFunction)(void (*)(void))pk_py_chain_one_jacobian,
     METH_FASTCALL, pk_chain_one_jacobian_doc},
    {"chain_one_pack", (PyCFunction)(void (*)(void))pk_py_chain_one_pack, METH_FASTCALL,
     pk_chain_one_pack_doc},
    {"chain_one_ik", (PyCFunction)(void (*)(void))pk_py_chain_one_ik, METH_FASTCALL,
     pk_chain_one_ik_doc},
    {"chain_one_fk", (PyCFunction)(void (*)(void))pk_py_chain_one_fk, METH_FASTCALL,
     pk_chain_one_fk_doc},
    {"chain_one_structured", (PyCFunction)(void (*)(void))pk_py_chain_one_structured,
     METH_FASTCALL, pk_chain_one_structured_doc},
    {"chain_one_closure", (PyCFunction)(void (*)(void))pk_py_chain_one_closure, METH_FASTCALL,
     pk_chain_one_closure_doc},
    {"chain_one_ik_jacobian", (PyCFunction)(void (*)(void))pk_py_chain_one_ik_jacobian,
     METH_FASTCALL, pk_chain_one_ik_jacobian_doc},
    {"rod_inverse_rows", (PyCFunction)(void (*)(void))pk_py_rod_inverse_rows, METH_FASTCALL,
     pk_rod_inverse_rows_doc},
    {"rod_reach_det", (PyCFunction)(void (*)(void))pk_py_rod_reach_det, METH_FASTCALL,
     pk_rod_reach_det_doc},
    {"chain_closed_rows", (PyCFunction)(void (*)(void))pk_py_chain_closed_rows, METH_FASTCALL,
     pk_chain_closed_rows_doc},
    {"chain_closed_direct_rows", (PyCFunction)(void (*)(void))pk_py_chain_closed_direct_rows,
     METH_FASTCALL, pk_chain_closed_direct_rows_doc},
    {"euler_quat", (PyCFunction)(void (*)(void))pk_py_euler_quat, METH_FASTCALL,
     pk_euler_quat_doc},
    {"euler_rotvec", (PyCFunction)(void (*)(void))pk_py_euler_rotvec, METH_FASTCALL,
     pk_euler_rotvec_doc},
    {"recycled_block", (PyCFunction)(void (*)(void))pk_py_recycled_block, METH_FASTCALL,
     pk_recycled_block_doc},
    {"recycled_release", (PyCFunction)(void (*)(void))pk_py_recycled_release, METH_FASTCALL,
     pk_recycled_release_doc},
    {"csv_rows", (PyCFunction)(void (*)(void))pk_py_csv_rows, METH_FASTCALL, pk_csv_rows_doc},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef module = {
    PyModuleDef_HEAD_INIT, "pkmkit.native.kernels",
    "Ahead-of-time (C) twins of pkmkit's full-pose Numba kernels (pkmkit.native).", -1,
    methods, NULL, NULL, NULL, NULL,
};

PyMODINIT_FUNC PyInit_kernels(void) { return PyModule_Create(&module); }
