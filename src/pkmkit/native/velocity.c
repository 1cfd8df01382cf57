/* pkmkit.native.kernels: the velocity model of one pose of a translational rod-leg machine
 * (issue 22 §1), the C twin of pkmkit.machines.velocity_one.OnePoseVelocity.
 *
 * The same operations in the same order as velocity_one.py (itself the operations of
 * velocity_chunk and numerics.small on one row), compiled without FMA contraction and without
 * fast-math, so every field it answers is the batch row's bits. NumPy's arccos is not libm's
 * acos (it differs in the last place for about one argument in ten on AVX-512 machines), so
 * the closed-form singular values call NumPy's own float64 arccos loop (found once, checked
 * against numpy.arccos; when it cannot be found the fields that need it are not answered).
 * Nearly equal singular values, which velocity_one.py hands to numpy.linalg.svd, are answered
 * by NumPy's own svd gufunc loop called from here (the same LAPACK call: the same bits).
 * Whatever else velocity_one.py hands elsewhere (a sum that is not finite, a zero row, a
 * reciprocal that overflows, a ZeroDivisionError) is not answered here either: rod_field
 * returns None and the Python path decides.
 *
 * Python face: rod_inverse(legs, x, max_abs) -> q (list) or None, the twin of
 * RodClosedForm.inverse_one; rod_velocity(legs, x, q, tol, near) -> state (a bytearray
 * holding a pk_rod_state); rod_field(state, code) -> the field (NumPy array or scalar) or
 * None. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <string.h>

#include "kernels.h"

/* ------------------------------------------------------------------ NumPy's arccos */

/* The head of NumPy's PyUFuncObject (numpy/ufuncobject.h, unchanged since NumPy 1.x). */
typedef void (*pk_loop)(char **args, const Py_ssize_t *dims, const Py_ssize_t *steps,
                        void *data);
typedef struct {
    PyObject_HEAD
    int nin, nout, nargs;
    int identity;
    pk_loop *functions;
    void *const *data;
    int ntypes;
    int reserved1;
    const char *name;
    const char *types;
} pk_ufunc_head;

static pk_loop acos_loop = NULL;
static void *acos_data = NULL;
static int acos_state = 0; /* 0 not looked for, 1 found and checked, -1 unavailable */

static double np_acos(double x) {
    double out;
    char *args[2] = {(char *)&x, (char *)&out};
    Py_ssize_t dims[1] = {1}, steps[2] = {8, 8};
    acos_loop(args, dims, steps, acos_data);
    return out;
}

/* Find numpy.arccos's float64 loop and check it against numpy.arccos on 64 arguments. */
static int find_acos(void) {
    PyObject *numpy = PyImport_ImportModule("numpy");
    if (!numpy) return -1;
    PyObject *ufunc = PyObject_GetAttrString(numpy, "arccos");
    Py_DECREF(numpy);
    if (!ufunc) return -1;
    int found = -1;
    const pk_ufunc_head *head = (const pk_ufunc_head *)ufunc;
    if (strcmp(Py_TYPE(ufunc)->tp_name, "numpy.ufunc") == 0 && head->nin == 1
        && head->nout == 1 && head->nargs == 2 && head->name
        && strcmp(head->name, "arccos") == 0 && head->types && head->functions) {
        for (int i = 0; i < head->ntypes; i++) {
            if (head->types[2 * i] == 12 && head->types[2 * i + 1] == 12) { /* NPY_DOUBLE */
                acos_loop = head->functions[i];
                acos_data = head->data ? head->data[i] : NULL;
                found = 1;
                break;
            }
        }
    }
    for (int k = 0; found == 1 && k < 64; k++) {
        double x = -1.0 + k / 31.5 + 1e-3 * sin((double)k);
        if (x > 1.0) x = 1.0;
        PyObject *arg = PyFloat_FromDouble(x);
        PyObject *want = arg ? PyObject_CallOneArg(ufunc, arg) : NULL;
        Py_XDECREF(arg);
        double w = want ? PyFloat_AsDouble(want) : -2.0;
        Py_XDECREF(want);
        if (PyErr_Occurred()) PyErr_Clear();
        if (memcmp(&w, &(double){np_acos(x)}, sizeof(double)) != 0) found = -1;
    }
    Py_DECREF(ufunc);
    if (found != 1) acos_loop = NULL;
    return found;
}

/* ------------------------------------------------------- NumPy's LAPACK singular values */

