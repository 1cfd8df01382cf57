/* pkmkit.native.kernels: the velocity model of one full pose of a six-rod machine (issue 22
 * §1), the C twin of pkmkit.machines.full_pose_velocity_kernel.velocity_matrices and
 * velocity_one (the Numba kernels behind full_pose_velocity_one.OnePoseFullVelocity).
 *
 * The plain arithmetic (A, B, J^-1, the serial measure, the parallel measure's one-sided
 * Jacobi singular values of svd_kernel) is the Numba kernel's, operation for operation, without
 * FMA contraction: the same bits. J's singular values (condition, singular_values and those of
 * its rows) take svd.c's round-robin Jacobi instead (pk_singular_values_fast, ≈ 1.5x faster:
 * the same accuracy, not the same bits). Where the Numba kernel calls LAPACK (np.linalg.solve
 * and det of 6x6 matrices),
 * this file factors A by its own LU with partial pivoting: the same numbers to rounding (tested
 * to 1e-12 of their scale, x cond A near a parallel singularity, in tests/native), and the
 * flags, whose bound on det(U) keeps a margin far above that rounding, equal.
 *
 * Python face: pose_velocity(geom, x, q, length, tol, exact) -> the kernel's output vector as
 * a bytearray of float64 (full_pose_velocity_kernel.layout(6, n)), or None for a refused row. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <string.h>

#include "kernels.h"

int pk_floats(PyObject *seq, const char *name, Py_ssize_t n, double *out); /* velocity.c */


/* full_pose_direct_kernel._rods: base joints a_j(q) and rod lengths of m rods. */
static void pose_rods(const double *q, const double *geom, ptrdiff_t m, double *base,
                      double *length) {
    for (ptrdiff_t j = 0; j < m; j++) {
        const double *g = geom + 16 * j;
        double qk = q[(ptrdiff_t)g[14]], kind = g[13];
        double *a = base + 3 * j;
        length[j] = g[12];
        if (kind == 0.0) {
            for (int i = 0; i < 3; i++) a[i] = g[i] + qk * g[6 + i];
        } else if (kind == 1.0) {
            for (int i = 0; i < 3; i++) a[i] = g[i];
            length[j] += qk;
        } else {
            double wx = g[6], wy = g[7], wz = g[8];
            double rx = g[0] - g[9], ry = g[1] - g[10], rz = g[2] - g[11];
            double c = cos(qk), s = sin(qk);
            double along = (wx * rx + wy * ry + wz * rz) * (1.0 - c);
            a[0] = g[9] + rx * c + (wy * rz - wz * ry) * s + wx * along;
            a[1] = g[10] + ry * c + (wz * rx - wx * rz) * s + wy * along;
            a[2] = g[11] + rz * c + (wx * ry - wy * rx) * s + wz * along;
        }
    }
}

/* svd_kernel.singular_values of one r x c matrix (row-major) into out (min(r, c)): one-sided
 * Jacobi, the same operations (NaN for a non-finite entry). r, c <= 6. The parallel
 * measure's (the flags: Numba's bits). */
static void jacobi_values(const double *mat, int r, int c, double *out) {
    double work[36], norms[6];
    pk_singular_values_one(mat, r, c, out, work, norms);
}

/* svd.c: the same in round-robin order (J's singular values: condition, singular_values). */
void pk_singular_values_fast(const double *mat, ptrdiff_t r, ptrdiff_t c, double *out);

/* LU with partial pivoting (the first largest |pivot|, as LAPACK's idamax) of a 6x6
 * row-major matrix in place; perm the row order; returns the determinant (0 for an exactly
 * zero pivot, the factorisation then unfinished). */
static double lu6(double *a, int *perm) {
    double det = 1.0;
    for (int i = 0; i < 6; i++) perm[i] = i;
    for (int k = 0; k < 6; k++) {
        int best = k;
        for (int i = k + 1; i < 6; i++)
            if (fabs(a[6 * i + k]) > fabs(a[6 * best + k])) best = i;
        if (a[6 * best + k] == 0.0) return 0.0;
        if (best != k) {
            for (int j = 0; j < 6; j++) {
                double t = a[6 * k + j];
                a[6 * k + j] = a[6 * best + j];
                a[6 * best + j] = t;
            }
            int t = perm[k];
            perm[k] = perm[best];
            perm[best] = t;
            det = -det;
        }
        double pivot = a[6 * k + k];
        det *= pivot;
        for (int i = k + 1; i < 6; i++) {
            double l = a[6 * i + k] / pivot;
            a[6 * i + k] = l;
            for (int j = k + 1; j < 6; j++) a[6 * i + j] -= l * a[6 * k + j];
        }
    }
    return det;
}

