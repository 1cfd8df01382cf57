/* pkmkit.native.kernels: one pose per call of a translational rod-leg machine in one C call
 * each (issue 22 §1): m.ik(x), m.fk(q) and m.jacobian(x) of a plain pose.
 *
 * A machine's constants are packed once (closed_form_one.one_pose_pack: bytes of float64, the
 * layout below); each call then reads its input (a list or tuple of floats or ints, or a 1-D
 * float64 NumPy array: what the Python one-pose paths take), checks it (the right count, every
 * value finite and within +-max_abs), solves, checks the strokes and returns a new NumPy array
 * — or None for anything the machine's batch path treats specially (another input type, a
 * value out of range, no real assembly, aligned sphere centres, a pose near a parallel
 * singularity whose solution the batch path checks, an actuator value beyond its stroke, an
 * unknown `strokes`): the machine then takes that path, which gives the same numbers and the
 * typed errors. The formulas are those of RodClosedForm.inverse_one (rod_inverse in
 * velocity.c) and closed_form_one.direct_one, in the same order of operations, compiled
 * without FMA contraction: the same bits as the Python one-pose paths and the batch row.
 *
 * Pack layout (float64): [0] n (legs = coordinates, 2 or 3), [1] max_abs, [2] suspect_gram,
 * [3] rel_tol, [4] near (velocity_one's NEAR_PARALLEL), [5..8) reserved, [8..11) the strokes'
 * lower limits and [11..14) their upper limits (STROKE_TOL included; +-inf unlimited), then
 * n x PK_INV_LEG inverse legs (RodClosedForm._single_legs of the working branches), n x PK_LEG
 * velocity legs (velocity_one.native_legs), n x PK_DIR_LEG direct legs (closed_form_one._legs).
 *
 * Python face: rod_ik_one(pack, x, strokes) -> q or None; rod_fk_one(pack, q, sign, strokes)
 * -> pose or None; rod_jacobian_one(pack, x, tol) -> a state for rod_field (velocity.c: the
 * fields computed when the first is read) or None. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <string.h>

#include "kernels.h"

#define PK_DIR_LEG 17
#define PK_HEAD 14

/* The pack's legs count n (2 or 3) and its head; NULL with an exception if it is not one. */
static const double *pack_of(PyObject *obj, int *n) {
    if (!PyBytes_CheckExact(obj)) {
        PyErr_SetString(PyExc_TypeError, "pack: bytes are needed");
        return NULL;
    }
    const double *p = (const double *)PyBytes_AS_STRING(obj); /* 8-aligned: bytes data */
    Py_ssize_t size = PyBytes_GET_SIZE(obj);
    int legs = size >= (Py_ssize_t)sizeof(double) ? (int)p[0] : 0;
    Py_ssize_t want = (Py_ssize_t)sizeof(double) * (PK_HEAD + legs * (PK_INV_LEG + PK_LEG
                                                                        + PK_DIR_LEG));
    if ((legs != 2 && legs != 3) || size != want) {
        PyErr_SetString(PyExc_ValueError, "pack: not a one-pose pack of 2 or 3 legs");
        return NULL;
    }
    *n = legs;
    return p;
}

/* 1 to check the strokes ("flag", "refuse"), 0 not ("ignore"), -1 another value. */
static int stroke_check(PyObject *strokes) {
    if (!PyUnicode_Check(strokes)) return -1;
    if (PyUnicode_CompareWithASCIIString(strokes, "flag") == 0
        || PyUnicode_CompareWithASCIIString(strokes, "refuse") == 0)
        return 1;
    return PyUnicode_CompareWithASCIIString(strokes, "ignore") == 0 ? 0 : -1;
}

/* Machine._within_strokes: every value within its stroke (NaN: outside). */
static int within(const double *pack, int n, const double *v) {
    for (int i = 0; i < n; i++)
        if (!(pack[8 + i] <= v[i] && v[i] <= pack[11 + i])) return 0;
    return 1;
}

/* closed_form_one.direct_one: the platform point of configuration q in the assembly mode of
 * sign `sign`; 0, or 1 where direct_one returns None. */