/* Where the closed forms hand a 3x3 matrix to LAPACK (nearly equal singular values: the
 * Orthoglide near its isotropic home, the linear Delta near its axis), the Python path and the
 * batch path call numpy.linalg.svd(m, compute_uv=False): NumPy's gufunc
 * numpy.linalg._umath_linalg.svd, loop 'd->d' (LAPACK dgesdd, JOBZ 'N'). Its float64 loop is
 * found once, as the arccos loop, and called on the matrix (outer dimension 1, the core
 * dimensions m = n = 3, the row-major strides): the same LAPACK call on the same numbers, so
 * NumPy's bits — checked against numpy.linalg.svd on matrices with nearly equal singular
 * values when found; unavailable (another NumPy), the Python path answers as before. */
static pk_loop svd_loop = NULL;
static void *svd_data = NULL;
static int svd_state = 0; /* 0 not looked for, 1 found and checked, -1 unavailable */

/* The singular values of a row-major 3x3 matrix by NumPy's gufunc loop; 0, or 1 where LAPACK
 * did not converge (the loop gives NaN there: the Python path decides). */
static int np_svd3(const double *mat, double *sv) {
    char *args[2] = {(char *)mat, (char *)sv};
    Py_ssize_t dims[4] = {1, 3, 3, 3};
    Py_ssize_t steps[5] = {72, 24, 24, 8, 8};
    svd_loop(args, dims, steps, svd_data);
    return !(sv[0] == sv[0] && sv[1] == sv[1] && sv[2] == sv[2]);
}

static int find_svd(void) {
    PyObject *mod = PyImport_ImportModule("numpy.linalg._umath_linalg");
    PyObject *ufunc = mod ? PyObject_GetAttrString(mod, "svd") : NULL;
    Py_XDECREF(mod);
    if (!ufunc) { /* another NumPy: the Python path answers */
        PyErr_Clear();
        return -1;
    }
    int found = -1;
    const pk_ufunc_head *head = (const pk_ufunc_head *)ufunc;
    if (strcmp(Py_TYPE(ufunc)->tp_name, "numpy.ufunc") == 0 && head->nin == 1
        && head->nout == 1 && head->nargs == 2 && head->name && strcmp(head->name, "svd") == 0
        && head->types && head->functions) {
        for (int i = 0; i < head->ntypes; i++) {
            if (head->types[2 * i] == 12 && head->types[2 * i + 1] == 12) { /* NPY_DOUBLE */
                svd_loop = head->functions[i];
                svd_data = head->data ? head->data[i] : NULL;
                found = 1;
                break;
            }
        }
    }
    Py_DECREF(ufunc);
    /* checked against numpy.linalg.svd: isotropic and nearly isotropic matrices, others */
    PyObject *numpy = found == 1 ? PyImport_ImportModule("numpy") : NULL;
    PyObject *linalg = numpy ? PyObject_GetAttrString(numpy, "linalg") : NULL;
    PyObject *svd = linalg ? PyObject_GetAttrString(linalg, "svd") : NULL;
    PyObject *array = numpy ? PyObject_GetAttrString(numpy, "array") : NULL;
    for (int k = 0; found == 1 && k < 24; k++) {
        double m[9], got[3] = {0, 0, 0}, want[3] = {-1, -1, -1};
        for (int e = 0; e < 9; e++)
            m[e] = (e % 4 == 0 ? 1.0 : 0.0) + (k < 12 ? 1e-7 : 0.3) * sin(1.0 + k * 9 + e);
        PyObject *rows = Py_BuildValue("[[ddd][ddd][ddd]]", m[0], m[1], m[2], m[3], m[4], m[5],
                                       m[6], m[7], m[8]);
        PyObject *arr = rows && array ? PyObject_CallOneArg(array, rows) : NULL;
        PyObject *kw = Py_BuildValue("{s:O}", "compute_uv", Py_False);
        PyObject *given = arr ? PyTuple_Pack(1, arr) : NULL;
        PyObject *out = given && kw && svd ? PyObject_Call(svd, given, kw) : NULL;
        Py_XDECREF(given);
        PyObject *list = out ? PyObject_CallMethod(out, "tolist", NULL) : NULL;
        if (list && PyList_Check(list) && PyList_GET_SIZE(list) == 3)
            for (int i = 0; i < 3; i++) want[i] = PyFloat_AsDouble(PyList_GET_ITEM(list, i));
        PyObject *held[5] = {rows, arr, kw, out, list};
        for (int i = 0; i < 5; i++) Py_XDECREF(held[i]);
        if (PyErr_Occurred()) PyErr_Clear();
        if (np_svd3(m, got) || memcmp(got, want, sizeof(got)) != 0) found = -1;
    }
    PyObject *names[4] = {numpy, linalg, svd, array};
    for (int i = 0; i < 4; i++) Py_XDECREF(names[i]);
    if (found != 1) svd_loop = NULL;
    return found;
}

/* --------------------------------------------------------------- singular values */

/* velocity_one.singular_values of a finite row-major 2x2 or 3x3 matrix into sv (decreasing);
 * 0, or 1 where the Python path calls LAPACK (or NumPy's arccos is unavailable). */