static double det6(const double *m) {
    double a[36];
    int perm[6];
    memcpy(a, m, sizeof a);
    return lu6(a, perm);
}

/* One full pose: full_pose_velocity_kernel._fill (and, by the bits of exact, velocity_one's
 * singular values: pk_pose_velocity_doc) for six rods; out laid out as its layout(6, n). 0, or 1 when the row is refused
 * (not finite, or A exactly singular where J is needed: the batch path decides). Also
 * called by pose_one.c. */
int pk_pose_fill(const double *x, const double *q, const double *geom, ptrdiff_t n,
                     double length_l, double tol, int exact, double *out) {
    enum { M = 6 };
    double base[3 * M], length[M], r[9], a[6 * M], unit[6 * M], b[6 * M];
    pose_rods(q, geom, M, base, length);
    pk_rotation(x[3], x[4], x[5], r);
    memset(b, 0, sizeof(double) * (size_t)(M * n));
    double serial = INFINITY;
    for (int j = 0; j < M; j++) {
        const double *g = geom + 16 * j;
        double bx = g[3], by = g[4], bz = g[5];
        double sx = r[0] * bx + r[1] * by + r[2] * bz;
        double sy = r[3] * bx + r[4] * by + r[5] * bz;
        double sz = r[6] * bx + r[7] * by + r[8] * bz;
        double dx = x[0] + sx - base[3 * j], dy = x[1] + sy - base[3 * j + 1],
               dz = x[2] + sz - base[3 * j + 2];
        double *row = a + 6 * j;
        row[0] = dx; row[1] = dy; row[2] = dz;
        row[3] = sy * dz - sz * dy; row[4] = sz * dx - sx * dz; row[5] = sx * dy - sy * dx;
        double kind = g[13], vx, vy, vz;
        ptrdiff_t k = (ptrdiff_t)g[14];
        if (kind == 0.0) {
            vx = g[6]; vy = g[7]; vz = g[8];
        } else if (kind == 2.0) {
            double wx = g[6], wy = g[7], wz = g[8];
            double px = base[3 * j] - g[9], py = base[3 * j + 1] - g[10],
                   pz = base[3 * j + 2] - g[11];
            vx = wy * pz - wz * py; vy = wz * px - wx * pz; vz = wx * py - wy * px;
        } else {
            vx = vy = vz = 0.0;
        }
        double dist = sqrt(dx * dx + dy * dy + dz * dz);
        for (int i = 0; i < 6; i++) unit[6 * j + i] = i < 3 ? row[i] / dist : row[i] / dist / length_l;
        if (kind == 1.0) {
            b[n * j + k] = length[j];
            serial = pk_min(serial, 1.0);
        } else {
            b[n * j + k] = dx * vx + dy * vy + dz * vz;
            double c = fabs(b[n * j + k]) / (dist * sqrt(vx * vx + vy * vy + vz * vz));
            if (c != c) return 1; /* 0/0: the batch path decides */
            serial = pk_min(serial, c);
        }
    }
    for (int t = 0; t < 6 * M; t++)
        if (!isfinite(a[t]) || !isfinite(unit[t])) return 1;
    for (ptrdiff_t t = 0; t < M * n; t++)
        if (!isfinite(b[t])) return 1;
    if (!isfinite(serial)) return 1;
    ptrdiff_t k6 = n < 6 ? n : 6, k3 = n < 3 ? n : 3;
    ptrdiff_t o_b = 6 * M, o_j = o_b + M * n, o_ji = o_j + 6 * n, o_sv = o_ji + 6 * n,
              o_st = o_sv + k6, o_sr = o_st + k3, o_cond = o_sr + k3;
    double parallel = NAN;
    int settle = 0;
    if (!(exact & 4)) { /* _surely_above */
        double frobenius = 0.0;
        for (int t = 0; t < 36; t++) frobenius += unit[t] * unit[t];
        double f3 = frobenius / 3.0;
        settle = fabs(det6(unit)) > (4.0 * tol + 2e-12) * (f3 * f3 * f3);
    }
    if (!settle) {
        double sv_a[6];
        jacobi_values(unit, 6, 6, sv_a);
        parallel = sv_a[5] / sv_a[0];
    }
    /* A measure within 1e-9 (relative) of tol: its flag is decided by the measure's last bits,
     * which the batch path rounds otherwise (an ulp or a few): that band is the batch path's
     * (25 of 250 flags at tol = the measure differed on the Gough-Stewart before). */
    if (fabs(serial - tol) <= 1e-9 * tol || fabs(parallel - tol) <= 1e-9 * tol) return 1;
    long flags = (serial < tol ? 1 : 0) | (parallel < tol ? 2 : 0);
    double lu[36];
    int perm[6];
    memcpy(lu, a, sizeof lu);
    double det_a = lu6(lu, perm);
    double *j_mat = out + o_j;
    if (flags & 2) {
        for (ptrdiff_t t = 0; t < 6 * n; t++) j_mat[t] = NAN;
    } else {
        if (det_a == 0.0) return 1; /* LinAlgError in the Numba kernel: the batch path */
        for (ptrdiff_t c = 0; c < n; c++) { /* J[:, c] = A^-1 B[:, c] */
            double y[6];
            for (int i = 0; i < 6; i++) {
                double s = b[n * perm[i] + c];
                for (int t = 0; t < i; t++) s -= lu[6 * i + t] * y[t];
                y[i] = s;
            }
            for (int i = 5; i >= 0; i--) {
                double s = y[i];
                for (int t = i + 1; t < 6; t++) s -= lu[6 * i + t] * y[t];
                y[i] = s / lu[6 * i + i];
            }
            for (int i = 0; i < 6; i++) j_mat[n * i + c] = y[i];
        }
    }
    memcpy(out, a, sizeof a);
    memcpy(out + o_b, b, sizeof(double) * (size_t)(M * n));
    /* J^-1 = B+ A (entry (c, j) of B+: B[j, c] / |B[:, c]|^2; 0 below 1e-15 of the largest) */
    double squares[6] = {0}, largest = 0.0;
    for (ptrdiff_t c = 0; c < n; c++)
        for (int j = 0; j < M; j++) squares[c] += b[n * j + c] * b[n * j + c];
    for (ptrdiff_t c = 0; c < n; c++) largest = pk_max(largest, sqrt(squares[c]));
    for (ptrdiff_t c = 0; c < n; c++) {
        int keep = sqrt(squares[c]) > 1e-15 * largest;
        for (int i = 0; i < 6; i++) {
            double s = 0.0;
            if (keep)
                for (int j = 0; j < M; j++) s += b[n * j + c] / squares[c] * a[6 * j + i];
            out[o_ji + 6 * c + i] = (flags & 2) ? NAN : s;
        }
    }
    out[o_cond + 1] = det_a;
    out[o_cond + 2] = n == 6 ? det6(b) : NAN;
    out[o_cond + 3] = parallel;
    out[o_cond + 4] = serial;
    out[o_cond + 5] = (double)flags;
    if (exact & 3) {
        double j_h[36];
        for (ptrdiff_t t = 0; t < 6 * n; t++) j_h[t] = j_mat[t];
        for (ptrdiff_t t = 3 * n; t < 6 * n; t++) j_h[t] *= length_l;
        pk_singular_values_fast(j_h, 6, n, out + o_sv);
        if (exact & 2) {
            pk_singular_values_fast(j_mat, 3, n, out + o_st);
            pk_singular_values_fast(j_mat + 3 * n, 3, n, out + o_sr);
        } else { /* those of J_h only (condition, singular_values) */
            for (ptrdiff_t t = o_st; t < o_cond; t++) out[t] = NAN;
        }
        out[o_cond] = out[o_sv] / out[o_sv + k6 - 1];
    } else {
        for (ptrdiff_t t = o_sv; t < o_cond + 1; t++) out[t] = NAN;
    }
    return 0;
}

