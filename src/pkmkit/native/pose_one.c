/* pkmkit.native.kernels: one pose per call of a full-pose rod machine of up to six rods, in
 * one C call each (issue 22 §1).
 *
 * pose_one(...) packs a machine's constants once (FullPoseMachine keeps the object) into a
 * PoseOne, whose methods take one plain pose or configuration, check it (six or n exact
 * Python floats or ints in a list or tuple, or a float64 or int64 vector; finite; within
 * max_abs), run the kernel, judge the strokes and return a new array:
 *
 *   ik(x, check)            the inverse model (pose_velocity.c's pk_pose_inverse_one, the
 *                           twin of full_pose_one.OnePoseInverse.__call__: the same bits)
 *   fk(q, check)            the direct model from the first-order guess, default options
 *                           (direct.c's pk_solve_row: the batch path's function, same bits)
 *   jacobian(x, tol, check, batch)
 *                           a PoseVelocity: the velocity model of the pose, computed when a
 *                           field is first read (PoseVelocity.field(name)) by one call of
 *                           pose_velocity.c's pk_pose_fill — A, B, J, J^-1, the
 *                           determinants, the flags (the singularity), with the singular
 *                           values of J_h and the condition when the field read needs them;
 *                           each SVD a later field needs (J_h's; J's linear and angular
 *                           rows'; the unit-row A's for an exact parallel measure) is then
 *                           added from the state's own J and A (add_singular_values: the
 *                           bits pk_pose_fill gives at that level).
 *
 * Each returns None where the batch path must answer (not finite, beyond max_abs, no closure,
 * not OK, beyond a stroke when check is true): it gives the same numbers and the typed
 * errors. ik and jacobian return NotImplemented for a pose in another buffer (a float32 or
 * int32 array: full_pose_one.OnePoseInverse decides); fk answers None there. A
 * PoseVelocity whose row the kernel refuses calls batch(x, q, tol) (lists, a float) once and
 * reads its fields from that record. Everything runs with the GIL held on the stack (no
 * shared buffers): thread-safe, and a PoseVelocity computes its state under the GIL. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <string.h>
#include <structmember.h>

#include "kernels.h"

int pk_pose_fill(const double *x, const double *q, const double *geom, ptrdiff_t n,
                 double length_l, double tol, int exact, double *out);      /* pose_velocity.c */
int pk_pose_inverse_one(const double *x, const double *rods, ptrdiff_t m, const double *groups,
                        ptrdiff_t n, int simple, double boundary_tol, double tol, double *q,
                        double *rod_q);                                     /* pose_velocity.c */
void pk_singular_values_fast(const double *mat, ptrdiff_t r, ptrdiff_t c,
                             double *out);                                  /* svd.c */
int pk_numpy_scalars(PyObject **float64, PyObject **int64);                /* velocity.c */

#define MAX_RODS 6
/* layout(6, n <= 6) of full_pose_velocity_kernel: A, B, J, J^-1, sv, sv_t, sv_r, 6 scalars */
#define STATE_DOUBLES (36 + 36 + 36 + 36 + 6 + 3 + 3 + 6)

typedef struct {
    PyObject_HEAD
    Py_ssize_t m, n;
    int simple;
    double boundary_tol, consistency_tol, max_abs, length;
    double rods[MAX_RODS * PK_POSE_ROD], groups[8 * MAX_RODS];
    double lo[MAX_RODS], hi[MAX_RODS];
    double geom[16 * MAX_RODS], home[6 + 7 * MAX_RODS], opts[7];
    PyObject *args; /* the constructor's arguments (pickling) */
} PoseOne;

typedef struct {
    PyObject_HEAD
    PoseOne *owner;
    PyObject *batch, *record; /* record: batch(x, q, tol) once the kernel refused the row */
    double x[6], q[6], tol;
    int level;                /* the pk_pose_fill level computed, -1 none */
    double state[STATE_DOUBLES];
} PoseVelocity;