static int pk_singular_values(const double *mat, int n, double *sv) {
    if (n == 2) {
        double a = mat[0], b = mat[1], c = mat[2], d = mat[3];
        double s1 = 0.5 * (hypot(a + d, c - b) + hypot(a - d, b + c));
        sv[0] = s1;
        sv[1] = s1 > 0 ? fabs(a * d - b * c) / s1 : 0.0;
        return 0;
    }
    if (acos_state == 0) acos_state = find_acos();
    if (acos_state != 1) return 1;
    double m00 = mat[0], m01 = mat[1], m02 = mat[2], m10 = mat[3], m11 = mat[4],
           m12 = mat[5], m20 = mat[6], m21 = mat[7], m22 = mat[8];
    double g00 = m00 * m00 + m10 * m10 + m20 * m20;
    double g11 = m01 * m01 + m11 * m11 + m21 * m21;
    double g22 = m02 * m02 + m12 * m12 + m22 * m22;
    double g01 = m00 * m01 + m10 * m11 + m20 * m21;
    double g02 = m00 * m02 + m10 * m12 + m20 * m22;
    double g12 = m01 * m02 + m11 * m12 + m21 * m22;
    double mean = (g00 + g11 + g22) / 3.0;
    double d0 = g00 - mean, d1 = g11 - mean, d2 = g22 - mean;
    double spread = sqrt((d0 * d0 + d1 * d1 + d2 * d2
                          + 2.0 * (g01 * g01 + g02 * g02 + g12 * g12)) / 6.0);
    double scale = spread > 0 ? 1.0 / spread : 0.0;
    double s00 = d0 * scale, s11 = d1 * scale, s22 = d2 * scale;
    double s01 = g01 * scale, s02 = g02 * scale, s12 = g12 * scale;
    double sym_det = (s00 * (s11 * s22 - s12 * s12) - s01 * (s01 * s22 - s12 * s02)
                      + s02 * (s01 * s12 - s11 * s02));
    double half_det = pk_min(pk_max(0.5 * sym_det, -1.0), 1.0);
    double lam1 = mean + 2.0 * spread * cos(np_acos(half_det) / 3.0);
    double s1 = lam1 > 0 ? sqrt(lam1) : 0.0;
    double c00 = m11 * m22 - m12 * m21, c01 = m12 * m20 - m10 * m22, c02 = m10 * m21 - m11 * m20;
    double c10 = m21 * m02 - m22 * m01, c11 = m22 * m00 - m20 * m02, c12 = m20 * m01 - m21 * m00;
    double c20 = m01 * m12 - m02 * m11, c21 = m02 * m10 - m00 * m12, c22 = m00 * m11 - m01 * m10;
    double d = fabs(m00 * c00 + m01 * c01 + m02 * c02);
    double e2 = (c00 * c00 + c01 * c01 + c02 * c02 + c10 * c10 + c11 * c11 + c12 * c12
                 + c20 * c20 + c21 * c21 + c22 * c22);
    double pair = s1 > 0 ? d / s1 : 0.0;
    double rest = lam1 > 0 ? (e2 - pair * pair) / lam1 : 0.0;
    if (spread > 0 && (fabs(half_det) > 1.0 - 1e-6 || rest - 2 * pair < 1e-6 * rest)) {
        /* nearly equal singular values: LAPACK, as the Python and the batch paths */
        if (svd_state == 0) svd_state = find_svd();
        return svd_state == 1 ? np_svd3(mat, sv) : 1;
    }
    double s2 = 0.5 * (sqrt(pk_max(rest + 2 * pair, 0.0)) + sqrt(pk_max(rest - 2 * pair, 0.0)));
    double s3 = s2 > 0 ? pair / s2 : 0.0;
    if (s2 > s1) s2 = s1;
    sv[0] = s1;
    sv[1] = s2;
    sv[2] = s3 < s2 ? s3 : s2;
    return 0;
}

/* ------------------------------------------------------------------ the pieces */

/* velocity_one._surely_above */
static int surely_above(double det_a, const double *lengths, int n, double t) {
    double product = lengths[0] * lengths[1] * (n == 3 ? lengths[2] : 1.0);
    return fabs(det_a) > (4.0 * t + 2e-12) * product;
}