const char pk_pose_velocity_doc[] =
"pose_velocity(geom, x, q, length, tol, exact)\n\n"
"The velocity model of one full pose of a six-rod machine: the C twin of\n"
"pkmkit.machines.full_pose_velocity_kernel.velocity_matrices (exact 0) and velocity_one\n"
"(exact 7; its bits: 1 the singular values of J_h and the condition, 2 those of J's linear\n"
"and angular rows (with 1), 4 the parallel measure even where its bound settles). geom (6, 16) float64 C-contiguous (full_pose_direct.DirectKernel.geom), x the\n"
"pose (6 floats) and q its actuator coordinates (n <= 6 floats), lists or tuples; length the\n"
"characteristic length, tol the singularity threshold. Returns the output vector of\n"
"full_pose_velocity_kernel.layout(6, n) as a bytearray of float64, or None when the row is\n"
"refused (not finite, or A exactly singular where J is needed).";

PyObject *pk_py_pose_velocity(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 6) {
        PyErr_Format(PyExc_TypeError, "pose_velocity() takes 6 positional arguments (%zd given)",
                     nargs);
        return NULL;
    }
    if (!PyList_CheckExact(args[2]) && !PyTuple_CheckExact(args[2])) {
        PyErr_SetString(PyExc_TypeError, "q: a list or tuple of floats is needed");
        return NULL;
    }
    Py_ssize_t n = PySequence_Fast_GET_SIZE(args[2]);
    if (n < 1 || n > 6) {
        PyErr_SetString(PyExc_ValueError, "q: 1 to 6 actuator values are needed");
        return NULL;
    }
    double x[6], q[6];
    if (pk_floats(args[1], "x", 6, x) < 0 || pk_floats(args[2], "q", n, q) < 0) return NULL;
    double length_l = PyFloat_AsDouble(args[3]);
    if (length_l == -1.0 && PyErr_Occurred()) return NULL;
    double tol = PyFloat_AsDouble(args[4]);
    if (tol == -1.0 && PyErr_Occurred()) return NULL;
    long exact = PyLong_AsLong(args[5]);
    if (exact == -1 && PyErr_Occurred()) return NULL;
    if (exact < 0 || exact > 7) {
        PyErr_SetString(PyExc_ValueError, "exact: 0 to 7");
        return NULL;
    }
    if (!(tol > 0 && tol < INFINITY) || !(length_l > 0 && length_l < INFINITY)) {
        PyErr_SetString(PyExc_ValueError, "length and tol must be positive and finite");
        return NULL;
    }
    Py_buffer view;
    if (PyObject_GetBuffer(args[0], &view, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT) < 0) {
        PyErr_SetString(PyExc_TypeError, "geom: a C-contiguous float64 array is needed");
        return NULL;
    }
    const char *f = view.format ? view.format : "B";
    if (f[0] == '<' || f[0] == '=' || f[0] == '@') f++;
    if (strcmp(f, "d") != 0 || view.itemsize != 8 || view.ndim != 2 || view.shape[0] != 6
        || view.shape[1] != 16) {
        PyBuffer_Release(&view);
        PyErr_SetString(PyExc_ValueError, "geom: a (6, 16) float64 array is needed");
        return NULL;
    }
    double geom[96];
    memcpy(geom, view.buf, sizeof geom);
    PyBuffer_Release(&view);
    for (int j = 0; j < 6; j++) {
        double actuator = geom[16 * j + 14], kind = geom[16 * j + 13];
        if (!(actuator >= 0.0 && actuator < (double)n && actuator == floor(actuator))
            || !(kind == 0.0 || kind == 1.0 || kind == 2.0)) {
            PyErr_Format(PyExc_ValueError, "rod %d: actuator index or kind out of range", j);
            return NULL;
        }
    }
    Py_ssize_t k6 = n < 6 ? n : 6, k3 = n < 3 ? n : 3;
    Py_ssize_t size = 36 + 6 * n + 6 * n + 6 * n + k6 + 2 * k3 + 6;
    PyObject *state = PyByteArray_FromStringAndSize(NULL, size * (Py_ssize_t)sizeof(double));
    if (!state) return NULL;
    if (pk_pose_fill(x, q, geom, n, length_l, tol, (int)exact, (double *)PyByteArray_AS_STRING(state))) {
        Py_DECREF(state);
        Py_RETURN_NONE;
    }
    return state;
}