static PyTypeObject PoseOneType, PoseVelocityType;

/* The static type of one of this file's objects: the two differ only in these. */
#define ONE_TYPE(object, name, dealloc, doc, methods, members)                              \
    {                                                                                     \
        PyVarObject_HEAD_INIT(NULL, 0).tp_name = "pkmkit.native.kernels." name,          \
        .tp_basicsize = sizeof(object), .tp_dealloc = (destructor)(dealloc),              \
        .tp_flags = Py_TPFLAGS_DEFAULT, .tp_doc = (doc), .tp_methods = (methods),          \
        .tp_members = (members),                                                          \
    }

/* ------------------------------------------------------------------ NumPy, by name */

static PyObject *np_float64, *np_int64; /* velocity.c's (pk_numpy_scalars), borrowed */

static int within_strokes(const PoseOne *self, const double *q) {
    for (Py_ssize_t k = 0; k < self->n; k++)
        if (!(self->lo[k] <= q[k] && q[k] <= self->hi[k])) return 0; /* NaN: outside */
    return 1;
}

static int truth(PyObject *const *args, Py_ssize_t nargs, Py_ssize_t expected, const char *name) {
    if (nargs != expected) {
        PyErr_Format(PyExc_TypeError, "%s() takes %zd positional arguments (%zd given)", name,
                     expected, nargs);
        return -1;
    }
    return PyObject_IsTrue(args[1]);
}

/* ------------------------------------------------------------------ PoseOne methods */

enum { SOLVED, BATCH_ANSWERS, OTHER_BUFFER };

/* The inverse model of one plain pose (ik and jacobian): x and q filled and SOLVED, or
 * BATCH_ANSWERS (refused, no closure, beyond a stroke when check), OTHER_BUFFER, -1 on error. */
static int inverse_of(PoseOne *self, PyObject *pose, int check, double *x, double *q) {
    double rod_q[MAX_RODS];
    int got = pk_plain_numbers(pose, 6, self->max_abs, x);
    if (got < 0) return -1;
    if (got == PK_PLAIN_OTHER) return OTHER_BUFFER;
    if (got == PK_PLAIN_REFUSED
        || pk_pose_inverse_one(x, self->rods, self->m, self->groups, self->n, self->simple,
                               self->boundary_tol, self->consistency_tol, q, rod_q)
        || (check && !within_strokes(self, q)))
        return BATCH_ANSWERS;
    return SOLVED;
}

/* What ik and jacobian answer where inverse_of did not solve: NULL, None or NotImplemented. */
static PyObject *unsolved(int found) {
    if (found < 0) return NULL;
    if (found == OTHER_BUFFER) Py_RETURN_NOTIMPLEMENTED;
    Py_RETURN_NONE;
}

static PyObject *one_ik(PoseOne *self, PyObject *const *args, Py_ssize_t nargs) {
    int check = truth(args, nargs, 2, "ik");
    if (check < 0) return NULL;
    double x[6], q[MAX_RODS];
    int found = inverse_of(self, args[0], check, x, q);
    return found == SOLVED ? pk_new_array(q, self->n, 0) : unsolved(found);
}

static PyObject *one_fk(PoseOne *self, PyObject *const *args, Py_ssize_t nargs) {
    int check = truth(args, nargs, 2, "fk");
    if (check < 0) return NULL;
    double q[MAX_RODS], out[9], zero[6] = {0};
    int got = pk_plain_numbers(args[0], self->n, self->max_abs, q);
    if (got < 0) return NULL;
    if (got != PK_PLAIN_TAKEN) Py_RETURN_NONE; /* the batch path converts it */
    double memory[18 * MAX_RODS];
    size_t cells = (size_t)self->m;
    pk_work work = {memory, memory + 3 * cells, memory + 4 * cells, memory + 5 * cells,
                    memory + 6 * cells, memory + 12 * cells};
    pk_solve_row(q, self->n, zero, 0, self->geom, self->m, self->home, self->opts, out, &work);
    if (out[6] != 0.0 || (check && !within_strokes(self, q))) Py_RETURN_NONE; /* Status.OK 0 */
    return pk_new_array(out, 6, 0);
}

