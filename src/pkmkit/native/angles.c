/* Angles of a table's poses -> rotation vectors: the algebra of
 * pkmkit.spatial.euler.rotvec_from_angles (quaternion products of the three elementary
 * rotations, the canonical sign, the rotation vector's scale) in one pass per row instead of
 * some forty NumPy passes (issue 22 §5: `pkmkit ik gough-stewart --input`).
 *
 * The transcendental functions stay NumPy's (the caller computes the half angles' sines and
 * cosines, arctan2 and the sine of the half rotation angle: NumPy's arctan2 is a vectorised
 * one on AVX-512 CPUs, not the C library's), and the operations here are those of the NumPy
 * functions, in their order (np.cross's a_j b_k - a_k b_j, zero components of the elementary
 * quaternions included), compiled without FMA contraction or fast-math (setup.py): the same
 * bits as the NumPy path.
 *
 * Python faces (C-contiguous float64 arrays; run without the GIL):
 *   euler_quat(sin_half (N, 3), cos_half (N, 3), seq, quat (N, 5))
 *   euler_rotvec(values (N, 6), quat (N, 5), angle (N,), sin_half (N,), scale, out (N, 6))
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <math.h>

#include "kernels.h"

/* quat_multiply: p q of (x, y, z, w) quaternions, as pkmkit.spatial.euler's. */
static void ea_multiply(const double *p, const double *q, double *r) {
    double c0 = p[1] * q[2] - p[2] * q[1];
    double c1 = p[2] * q[0] - p[0] * q[2];
    double c2 = p[0] * q[1] - p[1] * q[0];
    double x = p[3] * q[0] + q[3] * p[0] + c0;
    double y = p[3] * q[1] + q[3] * p[1] + c1;
    double z = p[3] * q[2] + q[3] * p[2] + c2;
    double w = p[3] * q[3] - p[0] * q[0] - p[1] * q[1] - p[2] * q[2];
    r[0] = x;
    r[1] = y;
    r[2] = z;
    r[3] = w;
}

static void ea_quat(const double *s, const double *c, Py_ssize_t size, const int *axes,
                    int intrinsic, double *quat) {
    for (Py_ssize_t k = 0; k < size; k++) {
        double e[3][4] = {{0.0}}, t[4], r[4];
        for (int j = 0; j < 3; j++) {
            e[j][3] = c[3 * k + j];
            e[j][axes[j]] = s[3 * k + j];
        }
        if (intrinsic) {
            ea_multiply(e[0], e[1], t);
            ea_multiply(t, e[2], r);
        } else {
            ea_multiply(e[1], e[0], t);
            ea_multiply(e[2], t, r);
        }
        double x = r[0], y = r[1], z = r[2], w = r[3];
        int flip = (w < 0) || (w == 0 && (x < 0 || (x == 0 && (y < 0 || (y == 0 && z < 0)))));
        if (flip) {
            x = -x;
            y = -y;
            z = -z;
            w = -w;
        }
        double *out = quat + 5 * k;
        out[0] = x;
        out[1] = y;
        out[2] = z;
        out[3] = w;
        out[4] = sqrt(x * x + y * y + z * z);
    }
}

static void ea_rotvec(const double *values, const double *quat, const double *angle,
                      const double *half_sin, double scale, Py_ssize_t size, double *out) {
    for (Py_ssize_t k = 0; k < size; k++) {
        const double *v = values + 6 * k, *q = quat + 5 * k;
        double *o = out + 6 * k;
        int finite = 1;
        for (int j = 0; j < 6; j++) finite &= isfinite(v[j]) != 0;
        if (!finite) {
            for (int j = 0; j < 6; j++) o[j] = NAN;
            continue;
        }
        double a = angle[k], a2 = a * a, f;
        if (a <= 1e-3)
            f = 2.0 + a2 / 12.0 + 7.0 * a2 * a2 / 2880.0;
        else
            f = a / half_sin[k];
        for (int j = 0; j < 3; j++) {
            o[j] = v[j] * scale;
            o[3 + j] = f * q[j];
        }
    }
}

/* ------------------------------------------------------------------ Python face */