/* velocity_one.rows: A row-major (n x n) and diag B of one pose; legs (n, PK_LEG). */
static void rod_rows(const double *legs, int n, const double *x, const double *q, double *a,
                     double *b) {
    double x0 = x[0], x1 = x[1], x2 = n == 2 ? 0.0 : x[2];
    for (int i = 0; i < n; i++) {
        const double *t = legs + PK_LEG * i;
        double qi = q[i], a0, a1, a2, bi;
        if (t[0] == 0.0) { /* slide */
            double u0 = t[4], u1 = t[5], u2 = t[6];
            a0 = x0 - (t[1] + qi * u0);
            a1 = x1 - (t[2] + qi * u1);
            a2 = x2 - (t[3] + qi * u2);
            bi = 0.0;
            if (u0) bi += a0 * u0;
            if (u1) bi += a1 * u1;
            if (u2) bi += a2 * u2;
        } else if (t[0] == 2.0) { /* crank */
            double e0 = t[4], e1 = t[5], e2 = t[6], f0 = t[7], f1 = t[8], f2 = t[9];
            double radius = t[10], c = cos(qi), s = sin(qi);
            a0 = x0 - ((t[1] + radius * (c * e0 + s * f0)) - t[11]);
            a1 = x1 - ((t[2] + radius * (c * e1 + s * f1)) - t[12]);
            a2 = x2 - ((t[3] + radius * (c * e2 + s * f2)) - t[13]);
            bi = (0.0 + a0 * (radius * (c * f0 - s * e0)) + a1 * (radius * (c * f1 - s * e1))
                  + a2 * (radius * (c * f2 - s * e2)));
        } else { /* strut */
            a0 = x0 - t[1];
            a1 = x1 - t[2];
            a2 = x2 - t[3];
            bi = t[4] + qi;
        }
        a[n * i] = a0;
        a[n * i + 1] = a1;
        if (n == 3) a[n * i + 2] = a2;
        b[i] = bi;
    }
}

/* The parallel measure (sigma_min / sigma_max of A with unit rows) into the state, once; 1 if
 * it is answered. Needs the row lengths (PK_F_SERIAL). */
static int rod_parallel(pk_rod_state *s) {
    if (s->ok & PK_F_PARALLEL) return 1;
    if (s->parallel_tried || !(s->ok & PK_F_SERIAL)) return 0;
    s->parallel_tried = 1;
    int n = s->n, nn = n * n;
    double unit[9], sv_u[3];
    for (int k = 0; k < nn; k++) unit[k] = s->a[k] / s->lengths[k / n];
    int parallel_ok = !pk_singular_values(unit, n, sv_u) && sv_u[0] != 0.0;
    s->parallel = parallel_ok ? sv_u[n - 1] / sv_u[0] : NAN;
    if (parallel_ok) s->ok |= PK_F_PARALLEL;
    return parallel_ok;
}

/* velocity_one.sv: J's singular values and the condition number, once J is known
 * (s->svd_pending); from J^-1 near a parallel singularity, as the batch path. */
static void rod_svd(pk_rod_state *s) {
    s->svd_pending = 0;
    int n = s->n;
    double *sv = s->sv, det_a = s->det_a;
    if (!surely_above(det_a, s->lengths, n, s->near)) {
        if (!rod_parallel(s)) return;
        if (s->parallel < s->near && s->parallel < s->serial) {
            double inverse[3];
            if (s->zero_b || pk_singular_values(s->j_inv, n, inverse)) return;
            for (int i = 0; i < n; i++) {
                if (inverse[n - 1 - i] == 0.0) return; /* ZeroDivisionError in Python */
                sv[i] = 1.0 / inverse[n - 1 - i];
            }
            goto condition;
        }
    }
    if (pk_singular_values(s->j, n, sv)) return;
condition:
    s->condition = sv[n - 1] == 0.0 ? INFINITY : sv[0] / sv[n - 1];
    s->ok |= PK_F_SV | PK_F_CONDITION;
}

/* Every field but the singular values of J, the condition number and (where the flags do
 * not need it) the parallel measure, which rod_svd and rod_parallel add when asked. */
#define PK_FLAG_BAND 1e-9 /* velocity_one.FLAG_BAND */