static int rod_direct(const double *pack, int n, const double *q, long sign, double *out) {
    const double *legs = pack + PK_HEAD + n * (PK_INV_LEG + PK_LEG);
    double suspect = pack[2], rel_tol = pack[3];
    double cx[3], cy[3], cz[3], rr[3];
    for (int i = 0; i < n; i++) {
        const double *t = legs + PK_DIR_LEG * i;
        double v = q[i], length = t[7];
        if (t[0] == 0.0) { /* slide */
            cx[i] = t[1] + v * t[4];
            cy[i] = t[2] + v * t[5];
            cz[i] = t[3] + v * t[6];
            rr[i] = length * length;
        } else if (t[0] == 1.0) { /* strut */
            if (!(length + v > 0.0)) return 1;
            cx[i] = t[1];
            cy[i] = t[2];
            cz[i] = t[3];
            rr[i] = (length + v) * (length + v);
        } else { /* crank */
            double c = cos(v), s = sin(v);
            cx[i] = t[8] + c * t[11] + s * t[14];
            cy[i] = t[9] + c * t[12] + s * t[15];
            cz[i] = t[10] + c * t[13] + s * t[16];
            rr[i] = length * length;
        }
    }
    double r1 = rr[0], r2 = rr[1], gram, wx, wy, wz, nx, ny, nz;
    if (n == 3) {
        double r3 = rr[2];
        double e1x = cx[1] - cx[0], e1y = cy[1] - cy[0], e1z = cz[1] - cz[0];
        double e2x = cx[2] - cx[0], e2y = cy[2] - cy[0], e2z = cz[2] - cz[0];
        double g11 = e1x * e1x + e1y * e1y + e1z * e1z;
        double g12 = e1x * e2x + e1y * e2y + e1z * e2z;
        double g22 = e2x * e2x + e2y * e2y + e2z * e2z;
        double h2 = 0.5 * (r1 - r2 + g11);
        double h3 = 0.5 * (r1 - r3 + g22);
        gram = g11 * g22 - g12 * g12;
        double size_sq = r1 + g11 + g22;
        if (!(gram >= suspect * size_sq * size_sq)) return 1; /* (nearly) aligned centres */
        double alpha = (h2 * g22 - h3 * g12) / gram;
        double beta = (h3 * g11 - h2 * g12) / gram;
        wx = alpha * e1x + beta * e2x;
        wy = alpha * e1y + beta * e2y;
        wz = alpha * e1z + beta * e2z;
        nx = e1y * e2z - e1z * e2y;
        ny = e1z * e2x - e1x * e2z;
        nz = e1x * e2y - e1y * e2x;
    } else {
        double ex = cx[1] - cx[0], ey = cy[1] - cy[0];
        gram = ex * ex + ey * ey;
        if (!(gram >= suspect * (r1 + gram))) return 1;
        double alpha = 0.5 * (r1 - r2 + gram) / gram;
        wx = alpha * ex;
        wy = alpha * ey;
        wz = 0.0;
        nx = -ey;
        ny = ex;
        nz = 0.0;
    }
    double t_sq = (r1 - (wx * wx + wy * wy + wz * wz)) / gram;
    /* a double root, or rounding away from the batch row's test of one (direct_all's sums
     * round otherwise): the batch path */
    if (fabs(t_sq) <= 2.0 * rel_tol * r1 / gram) return 1;
    if (!(t_sq >= 0.0)) return 1; /* no real assembly */
    double t = sign > 0 ? sqrt(t_sq) : -sqrt(t_sq);
    out[0] = cx[0] + wx + t * nx;
    out[1] = cy[0] + wy + t * ny;
    if (n == 3) out[2] = cz[0] + wz + t * nz;
    return 0;
}

int pk_rod_inverse_one(const double *legs, Py_ssize_t n, int dims, const double *x,
                       double *q); /* velocity.c */

const char pk_rod_ik_one_doc[] =
"rod_ik_one(pack, x, strokes)\n\n"
"Machine.ik(x) of one plain pose (a list or tuple of 2 or 3 numbers, or a 1-D float64\n"
"array) in one call: q as a new float64 array, or None where the batch path must answer\n"
"(see rod_one.c). strokes 'flag' or 'refuse': None beyond a stroke; 'ignore': unchecked.";