const char pk_euler_quat_doc[] =
    "euler_quat(sin_half, cos_half, seq, quat)\n\n"
    "The unit quaternions (x, y, z, w) of angles in the scipy axis sequence seq ('xyz'\n"
    "extrinsic, 'ZYX' intrinsic, ...), given the sines and cosines of the half angles\n"
    "(N, 3): the products of pkmkit.spatial.euler.quat_from_angles, the canonical sign of\n"
    "rotvec_from_quat (w > 0, else the first non-zero of x, y, z positive), and the norm of\n"
    "(x, y, z) in column 4 of quat (N, 5). C-contiguous float64; runs without the GIL.";

PyObject *pk_py_euler_quat(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 4) {
        PyErr_Format(PyExc_TypeError, "euler_quat() takes 4 positional arguments (%zd given)",
                     nargs);
        return NULL;
    }
    Py_ssize_t length;
    const char *seq = PyUnicode_AsUTF8AndSize(args[2], &length);
    if (seq == NULL) return NULL;
    int axes[3], lower = 0, upper = 0;
    for (int j = 0; j < 3 && length == 3; j++) {
        char ch = seq[j];
        lower += ch >= 'x' && ch <= 'z';
        upper += ch >= 'X' && ch <= 'Z';
        axes[j] = (ch | 0x20) - 'x';
    }
    if (length != 3 || (lower != 3 && upper != 3)) {
        PyErr_Format(PyExc_ValueError, "seq: three axes of x, y, z, all lower or all upper "
                     "case, got %R", args[2]);
        return NULL;
    }
    Py_buffer s, c, q;
    Py_ssize_t any[2] = {-1, 3};
    if (pk_take(args[0], &s, "sin_half", 'd', 0, 2, any) < 0) return NULL;
    Py_ssize_t size = s.shape[0], three[2] = {size, 3}, five[2] = {size, 5};
    if (pk_take(args[1], &c, "cos_half", 'd', 0, 2, three) < 0) {
        PyBuffer_Release(&s);
        return NULL;
    }
    if (pk_take(args[3], &q, "quat", 'd', 1, 2, five) < 0) {
        PyBuffer_Release(&s);
        PyBuffer_Release(&c);
        return NULL;
    }
    Py_BEGIN_ALLOW_THREADS
    ea_quat(s.buf, c.buf, size, axes, upper == 3, q.buf);
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&s);
    PyBuffer_Release(&c);
    PyBuffer_Release(&q);
    Py_RETURN_NONE;
}

const char pk_euler_rotvec_doc[] =
    "euler_rotvec(values, quat, angle, sin_half, scale, out)\n\n"
    "Pose rows out (N, 6): the positions values[:, :3] * scale and the rotation vectors of\n"
    "euler_quat's quat (N, 5) (the series below 1e-3 rad, else angle / sin_half times\n"
    "(x, y, z): pkmkit.spatial.euler.rotvec_from_quat), where angle (N,) is\n"
    "2 arctan2(norm, w) and sin_half (N,) sin(angle / 2); NaN rows where a value of values\n"
    "(N, 6) is not finite. C-contiguous float64; runs without the GIL.";

PyObject *pk_py_euler_rotvec(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 6) {
        PyErr_Format(PyExc_TypeError, "euler_rotvec() takes 6 positional arguments "
                     "(%zd given)", nargs);
        return NULL;
    }
    double scale = PyFloat_AsDouble(args[4]);
    if (scale == -1.0 && PyErr_Occurred()) return NULL;
    Py_buffer v[5];
    Py_ssize_t any[2] = {-1, 6};
    if (pk_take(args[0], &v[0], "values", 'd', 0, 2, any) < 0) return NULL;
    Py_ssize_t size = v[0].shape[0];
    Py_ssize_t five[2] = {size, 5}, one[1] = {size}, six[2] = {size, 6};
    const char *names[4] = {"quat", "angle", "sin_half", "out"};
    const Py_ssize_t *shapes[4] = {five, one, one, six};
    int ndims[4] = {2, 1, 1, 2}, held = 1;
    for (int j = 0; j < 4; j++) {
        PyObject *obj = args[j < 3 ? j + 1 : 5];
        if (pk_take(obj, &v[held], names[j], 'd', j == 3, ndims[j], shapes[j]) < 0) break;
        held++;
    }
    if (held == 5) {
        Py_BEGIN_ALLOW_THREADS
        ea_rotvec(v[0].buf, v[1].buf, v[2].buf, v[3].buf, scale, size, v[4].buf);
        Py_END_ALLOW_THREADS
    }
    for (int j = 0; j < held; j++) PyBuffer_Release(&v[j]);
    if (held < 5) return NULL;
    Py_RETURN_NONE;
}