static void rod_core(const double *legs, int n, const double *x, const double *q, double tol,
                     double near, pk_rod_state *s) {
    double *a = s->a, *b = s->b;
    int nn = n * n;
    s->n = n;
    s->ok &= PK_F_Q | PK_F_X; /* the inputs a rod_jacobian_one state keeps */
    rod_rows(legs, n, x, q, a, b);
    double sum_a = 0.0, sum_b = 0.0; /* Python's sum(a) + sum(b) (3.11: in order) */
    for (int k = 0; k < nn; k++) sum_a += a[k];
    for (int i = 0; i < n; i++) sum_b += b[i];
    double total = sum_a + sum_b;
    if (!(-INFINITY < total && total < INFINITY)) return; /* the Python path decides */
    s->ok |= PK_F_A | PK_F_B | PK_F_DET_A | PK_F_DET_B | PK_F_MODE;
    double cof[9] = {0}, det_a;
    if (n == 2) {
        cof[0] = a[3]; cof[1] = -a[2]; cof[2] = -a[1]; cof[3] = a[0];
        det_a = a[0] * a[3] - a[1] * a[2];
    } else {
        double a00 = a[0], a01 = a[1], a02 = a[2], a10 = a[3], a11 = a[4], a12 = a[5],
               a20 = a[6], a21 = a[7], a22 = a[8];
        cof[0] = a11 * a22 - a12 * a21; cof[1] = a12 * a20 - a10 * a22;
        cof[2] = a10 * a21 - a11 * a20; cof[3] = a21 * a02 - a22 * a01;
        cof[4] = a22 * a00 - a20 * a02; cof[5] = a20 * a01 - a21 * a00;
        cof[6] = a01 * a12 - a02 * a11; cof[7] = a02 * a10 - a00 * a12;
        cof[8] = a00 * a11 - a01 * a10;
        det_a = a00 * cof[0] + a01 * cof[1] + a02 * cof[2];
    }
    s->det_a = det_a;
    s->mode = (det_a > 0) - (det_a < 0);
    s->det_b = n == 3 ? b[0] * b[1] * b[2] : b[0] * b[1];
    int zero_b = 0;
    for (int i = 0; i < n; i++) zero_b |= b[i] == 0.0;
    s->zero_b = zero_b;
    if (!zero_b) {
        for (int k = 0; k < nn; k++) s->j_inv[k] = a[k] / b[k / n];
        s->ok |= PK_F_J_INV;
    }
    double *lengths = s->lengths;
    s->near = near;
    for (int i = 0; i < n; i++) {
        const double *r = a + n * i;
        lengths[i] = n == 2 ? sqrt(r[0] * r[0] + r[1] * r[1])
                            : sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    }
    if (!(lengths[0] > 0 && lengths[1] > 0 && lengths[n - 1] > 0)) return; /* a zero row */
    double serial = fabs(b[0]) / lengths[0];
    for (int i = 1; i < n; i++) {
        double v = fabs(b[i]) / lengths[i];
        if (v < serial) serial = v;
    }
    s->serial = serial;
    s->ok |= PK_F_SERIAL;
    /* A measure within 1e-9 (relative) of tol: its flag is decided by its last bits, which the
     * batch path rounds otherwise; the flags, J and what follows them are then left to the
     * Python pieces, which hand that band to the batch path (velocity_one.in_band) */
    if (fabs(serial - tol) <= PK_FLAG_BAND * tol) return;
    /* velocity_one.at_parallel: the parallel measure only where its bound cannot tell */
    int at_parallel;
    if (surely_above(det_a, lengths, n, tol)) {
        at_parallel = 0;
    } else if (!rod_parallel(s)) {
        return;
    } else if (det_a != 0.0 && fabs(s->parallel - tol) <= PK_FLAG_BAND * tol) {
        return;
    } else {
        at_parallel = s->parallel < tol || det_a == 0.0;
    }
    s->flags = (serial < tol ? 1 : 0) | (at_parallel ? 2 : 0); /* Singularity.SERIAL, PARALLEL */
    s->ok |= PK_F_SINGULARITY;
    double *j = s->j;
    if (at_parallel) {
        for (int k = 0; k < nn; k++) j[k] = NAN;
        for (int i = 0; i < n; i++) s->sv[i] = NAN;
        s->condition = NAN;
        s->ok |= PK_F_J | PK_F_SV | PK_F_CONDITION;
        return;
    }
    double inv_det = 1.0 / det_a; /* det_a != 0 here (else at_parallel) */
    if (!(-INFINITY < inv_det && inv_det < INFINITY)) return;
    double s0 = b[0] * inv_det, s1 = b[1] * inv_det;
    if (n == 2) {
        j[0] = cof[0] * s0; j[1] = cof[2] * s1; j[2] = cof[1] * s0; j[3] = cof[3] * s1;
    } else {
        double s2 = b[2] * inv_det;
        j[0] = cof[0] * s0; j[1] = cof[3] * s1; j[2] = cof[6] * s2;
        j[3] = cof[1] * s0; j[4] = cof[4] * s1; j[5] = cof[7] * s2;
        j[6] = cof[2] * s0; j[7] = cof[5] * s1; j[8] = cof[8] * s2;
    }
    for (int k = 0; k < nn; k++)
        if (!(-INFINITY < j[k] && j[k] < INFINITY)) return;
    s->ok |= PK_F_J;
    s->svd_pending = 1;
}

void pk_rod_velocity(const double *legs, int n, const double *x, const double *q, double tol,
                     double near, pk_rod_state *s) {
    rod_core(legs, n, x, q, tol, near, s);
    rod_parallel(s);
    if (s->svd_pending) rod_svd(s);
}

/* ------------------------------------------------------------------ Python face */

static PyObject *np_empty = NULL, *np_float64 = NULL, *np_int64 = NULL;