static PyObject *one_jacobian(PoseOne *self, PyObject *const *args, Py_ssize_t nargs) {
    if (nargs != 4) {
        PyErr_Format(PyExc_TypeError, "jacobian() takes 4 positional arguments (%zd given)",
                     nargs);
        return NULL;
    }
    int check = PyObject_IsTrue(args[2]);
    if (check < 0) return NULL;
    if (!PyFloat_CheckExact(args[1])) {
        PyErr_SetString(PyExc_TypeError, "tol: a float is needed");
        return NULL;
    }
    double tol = PyFloat_AS_DOUBLE(args[1]);
    if (!(tol > 0.0 && tol < INFINITY)) {
        PyErr_SetString(PyExc_ValueError, "tol must be positive and finite");
        return NULL;
    }
    if (!PyCallable_Check(args[3])) {
        PyErr_SetString(PyExc_TypeError, "batch: a callable is needed");
        return NULL;
    }
    if (self->m != 6) Py_RETURN_NOTIMPLEMENTED; /* the velocity kernel is for six rods */
    double x[6], q[MAX_RODS];
    int found = inverse_of(self, args[0], check, x, q);
    if (found != SOLVED) return unsolved(found);
    PoseVelocity *v = PyObject_New(PoseVelocity, &PoseVelocityType);
    if (!v) return NULL;
    Py_INCREF(self);
    Py_INCREF(args[3]);
    v->owner = self;
    v->batch = args[3];
    v->record = NULL;
    memcpy(v->x, x, sizeof x);
    memcpy(v->q, q, sizeof(double) * (size_t)self->n);
    v->tol = tol;
    v->level = -1;
    return (PyObject *)v;
}

static PyObject *one_reduce(PoseOne *self, PyObject *unused) {
    (void)unused;
    PyObject *module = PyImport_ImportModule("pkmkit.native.kernels");
    if (!module) return NULL;
    PyObject *make = PyObject_GetAttrString(module, "pose_one");
    Py_DECREF(module);
    if (!make) return NULL;
    return Py_BuildValue("(NO)", make, self->args);
}

static void one_dealloc(PoseOne *self) {
    Py_XDECREF(self->args);
    PyObject_Free(self);
}

static PyMethodDef one_methods[] = {
    {"ik", (PyCFunction)(void (*)(void))one_ik, METH_FASTCALL,
     "ik(x, check): q (n,) of one pose, or None / NotImplemented (module doc)."},
    {"fk", (PyCFunction)(void (*)(void))one_fk, METH_FASTCALL,
     "fk(q, check): the pose (6,) of one configuration, or None (module doc)."},
    {"jacobian", (PyCFunction)(void (*)(void))one_jacobian, METH_FASTCALL,
     "jacobian(x, tol, check, batch): a PoseVelocity, or None / NotImplemented (module doc)."},
    {"__reduce__", (PyCFunction)one_reduce, METH_NOARGS, "Pickled as its constructor call."},
    {NULL, NULL, 0, NULL},
};

static PyMemberDef one_members[] = {
    {"n", T_PYSSIZET, offsetof(PoseOne, n), READONLY, "actuators"},
    {NULL, 0, 0, 0, NULL},
};

static PyTypeObject PoseOneType =
    ONE_TYPE(PoseOne, "PoseOne", one_dealloc,
             "A full-pose machine's constants for one-pose calls (pose_one).", one_methods,
             one_members);

/* ------------------------------------------------------------------ PoseVelocity */

/* The fields, in FullPoseJacobians' order, with the level of pk_pose_fill each needs (bit 1:
 * the singular values of J_h; 2 those of J's rows; 4 the exact parallel measure). */