PyObject *pk_py_rod_ik_one(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    int n;
    if (nargs != 3) {
        PyErr_Format(PyExc_TypeError, "rod_ik_one() takes 3 positional arguments (%zd given)",
                     nargs);
        return NULL;
    }
    const double *pack = pack_of(args[0], &n);
    if (!pack) return NULL;
    double x[3], q[3];
    int got = pk_plain_numbers(args[1], n, pack[1], x); /* plain_numbers.c */
    if (got != PK_PLAIN_TAKEN) return got < 0 ? NULL : Py_NewRef(Py_None);
    int check = stroke_check(args[2]);
    if (check < 0 || pk_rod_inverse_one(pack + PK_HEAD, n, n, x, q)
        || (check && !within(pack, n, q)))
        Py_RETURN_NONE;
    return pk_new_array(q, n, 0);
}

const char pk_rod_fk_one_doc[] =
"rod_fk_one(pack, q, sign, strokes)\n\n"
"Machine.fk(q) of one plain configuration in the assembly mode of sign `sign` (+-1) in one\n"
"call: the pose as a new float64 array, or None where the batch path must answer (see\n"
"rod_one.c). strokes as for rod_ik_one (the given q checked).";

PyObject *pk_py_rod_fk_one(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    int n;
    if (nargs != 4) {
        PyErr_Format(PyExc_TypeError, "rod_fk_one() takes 4 positional arguments (%zd given)",
                     nargs);
        return NULL;
    }
    const double *pack = pack_of(args[0], &n);
    if (!pack) return NULL;
    long sign = PyLong_AsLong(args[2]);
    if (sign == -1 && PyErr_Occurred()) return NULL;
    double q[3], pose[3];
    int got = pk_plain_numbers(args[1], n, pack[1], q);
    if (got != PK_PLAIN_TAKEN) return got < 0 ? NULL : Py_NewRef(Py_None);
    int check = stroke_check(args[3]);
    if (check < 0 || (check && !within(pack, n, q)) || rod_direct(pack, n, q, sign, pose))
        Py_RETURN_NONE;
    return pk_new_array(pose, n, 0);
}

const char pk_rod_jacobian_one_doc[] =
"rod_jacobian_one(pack, x, tol)\n\n"
"Machine.jacobian(x) of one plain pose in one call: the inverse model (working branches)\n"
"within the strokes, kept with x in a state (a bytearray) whose fields rod_field computes\n"
"when the first is read; None where the batch path must answer (see rod_one.c).";

PyObject *pk_py_rod_jacobian_one(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    int n;
    if (nargs != 3) {
        PyErr_Format(PyExc_TypeError,
                     "rod_jacobian_one() takes 3 positional arguments (%zd given)", nargs);
        return NULL;
    }
    const double *pack = pack_of(args[0], &n);
    if (!pack) return NULL;
    double tol = PyFloat_AsDouble(args[2]);
    if (tol == -1.0 && PyErr_Occurred()) return NULL;
    if (!(tol > 0 && tol < INFINITY)) {
        PyErr_SetString(PyExc_ValueError, "tol must be positive and finite");
        return NULL;
    }
    double x[3], q[3];
    int got = pk_plain_numbers(args[1], n, pack[1], x); /* plain_numbers.c */
    if (got != PK_PLAIN_TAKEN) return got < 0 ? NULL : Py_NewRef(Py_None);
    if (pk_rod_inverse_one(pack + PK_HEAD, n, n, x, q) || !within(pack, n, q)) Py_RETURN_NONE;
    PyObject *state = PyByteArray_FromStringAndSize(NULL, sizeof(pk_rod_state));
    if (!state) return NULL;
    pk_rod_state *s = (pk_rod_state *)PyByteArray_AS_STRING(state);
    memset(s, 0, sizeof(pk_rod_state));
    s->n = n;
    s->ok = PK_F_Q | PK_F_X;
    s->pending = 1;
    memcpy(s->legs, pack + PK_HEAD + n * PK_INV_LEG, sizeof(double) * (size_t)(n * PK_LEG));
    memcpy(s->x, x, sizeof(double) * (size_t)n);
    memcpy(s->q, q, sizeof(double) * (size_t)n);
    s->tol = tol;
    s->near = pack[4];
    return state;
}