/* ------------------------------------------------------------------ inverse model */

/* full_pose_one.OnePoseInverse.__call__ for a pose x (6 finite floats): rods (m, PK_POSE_ROD)
 * as its rows, groups (n, 8): count, angular, then the rod indices, of the actuators (unused
 * when simple). 0, or 1 where it returns None. Called by pose_one.c (PoseOne.ik, .jacobian). */
int pk_pose_inverse_one(const double *x, const double *rods, ptrdiff_t m, const double *groups,
                        ptrdiff_t n, int simple, double boundary_tol, double tol, double *q,
                        double *rod_q) {
    double px = x[0], py = x[1], pz = x[2], r[9];
    pk_rotation(x[3], x[4], x[5], r);
    for (ptrdiff_t j = 0; j < m; j++) {
        const double *t = rods + PK_POSE_ROD * j;
        double kind = t[0], bx = t[1], by = t[2], bz = t[3], cx = t[4], cy = t[5], cz = t[6],
               ux = t[7], uy = t[8], uz = t[9], length_sq = t[10], length = t[11],
               ox = t[12], oy = t[13], oz = t[14], e1x = t[15], e1y = t[16], e1z = t[17],
               e2x = t[18], e2y = t[19], e2z = t[20], radius = t[21], offset = t[22],
               sigma = t[23];
        double qx = px + r[0] * bx + r[1] * by + r[2] * bz;
        double qy = py + r[3] * bx + r[4] * by + r[5] * bz;
        double qz = pz + r[6] * bx + r[7] * by + r[8] * bz;
        if (kind == 2.0) { /* crank */
            double vx = qx - ox, vy = qy - oy, vz = qz - oz;
            double vw = vx * ux + vy * uy + vz * uz - offset;
            double v1 = vx * e1x + vy * e1y + vz * e1z;
            double v2 = vx * e2x + vy * e2y + vz * e2z;
            double perp = sqrt(v1 * v1 + v2 * v2);
            double g = vw * vw + perp * perp + radius * radius - length_sq;
            double amplitude = 2.0 * radius * perp;
            if (amplitude <= 0.0) return 1;
            double cosine = g / amplitude;
            if (fabs(g) - amplitude <= boundary_tol * length_sq) {
                cosine = pk_min(1.0, pk_max(-1.0, cosine));
            } else if (!(-1.0 <= cosine && cosine <= 1.0)) {
                return 1;
            }
            double angle = atan2(v2, v1) + sigma * acos(cosine);
            rod_q[j] = pk_pymod(angle + PK_PI, 2.0 * PK_PI) - PK_PI;
            continue;
        }
        double wxr = qx - cx, wyr = qy - cy, wzr = qz - cz;
        double dist_sq = wxr * wxr + wyr * wyr + wzr * wzr;
        if (kind == 1.0) { /* strut */
            rod_q[j] = sqrt(dist_sq) - length;
            continue;
        }
        double s = wxr * ux + wyr * uy + wzr * uz;
        double radicand = length_sq - dist_sq + s * s;
        if (radicand < 0.0) {
            if (radicand <= -boundary_tol * length_sq) return 1;
            radicand = 0.0;
        }
        rod_q[j] = s + sigma * sqrt(radicand);
    }
    if (simple) {
        for (ptrdiff_t j = 0; j < m; j++) q[j] = rod_q[j];
        return 0;
    }
    for (ptrdiff_t k = 0; k < n; k++) {
        const double *g = groups + 8 * k;
        int count = (int)g[0], angular = g[1] != 0.0;
        double first = rod_q[(ptrdiff_t)g[2]], diffs[6], sum = 0.0;
        diffs[0] = 0.0;
        for (int i = 1; i < count; i++) {
            double d = rod_q[(ptrdiff_t)g[2 + i]] - first;
            if (angular) d = pk_pymod(d + PK_PI, 2.0 * PK_PI) - PK_PI;
            diffs[i] = d;
            sum += d;
        }
        double mean = sum / count;
        double worst = fabs(diffs[0] - mean);
        for (int i = 1; i < count; i++) worst = pk_max(worst, fabs(diffs[i] - mean));
        if (worst > tol) return 1;
        q[k] = first + mean;
    }
    return 0;
}