enum { F_A, F_B, F_J, F_J_INV, F_SV, F_CONDITION, F_DET_A, F_DET_B, F_PARALLEL, F_SERIAL,
       F_SINGULARITY, F_TOLERANCE, F_Q, F_MODE, F_J_H, F_LENGTH, F_SV_T, F_SV_R, F_COUNT };
static const char *field_names[F_COUNT] = {
    "A", "B", "J", "J_inv", "singular_values", "condition", "det_A", "det_B",
    "parallel_measure", "serial_measure", "singularity", "tolerance", "q", "mode",
    "J_homogeneous", "characteristic_length", "translation_singular_values",
    "rotation_singular_values"};
static const int field_level[F_COUNT] = {
    [F_SV] = 1, [F_CONDITION] = 1, [F_PARALLEL] = 4, [F_SV_T] = 3, [F_SV_R] = 3};
static PyObject *field_index; /* name -> index */

static int field_of(PyObject *name) {
    if (!PyUnicode_Check(name)) {
        PyErr_SetString(PyExc_TypeError, "field: a name (str) is needed");
        return -1;
    }
    if (!field_index) {
        field_index = PyDict_New();
        if (!field_index) return -1;
        for (int i = 0; i < F_COUNT; i++) {
            PyObject *k = PyLong_FromLong(i);
            if (!k || PyDict_SetItemString(field_index, field_names[i], k) < 0) {
                Py_XDECREF(k);
                Py_CLEAR(field_index);
                return -1;
            }
            Py_DECREF(k);
        }
    }
    PyObject *index = PyDict_GetItemWithError(field_index, name);
    if (!index) {
        if (!PyErr_Occurred())
            PyErr_Format(PyExc_AttributeError, "no field %R in a full-pose velocity model",
                         name);
        return -1;
    }
    return (int)PyLong_AsLong(index);
}

static PyObject *list_of(const double *values, Py_ssize_t count) {
    PyObject *out = PyList_New(count);
    for (Py_ssize_t i = 0; out && i < count; i++) {
        PyObject *v = PyFloat_FromDouble(values[i]);
        if (!v) {
            Py_CLEAR(out);
            break;
        }
        PyList_SET_ITEM(out, i, v);
    }
    return out;
}

/* type(value): type np_float64 or np_int64 (loaded by pose_one). */
static PyObject *scalar(PyObject *type, double value) {
    PyObject *v = PyFloat_FromDouble(value);
    if (!v) return NULL;
    PyObject *out = PyObject_CallOneArg(type, v);
    Py_DECREF(v);
    return out;
}

/* The record of the batch path for a row the kernel refused (called once). */
static PyObject *batch_record(PoseVelocity *self) {
    if (self->record) return self->record;
    PyObject *x = list_of(self->x, 6), *q = list_of(self->q, self->owner->n);
    PyObject *record = NULL;
    if (x && q) record = PyObject_CallFunction(self->batch, "OOd", x, q, self->tol);
    Py_XDECREF(x);
    Py_XDECREF(q);
    if (!record) return NULL;
    if (self->record) { /* another thread got there while the batch path ran */
        Py_DECREF(record);
    } else {
        self->record = record;
    }
    return self->record;
}

/* The pieces of pk_pose_fill's level bits `missing` added to a computed state from its own
 * J and A (the same operations on the same numbers: the bits of pk_pose_fill at the higher
 * level): 1 the singular values of J_h and the condition, 2 those of J's linear and angular
 * rows, 4 the parallel measure where the bound settled the flags without it. */