static int numpy_names(void);

/* numpy.empty (a borrowed reference), or NULL with an exception (also for pose_velocity.c
 * and plain_numbers.c). */
PyObject *pk_numpy_empty(void) { return numpy_names() < 0 ? NULL : np_empty; }

/* numpy.float64 and numpy.int64 (borrowed) into the pointers (pose_one.c); -1 on error. */
int pk_numpy_scalars(PyObject **float64, PyObject **int64) {
    if (numpy_names() < 0) return -1;
    *float64 = np_float64;
    *int64 = np_int64;
    return 0;
}

static int numpy_names(void) {
    if (np_empty) return 0;
    PyObject *numpy = PyImport_ImportModule("numpy");
    if (!numpy) return -1;
    np_float64 = PyObject_GetAttrString(numpy, "float64");
    np_int64 = PyObject_GetAttrString(numpy, "int64");
    np_empty = PyObject_GetAttrString(numpy, "empty");
    Py_DECREF(numpy);
    return np_empty && np_float64 && np_int64 ? 0 : -1;
}

/* n floats from a list or tuple of exact Python floats; -1 with TypeError otherwise (also
 * used by pose_velocity.c). */
int pk_floats(PyObject *seq, const char *name, Py_ssize_t n, double *out) {
    if (!PyList_CheckExact(seq) && !PyTuple_CheckExact(seq)) {
        PyErr_Format(PyExc_TypeError, "%s: a list or tuple of floats is needed", name);
        return -1;
    }
    if (PySequence_Fast_GET_SIZE(seq) != n) {
        PyErr_Format(PyExc_ValueError, "%s: %zd values needed", name, n);
        return -1;
    }
    PyObject **items = PySequence_Fast_ITEMS(seq);
    for (Py_ssize_t i = 0; i < n; i++) {
        if (!PyFloat_CheckExact(items[i])) {
            PyErr_Format(PyExc_TypeError, "%s[%zd]: a float is needed", name, i);
            return -1;
        }
        out[i] = PyFloat_AS_DOUBLE(items[i]);
    }
    return 0;
}

const char pk_rod_velocity_doc[] =
"rod_velocity(legs, x, q, tol, near)\n\n"
"The velocity model of one pose of a translational rod-leg machine (the C twin of\n"
"pkmkit.machines.velocity_one.OnePoseVelocity): legs the per-leg constants (bytes of n x 14\n"
"float64: kind, then the terms of velocity_one._legs, zero-padded), x the pose and q its\n"
"actuator coordinates (n = 2 or 3 floats each, list or tuple), tol and near the thresholds.\n"
"Returns the state (a bytearray) that rod_field reads.";

PyObject *pk_py_rod_velocity(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 5) {
        PyErr_Format(PyExc_TypeError, "rod_velocity() takes 5 positional arguments (%zd given)",
                     nargs);
        return NULL;
    }
    if (!PyBytes_CheckExact(args[0])) {
        PyErr_SetString(PyExc_TypeError, "legs: bytes are needed");
        return NULL;
    }
    Py_ssize_t size = PyBytes_GET_SIZE(args[0]);
    Py_ssize_t n = size / (Py_ssize_t)(PK_LEG * sizeof(double));
    if ((n != 2 && n != 3) || size != n * (Py_ssize_t)(PK_LEG * sizeof(double))) {
        PyErr_SetString(PyExc_ValueError, "legs: 2 or 3 legs of 14 float64 are needed");
        return NULL;
    }
    double legs[3 * PK_LEG], x[3], q[3], tol, near;
    memcpy(legs, PyBytes_AS_STRING(args[0]), (size_t)size);
    for (Py_ssize_t i = 0; i < n; i++) {
        double kind = legs[PK_LEG * i];
        if (kind != 0.0 && kind != 1.0 && kind != 2.0) {
            PyErr_Format(PyExc_ValueError, "legs: leg %zd: kind must be 0, 1 or 2", i);
            return NULL;
        }
    }
    if (pk_floats(args[1], "x", n, x) < 0 || pk_floats(args[2], "q", n, q) < 0) return NULL;
    tol = PyFloat_AsDouble(args[3]);
    if (tol == -1.0 && PyErr_Occurred()) return NULL;
    near = PyFloat_AsDouble(args[4]);
    if (near == -1.0 && PyErr_Occurred()) return NULL;
    if (!(tol > 0 && tol < INFINITY) || !(near > 0 && near < INFINITY)) {
        PyErr_SetString(PyExc_ValueError, "tol and near must be positive and finite");
        return NULL;
    }
    PyObject *state = PyByteArray_FromStringAndSize(NULL, sizeof(pk_rod_state));
    if (!state) return NULL;
    pk_rod_state *s = (pk_rod_state *)PyByteArray_AS_STRING(state);
    memset(s, 0, sizeof(pk_rod_state));
    pk_rod_velocity(legs, (int)n, x, q, tol, near, s);
    if (PyErr_Occurred()) { /* finding NumPy's arccos raised (then cleared): never here */
        Py_DECREF(state);
        return NULL;
    }
    return state;
}