const char pk_state_array_doc[] =
"state_array(state, start, rows, cols)\n\n"
"A new float64 array of shape (rows, cols) (cols 0: (rows,)) holding the doubles\n"
"state[start:start + rows * max(cols, 1)] of a pose_velocity result.";

PyObject *pk_py_state_array(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 4) {
        PyErr_Format(PyExc_TypeError, "state_array() takes 4 positional arguments (%zd given)",
                     nargs);
        return NULL;
    }
    if (!PyByteArray_CheckExact(args[0])) {
        PyErr_SetString(PyExc_TypeError, "state: a pose_velocity result is needed");
        return NULL;
    }
    Py_ssize_t start = PyLong_AsSsize_t(args[1]), rows = PyLong_AsSsize_t(args[2]),
               cols = PyLong_AsSsize_t(args[3]);
    if (PyErr_Occurred()) return NULL;
    Py_ssize_t size = PyByteArray_GET_SIZE(args[0]) / (Py_ssize_t)sizeof(double);
    Py_ssize_t count = rows * (cols ? cols : 1);
    if (start < 0 || rows < 1 || rows > 36 || cols < 0 || cols > 36 || start + count > size) {
        PyErr_SetString(PyExc_ValueError, "start, rows, cols: out of the state");
        return NULL;
    }
    return pk_new_array((const double *)PyByteArray_AS_STRING(args[0]) + start, rows, cols);
}