static void add_singular_values(PoseVelocity *self, int missing) {
    const PoseOne *o = self->owner;
    Py_ssize_t n = o->n, k6 = n < 6 ? n : 6, k3 = n < 3 ? n : 3;
    Py_ssize_t o_j = 36 + 6 * n, o_sv = o_j + 12 * n, o_st = o_sv + k6, o_sr = o_st + k3,
               o_c = o_sr + k3;
    double *s = self->state, work[36], norms[6];
    if (missing & 1) {
        double j_h[36];
        memcpy(j_h, s + o_j, sizeof(double) * (size_t)(6 * n));
        for (Py_ssize_t t = 3 * n; t < 6 * n; t++) j_h[t] *= o->length;
        pk_singular_values_fast(j_h, 6, n, s + o_sv);
        s[o_c] = s[o_sv] / s[o_sv + k6 - 1];
    }
    if (missing & 2) {
        pk_singular_values_fast(s + o_j, 3, n, s + o_st);
        pk_singular_values_fast(s + o_j + 3 * n, 3, n, s + o_sr);
    }
    if ((missing & 4) && s[o_c + 3] != s[o_c + 3]) { /* settled: the measure not computed */
        double unit[36], sv_a[6];
        for (int j = 0; j < 6; j++) {
            const double *row = s + 6 * j;
            double dist = sqrt(row[0] * row[0] + row[1] * row[1] + row[2] * row[2]);
            for (int i = 0; i < 6; i++)
                unit[6 * j + i] = i < 3 ? row[i] / dist : row[i] / dist / o->length;
        }
        pk_singular_values_one(unit, 6, 6, sv_a, work, norms);
        s[o_c + 3] = sv_a[5] / sv_a[0];
    }
    self->level |= missing;
}

static PyObject *velocity_field(PoseVelocity *self, PyObject *name) {
    int id = field_of(name);
    if (id < 0) return NULL;
    const PoseOne *o = self->owner;
    Py_ssize_t n = o->n, k6 = n < 6 ? n : 6, k3 = n < 3 ? n : 3;
    if (id == F_Q) return pk_new_array(self->q, n, 0);
    if (id == F_TOLERANCE) return PyFloat_FromDouble(self->tol);
    if (id == F_LENGTH) return PyFloat_FromDouble(o->length);
    if (!self->record) {
        int need = field_level[id];
        if (self->level < 0) { /* the first field read: everything but the SVDs it needs not */
            if (pk_pose_fill(self->x, self->q, o->geom, n, o->length, self->tol, need,
                             self->state)) {
                if (!batch_record(self)) return NULL;
            } else {
                self->level = need;
            }
        } else if (need & ~self->level) {
            add_singular_values(self, need & ~self->level);
        }
    }
    if (self->record) return PyObject_GetAttr(self->record, name);
    const double *s = self->state;
    Py_ssize_t o_b = 36, o_j = o_b + 6 * n, o_ji = o_j + 6 * n, o_sv = o_ji + 6 * n,
               o_st = o_sv + k6, o_sr = o_st + k3, o_c = o_sr + k3;
    switch (id) {
    case F_A: return pk_new_array(s, 6, 6);
    case F_B: return pk_new_array(s + o_b, 6, n);
    case F_J: return pk_new_array(s + o_j, 6, n);
    case F_J_H: {
        double j[36];
        memcpy(j, s + o_j, sizeof(double) * (size_t)(6 * n));
        for (Py_ssize_t t = 3 * n; t < 6 * n; t++) j[t] *= o->length;
        return pk_new_array(j, 6, n);
    }
    case F_J_INV: return pk_new_array(s + o_ji, n, 6);
    case F_SV: return pk_new_array(s + o_sv, k6, 0);
    case F_SV_T: return pk_new_array(s + o_st, k3, 0);
    case F_SV_R: return pk_new_array(s + o_sr, k3, 0);
    case F_CONDITION: return scalar(np_float64, s[o_c]);
    case F_DET_A: return scalar(np_float64, s[o_c + 1]);
    case F_DET_B: return scalar(np_float64, s[o_c + 2]);
    case F_PARALLEL: return scalar(np_float64, s[o_c + 3]);
    case F_SERIAL: return scalar(np_float64, s[o_c + 4]);
    case F_SINGULARITY: return PyObject_CallFunction(np_int64, "l", (long)s[o_c + 5]);
    default: { /* F_MODE: the sign of det A, 0 where it is NaN */
        double d = s[o_c + 1];
        return PyObject_CallFunction(np_int64, "l", d > 0.0 ? 1L : d < 0.0 ? -1L : 0L);
    }
    }
}