static PyObject *scalar(PyObject *type, PyObject *value) {
    if (!value) return NULL;
    PyObject *out = PyObject_CallOneArg(type, value);
    Py_DECREF(value);
    return out;
}

const char pk_rod_field_doc[] =
"rod_field(state, code)\n\n"
"Field `code` of a rod_velocity or rod_jacobian_one state (0 A, 1 B, 2 J, 3 J_inv,\n"
"4 singular_values, 5 condition, 6 det_A, 7 det_B, 8 parallel_measure, 9 serial_measure,\n"
"10 singularity, 11 mode; of a rod_jacobian_one state also 12 q and 13 x, its inputs), as\n"
"the single-pose Jacobians record holds it (NumPy arrays, numpy.float64, numpy.int64), or\n"
"None where the Python path must answer. A rod_jacobian_one state computes its fields\n"
"when first asked: the rows, determinants, J and the flags on the first read; J's singular\n"
"values, the condition number and the parallel measure when one of them is read.";

PyObject *pk_py_rod_field(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 2) {
        PyErr_Format(PyExc_TypeError, "rod_field() takes 2 positional arguments (%zd given)",
                     nargs);
        return NULL;
    }
    if (!PyByteArray_CheckExact(args[0])
        || PyByteArray_GET_SIZE(args[0]) != (Py_ssize_t)sizeof(pk_rod_state)) {
        PyErr_SetString(PyExc_TypeError, "state: a rod_velocity state is needed");
        return NULL;
    }
    long code = PyLong_AsLong(args[1]);
    if (code == -1 && PyErr_Occurred()) return NULL;
    if (code < 0 || code > 13) {
        PyErr_Format(PyExc_ValueError, "code: 0 to 13, got %ld", code);
        return NULL;
    }
    pk_rod_state *s = (pk_rod_state *)PyByteArray_AS_STRING(args[0]);
    if (s->pending && code < 12) { /* rod_jacobian_one's state: its fields, once */
        s->pending = 0;
        rod_core(s->legs, s->n, s->x, s->q, s->tol, s->near, s);
    }
    if (code == 8) rod_parallel(s); /* the singular values when a field needs them */
    if ((code == 4 || code == 5) && s->svd_pending) rod_svd(s);
    if (PyErr_Occurred()) return NULL;
    if (!(s->ok & (1u << code))) Py_RETURN_NONE;
    if (numpy_names() < 0) return NULL;
    int n = s->n;
    switch (code) {
    case 0: return pk_new_array(s->a, n, n);
    case 1: {
        double diag[9] = {0};
        for (int i = 0; i < n; i++) diag[(n + 1) * i] = s->b[i];
        return pk_new_array(diag, n, n);
    }
    case 2: return pk_new_array(s->j, n, n);
    case 3: return pk_new_array(s->j_inv, n, n);
    case 4: return pk_new_array(s->sv, n, 0);
    case 5: return scalar(np_float64, PyFloat_FromDouble(s->condition));
    case 6: return scalar(np_float64, PyFloat_FromDouble(s->det_a));
    case 7: return scalar(np_float64, PyFloat_FromDouble(s->det_b));
    case 8: return scalar(np_float64, PyFloat_FromDouble(s->parallel));
    case 9: return scalar(np_float64, PyFloat_FromDouble(s->serial));
    case 10: return scalar(np_int64, PyLong_FromLong(s->flags));
    case 11: return scalar(np_int64, PyLong_FromLong(s->mode));
    case 12: return pk_new_array(s->q, n, 0);
    default: return pk_new_array(s->x, n, 0);
    }
}

/* ------------------------------------------------------------------ inverse model */

/* RodClosedForm.inverse_one for one pose x (dims = 2 or 3) and legs (n, PK_INV_LEG) laid out
 * as its _single_legs tuples; 0, or 1 where inverse_one returns None (also for rod_one.c). */