static void velocity_dealloc(PoseVelocity *self) {
    Py_XDECREF(self->owner);
    Py_XDECREF(self->batch);
    Py_XDECREF(self->record);
    PyObject_Free(self);
}

static PyMethodDef velocity_methods[] = {
    {"field", (PyCFunction)velocity_field, METH_O,
     "field(name): the value of field name of the velocity model (module doc)."},
    {NULL, NULL, 0, NULL},
};

static PyMemberDef velocity_members[] = {
    {"level", T_INT, offsetof(PoseVelocity, level), READONLY,
     "the pk_pose_fill level computed so far (-1: none, or the batch path answered)"},
    {NULL, 0, 0, 0, NULL},
};

static PyTypeObject PoseVelocityType =
    ONE_TYPE(PoseVelocity, "PoseVelocity", velocity_dealloc,
             "The velocity model of one pose, computed when first read (PoseOne.jacobian).",
             velocity_methods, velocity_members);

/* ------------------------------------------------------------------ constructor */

/* count float64 values of a C-contiguous buffer (bytes or an array) into out; count < 0: any
 * multiple of -count up to -count * MAX_RODS, the number of values returned. -1 on error. */
static Py_ssize_t doubles(PyObject *obj, const char *name, Py_ssize_t count, double *out) {
    Py_buffer view;
    if (PyObject_GetBuffer(obj, &view, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0) {
        PyErr_Format(PyExc_TypeError, "%s: a C-contiguous float64 buffer is needed", name);
        return -1;
    }
    const char *f = view.format ? view.format : "B";
    if (f[0] == '@' || f[0] == '=' || f[0] == '<') f++;
    int bytes = f[0] == 'B' && !f[1] && view.itemsize == 1;
    Py_ssize_t got = bytes ? view.len / 8 : view.len / view.itemsize;
    int ok = (bytes && view.len % 8 == 0) || (f[0] == 'd' && !f[1] && view.itemsize == 8);
    ok = ok && (count >= 0 ? got == count
                           : got >= -count && got <= -count * MAX_RODS && got % -count == 0);
    if (ok) memcpy(out, view.buf, sizeof(double) * (size_t)got);
    PyBuffer_Release(&view);
    if (!ok) {
        PyErr_Format(PyExc_ValueError, "%s: wrong size or type", name);
        return -1;
    }
    return got;
}

const char pk_pose_one_doc[] =
"pose_one(rods, groups, simple, boundary_tol, consistency_tol, max_abs, lower, upper, geom,\n"
"         home, opts, length)\n\n"
"A PoseOne: the one-pose calls ik, fk, jacobian of a full-pose machine of m <= 6 rods and\n"
"n actuators (module doc of pose_one.c). rods (m x 24 float64: OnePoseInverse.rows), groups\n"
"(n x 8: rod count, angular, rod indices), simple, the boundary and consistency tolerances\n"
"and max_abs (pk_pose_inverse_one); lower, upper (n,) the strokes widened by their\n"
"tolerance; geom (m x 16), home (6 + 7n,), opts (7,) as solve_one takes them; length the\n"
"characteristic length. Buffers: bytes or C-contiguous float64 arrays.";

static int types_ready;

PyObject *pk_py_pose_one(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 12) {
        PyErr_Format(PyExc_TypeError, "pose_one() takes 12 positional arguments (%zd given)",
                     nargs);
        return NULL;
    }
    if (!types_ready) {
        if (PyType_Ready(&PoseOneType) < 0 || PyType_Ready(&PoseVelocityType) < 0) return NULL;
        types_ready = 1;
    }
    if (pk_numpy_scalars(&np_float64, &np_int64) < 0) return NULL; /* for the fields */
    PoseOne *o = PyObject_New(PoseOne, &PoseOneType);
    if (!o) return NULL;
    o->args = PyTuple_New(nargs);
    if (!o->args) goto fail;
    for (Py_ssize_t i = 0; i < nargs; i++) {
        Py_INCREF(args[i]);
        PyTuple_SET_ITEM(o->args, i, args[i]);
    }
    Py_ssize_t rods = doubles(args[0], "rods", -PK_POSE_ROD, o->rods);
    if (rods < 0) goto fail;
    o->m = rods / PK_POSE_ROD;
    Py_ssize_t lows = doubles(args[6], "lower", -1, o->lo);
    if (lows < 0) goto fail;
    o->n = lows;
    if (o->n > o->m) {
        PyErr_SetString(PyExc_ValueError, "more actuators than rods");
        goto fail;
    }
    if (doubles(args[1], "groups", 8 * o->n, o->groups) < 0
        || doubles(args[7], "upper", o->n, o->hi) < 0
        || doubles(args[8], "geom", 16 * o->m, o->geom) < 0
        || doubles(args[9], "home", 6 + 7 * o->n, o->home) < 0
        || doubles(args[10], "opts", 7, o->opts) < 0)
        goto fail;
    o->simple = PyObject_IsTrue(args[2]);
    if (o->simple < 0) goto fail;
    double *scalars[] = {&o->boundary_tol, &o->consistency_tol, &o->max_abs, &o->length};
    PyObject *given[] = {args[3], args[4], args[5], args[11]};
    for (int i = 0; i < 4; i++) {
        *scalars[i] = PyFloat_AsDouble(given[i]);
        if (*scalars[i] == -1.0 && PyErr_Occurred()) goto fail;
        if (!(*scalars[i] >= 0.0 && *scalars[i] < INFINITY) || (i >= 2 && *scalars[i] == 0.0)) {
            PyErr_SetString(PyExc_ValueError, "tolerances, max_abs and length: finite, >= 0 "
                            "(max_abs and length > 0)");
            goto fail;
        }
    }
    if (o->simple && o->n != o->m) {
        PyErr_SetString(PyExc_ValueError, "simple: as many actuators as rods are needed");
        goto fail;
    }
    for (Py_ssize_t j = 0; j < o->m; j++) {
        double kind = o->rods[PK_POSE_ROD * j], g_kind = o->geom[16 * j + 13],
               actuator = o->geom[16 * j + 14];
        if (!(kind == 0.0 || kind == 1.0 || kind == 2.0) || g_kind != kind
            || !(actuator >= 0.0 && actuator < (double)o->n && actuator == floor(actuator))) {
            PyErr_Format(PyExc_ValueError, "rod %zd: kind or actuator index out of range", j);
            goto fail;
        }
    }
    for (Py_ssize_t k = 0; !o->simple && k < o->n; k++) {
        double count = o->groups[8 * k];
        int bad = !(count >= 1.0 && count <= 6.0 && count == floor(count));
        for (int i = 0; !bad && i < (int)count; i++) {
            double rod = o->groups[8 * k + 2 + i];
            bad = !(rod >= 0.0 && rod < (double)o->m && rod == floor(rod));
        }
        if (bad) {
            PyErr_Format(PyExc_ValueError, "actuator %zd: rod group out of range", k);
            goto fail;
        }
    }
    for (Py_ssize_t k = 0; k < o->n; k++) {
        if (o->lo[k] != o->lo[k] || o->hi[k] != o->hi[k]) {
            PyErr_SetString(PyExc_ValueError, "lower, upper: NaN");
            goto fail;
        }
    }
    return (PyObject *)o;
fail:
    Py_DECREF(o);
    return NULL;
}