int pk_rod_inverse_one(const double *legs, Py_ssize_t n, int dims, const double *x,
                       double *q) {
    double x0 = x[0], x1 = x[1], x2 = dims == 3 ? x[2] : 0.0;
    for (Py_ssize_t i = 0; i < n; i++) {
        const double *t = legs + PK_INV_LEG * i;
        double y0, y1, y2, perp_sq;
        if (dims == 3) {
            y0 = t[1] * x0 + t[2] * x1 + t[3] * x2 - t[10];
            y1 = t[4] * x0 + t[5] * x1 + t[6] * x2 - t[11];
            y2 = t[7] * x0 + t[8] * x1 + t[9] * x2 - t[12];
            perp_sq = y1 * y1 + y2 * y2;
        } else {
            y0 = t[1] * x0 + t[2] * x1 - t[10];
            y1 = t[4] * x0 + t[5] * x1 - t[11];
            y2 = 0.0;
            perp_sq = y1 * y1;
        }
        double length_sq = t[13], length = t[14], limit = t[15], radius_sq = t[16],
               diameter = t[17], offset = t[18], branch = t[19];
        if (t[0] == 0.0) { /* slide */
            double radicand = length_sq - perp_sq;
            if (radicand < 0.0) {
                if (radicand <= -limit) return 1;
                radicand = 0.0;
            }
            double root = sqrt(radicand);
            q[i] = branch < 0 ? y0 - root : y0 + root;
        } else if (t[0] == 2.0) { /* crank */
            double along = y0 - offset;
            double g = along * along + perp_sq + radius_sq - length_sq;
            double amplitude = diameter * sqrt(perp_sq);
            if (amplitude == 0.0) return 1;
            double cosine = g / amplitude;
            if (!(-1.0 <= cosine && cosine <= 1.0)) {
                if (fabs(g) - amplitude > limit) return 1;
                cosine = cosine < 0.0 ? -1.0 : 1.0;
            }
            double angle = atan2(y2, y1) + branch * acos(cosine);
            q[i] = pk_pymod(angle + PK_PI, 2.0 * PK_PI) - PK_PI;
        } else { /* strut */
            q[i] = sqrt(perp_sq + y0 * y0) - length;
        }
    }
    return 0;
}

const char pk_rod_inverse_doc[] =
"rod_inverse(legs, x, max_abs)\n\n"
"The C twin of pkmkit.machines.closed_form.RodClosedForm.inverse_one: legs the per-leg\n"
"constants of its _single_legs (bytes of n x 20 float64), x the pose (a list or tuple of 2 or\n"
"3 floats). Returns q (a list of n floats), or None where inverse_one returns None and also\n"
"where x is not a list or tuple of exact floats (inverse_one then decides).";

PyObject *pk_py_rod_inverse(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 3) {
        PyErr_Format(PyExc_TypeError, "rod_inverse() takes 3 positional arguments (%zd given)",
                     nargs);
        return NULL;
    }
    if (!PyBytes_CheckExact(args[0])) {
        PyErr_SetString(PyExc_TypeError, "legs: bytes are needed");
        return NULL;
    }
    Py_ssize_t size = PyBytes_GET_SIZE(args[0]);
    Py_ssize_t n = size / (Py_ssize_t)(PK_INV_LEG * sizeof(double));
    if (n < 1 || n > 3 || size != n * (Py_ssize_t)(PK_INV_LEG * sizeof(double))) {
        PyErr_SetString(PyExc_ValueError, "legs: 1 to 3 legs of 20 float64 are needed");
        return NULL;
    }
    double max_abs = PyFloat_AsDouble(args[2]);
    if (max_abs == -1.0 && PyErr_Occurred()) return NULL;
    PyObject *seq = args[1];
    if (!PyList_CheckExact(seq) && !PyTuple_CheckExact(seq)) Py_RETURN_NONE;
    Py_ssize_t dims = PySequence_Fast_GET_SIZE(seq);
    if (dims != n || dims < 2) Py_RETURN_NONE; /* as many legs as coordinates */
    PyObject **items = PySequence_Fast_ITEMS(seq);
    double x[3], q[3], legs[3 * PK_INV_LEG];
    for (Py_ssize_t i = 0; i < dims; i++) {
        if (!PyFloat_CheckExact(items[i])) Py_RETURN_NONE;
        x[i] = PyFloat_AS_DOUBLE(items[i]);
        if (!(-max_abs <= x[i] && x[i] <= max_abs)) Py_RETURN_NONE;
    }
    memcpy(legs, PyBytes_AS_STRING(args[0]), (size_t)size);
    for (Py_ssize_t i = 0; i < n; i++) {
        double kind = legs[PK_INV_LEG * i];
        if (kind != 0.0 && kind != 1.0 && kind != 2.0) {
            PyErr_Format(PyExc_ValueError, "legs: leg %zd: kind must be 0, 1 or 2", i);
            return NULL;
        }
    }
    if (pk_rod_inverse_one(legs, n, (int)dims, x, q)) Py_RETURN_NONE;
    PyObject *out = PyList_New(n);
    if (!out) return NULL;
    for (Py_ssize_t i = 0; i < n; i++) {
        PyObject *v = PyFloat_FromDouble(q[i]);
        if (!v) {
            Py_DECREF(out);
            return NULL;
        }
        PyList_SET_ITEM(out, i, v);
    }
    return out;
}
