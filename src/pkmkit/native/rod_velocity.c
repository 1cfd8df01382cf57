/* pkmkit.native.kernels: the batched velocity summary of square translational rod-leg
 * machines, the C twins of pkmkit.machines.kernels.velocity3 and velocity2 (issue 22 §5: a
 * fresh `pkmkit jacobian orthoglide --input` then needs no Numba).
 *
 * The same statements in the same order as the Numba kernels (_leg_row with its zero terms
 * for planar machines, the cofactors, the closed-form singular values, _cos_third's polynomial
 * and Newton steps, Python's min/max), compiled without FMA contraction and without
 * fast-math: the same bits (tests/native/test_rod_velocity.py). The polynomial's coefficients
 * are read once from pkmkit.machines.cos_third.COEFFICIENTS (what the Numba kernel compiles
 * in), so both use the same numbers.
 *
 * Python face (the Numba kernels' arguments; C-contiguous arrays; runs without the GIL):
 * rod_velocity3|rod_velocity2(x (N, n), q (n, N), centre (n, n), axis (n, n), slide (n,) bool,
 * rod (n,), bound_limit, det_out (N,), sv_out (n, N), cond_out (N,), serial_out (N,),
 * hard_out (N,) bool). */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <string.h>

#include "kernels.h"

#define PK_COS_TERMS 13 /* cos_third.COEFFICIENTS.size (degree 12) */
#define PK_VBLOCK 256   /* kernels._VBLOCK */

static double cos_third_coef[PK_COS_TERMS];
static int cos_third_state = 0; /* 0 not read, 1 read */

/* Read cos_third.COEFFICIENTS (with the GIL); -1 with an exception set on failure. */
static int load_cos_third(void) {
    if (cos_third_state == 1) return 0;
    PyObject *mod = PyImport_ImportModule("pkmkit.machines.cos_third");
    if (!mod) return -1;
    PyObject *arr = PyObject_GetAttrString(mod, "COEFFICIENTS");
    Py_DECREF(mod);
    if (!arr) return -1;
    Py_buffer view;
    int rc = PyObject_GetBuffer(arr, &view, PyBUF_C_CONTIGUOUS | PyBUF_FORMAT);
    Py_DECREF(arr);
    if (rc < 0) return -1;
    const char *f = view.format ? view.format : "B";
    if (f[0] == '@' || f[0] == '=' || f[0] == '<') f++;
    if (!(f[0] == 'd' && !f[1]) || view.ndim != 1 || view.shape[0] != PK_COS_TERMS) {
        PyBuffer_Release(&view);
        PyErr_SetString(PyExc_ValueError, "cos_third.COEFFICIENTS: 13 float64 expected");
        return -1;
    }
    memcpy(cos_third_coef, view.buf, sizeof(cos_third_coef));
    PyBuffer_Release(&view);
    cos_third_state = 1;
    return 0;
}

/* kernels._leg_row: row p − c_i(q) of A and entry i of diag B. */
static inline void leg_row(double x0, double x1, double x2, double q, const double *g,
                           double *a0, double *a1, double *a2, double *b) {
    double c0 = g[0], c1 = g[1], c2 = g[2], u0 = g[3], u1 = g[4], u2 = g[5];
    double slide = g[6], rod = g[7];
    *a0 = x0 - (c0 + q * u0);
    *a1 = x1 - (c1 + q * u1);
    *a2 = x2 - (c2 + q * u2);
    *b = slide * (*a0 * u0 + *a1 * u1 + *a2 * u2) + (1.0 - slide) * (rod + q);
}

/* kernels._cos_third */
static inline double cos_third(double h) {
    double s = sqrt(0.5 * (1.0 + h));
    double c = 0.0;
    for (int k = PK_COS_TERMS - 1; k >= 0; k--) c = c * s + cos_third_coef[k];
    for (int it = 0; it < 2; it++) {
        double slope = 12.0 * c * c - 3.0;
        double step = ((4.0 * c * c - 3.0) * c - h) / slope;
        c = slope > 1e-300 ? c - step : c;
    }
    return c;
}

/* kernels._legs: (n, 8) rows c0 c1 c2 u0 u1 u2 slide rod, z = 0 for planar machines. */
static void legs(const double *centre, const double *axis, const unsigned char *slide,
                 const double *rod, int n, double *g) {
    memset(g, 0, sizeof(double) * 8 * (size_t)n);
    for (int i = 0; i < n; i++) {
        for (int d = 0; d < n; d++) {
            g[8 * i + d] = centre[n * i + d];
            g[8 * i + 3 + d] = axis[n * i + d];
        }
        g[8 * i + 6] = slide[i] ? 1.0 : 0.0;
        g[8 * i + 7] = rod[i];
    }
}

static void velocity3(const double *x, ptrdiff_t size, const double *q, const double *g,
                      double bound_limit, double *det_out, double *sv_out, double *cond_out,
                      double *serial_out, unsigned char *hard_out) {
    double inv_bound = 1.0 / (1.5 * sqrt(3.0));
    double mean_b[PK_VBLOCK], spread_b[PK_VBLOCK], half_b[PK_VBLOCK], cos_b[PK_VBLOCK];
    double detj_b[PK_VBLOCK], e2_b[PK_VBLOCK], bound_b[PK_VBLOCK], check_b[PK_VBLOCK];
    double det_b[PK_VBLOCK], serial_b[PK_VBLOCK];
    for (ptrdiff_t start = 0; start < size; start += PK_VBLOCK) {
        ptrdiff_t m = size - start < PK_VBLOCK ? size - start : PK_VBLOCK;
        const double *q0 = q + start, *q1 = q + size + start, *q2 = q + 2 * size + start;
        for (ptrdiff_t t = 0; t < m; t++) {
            const double *xr = x + 3 * (start + t);
            double x0 = xr[0], x1 = xr[1], x2 = xr[2];
            double a00, a01, a02, b0, a10, a11, a12, b1, a20, a21, a22, b2;
            leg_row(x0, x1, x2, q0[t], g, &a00, &a01, &a02, &b0);
            leg_row(x0, x1, x2, q1[t], g + 8, &a10, &a11, &a12, &b1);
            leg_row(x0, x1, x2, q2[t], g + 16, &a20, &a21, &a22, &b2);
            check_b[t] = (a00 + a01 + a02 + a10 + a11 + a12 + a20 + a21 + a22
                          + b0 + b1 + b2);
            double c00 = a11 * a22 - a12 * a21;
            double c01 = a12 * a20 - a10 * a22;
            double c02 = a10 * a21 - a11 * a20;
            double c10 = a21 * a02 - a22 * a01;
            double c11 = a22 * a00 - a20 * a02;
            double c12 = a20 * a01 - a21 * a00;
            double c20 = a01 * a12 - a02 * a11;
            double c21 = a02 * a10 - a00 * a12;
            double c22 = a00 * a11 - a01 * a10;
            double det = a00 * c00 + a01 * c01 + a02 * c02;
            det_b[t] = det;
            double l0 = sqrt(a00 * a00 + a01 * a01 + a02 * a02);
            double l1 = sqrt(a10 * a10 + a11 * a11 + a12 * a12);
            double l2 = sqrt(a20 * a20 + a21 * a21 + a22 * a22);
            serial_b[t] = pk_min(pk_min(fabs(b0) / l0, fabs(b1) / l1), fabs(b2) / l2);
            bound_b[t] = fabs(det) / (l0 * l1 * l2) * inv_bound;
            double s0 = b0 / det, s1 = b1 / det, s2 = b2 / det;
            double j00 = c00 * s0, j01 = c10 * s1, j02 = c20 * s2;
            double j10 = c01 * s0, j11 = c11 * s1, j12 = c21 * s2;
            double j20 = c02 * s0, j21 = c12 * s1, j22 = c22 * s2;
            double g00 = j00 * j00 + j10 * j10 + j20 * j20;
            double g11 = j01 * j01 + j11 * j11 + j21 * j21;
            double g22 = j02 * j02 + j12 * j12 + j22 * j22;
            double g01 = j00 * j01 + j10 * j11 + j20 * j21;
            double g02 = j00 * j02 + j10 * j12 + j20 * j22;
            double g12 = j01 * j02 + j11 * j12 + j21 * j22;
            double mean = (g00 + g11 + g22) / 3.0;
            double off = g01 * g01 + g02 * g02 + g12 * g12;
            double d0 = g00 - mean, d1 = g11 - mean, d2 = g22 - mean;
            double spread = sqrt((d0 * d0 + d1 * d1 + d2 * d2 + 2.0 * off) / 6.0);
            double scale = spread > 0.0 ? 1.0 / spread : 0.0;
            double h00 = d0 * scale, h11 = d1 * scale, h22 = d2 * scale;
            double h01 = g01 * scale, h02 = g02 * scale, h12 = g12 * scale;
            double half = 0.5 * (h00 * (h11 * h22 - h12 * h12) - h01 * (h01 * h22 - h12 * h02)
                                 + h02 * (h01 * h12 - h11 * h02));
            half_b[t] = pk_min(pk_max(half, -1.0), 1.0);
            mean_b[t] = mean;
            spread_b[t] = spread;
            double m00 = j11 * j22 - j12 * j21;
            double m01 = j12 * j20 - j10 * j22;
            double m02 = j10 * j21 - j11 * j20;
            double m10 = j21 * j02 - j22 * j01;
            double m11 = j22 * j00 - j20 * j02;
            double m12 = j20 * j01 - j21 * j00;
            double m20 = j01 * j12 - j02 * j11;
            double m21 = j02 * j10 - j00 * j12;
            double m22 = j00 * j11 - j01 * j10;
            detj_b[t] = fabs(j00 * m00 + j01 * m01 + j02 * m02);
            e2_b[t] = (m00 * m00 + m01 * m01 + m02 * m02 + m10 * m10 + m11 * m11 + m12 * m12
                       + m20 * m20 + m21 * m21 + m22 * m22);
        }
        for (ptrdiff_t t = 0; t < m; t++) {
            double h = half_b[t];
            h = h - h == 0.0 ? h : 0.0;
            cos_b[t] = cos_third(h);
        }
        for (ptrdiff_t t = 0; t < m; t++) {
            ptrdiff_t row = start + t;
            double mean = mean_b[t], spread = spread_b[t];
            double lam1 = mean + 2.0 * spread * cos_b[t];
            double sig1 = sqrt(pk_max(lam1, 0.0));
            double pair = sig1 > 0.0 ? detj_b[t] / sig1 : 0.0;
            double rest = lam1 > 0.0 ? (e2_b[t] - pair * pair) / lam1 : 0.0;
            double sig2 = 0.5 * (sqrt(pk_max(rest + 2.0 * pair, 0.0))
                                 + sqrt(pk_max(rest - 2.0 * pair, 0.0)));
            double sig3 = sig2 > 0.0 ? pair / sig2 : 0.0;
            sig2 = pk_min(sig2, sig1);
            sig3 = pk_min(sig3, sig2);
            int coincide = (spread > 0.0) & ((fabs(half_b[t]) > 1.0 - 1e-6)
                                             | (rest - 2.0 * pair < 1e-6 * rest));
            double total = sig1 + sig2 + sig3;
            double check = check_b[t];
            int finite_in = check - check == 0.0;
            int hard = finite_in & ((!(bound_b[t] >= bound_limit)) | coincide
                                    | (!(total - total == 0.0)));
            hard_out[row] = (unsigned char)hard;
            sv_out[row] = finite_in ? sig1 : NAN;
            sv_out[size + row] = finite_in ? sig2 : NAN;
            sv_out[2 * size + row] = finite_in ? sig3 : NAN;
            double cond = sig3 != 0.0 ? sig1 / sig3 : INFINITY;
            cond_out[row] = finite_in ? cond : NAN;
            det_out[row] = finite_in ? det_b[t] : NAN;
            serial_out[row] = finite_in ? serial_b[t] : NAN;
        }
    }
}

static void velocity2(const double *x, ptrdiff_t size, const double *q, const double *g,
                      double bound_limit, double *det_out, double *sv_out, double *cond_out,
                      double *serial_out, unsigned char *hard_out) {
    const double *g0 = g, *g1 = g + 8;
    for (ptrdiff_t k = 0; k < size; k++) {
        double x0 = x[2 * k], x1 = x[2 * k + 1];
        double a00, a01, a02, b0, a10, a11, a12, b1;
        /* _leg_row(x0, x1, 0.0, q, c0, c1, 0.0, u0, u1, 0.0, slide, rod) */
        double l0g[8] = {g0[0], g0[1], 0.0, g0[3], g0[4], 0.0, g0[6], g0[7]};
        double l1g[8] = {g1[0], g1[1], 0.0, g1[3], g1[4], 0.0, g1[6], g1[7]};
        leg_row(x0, x1, 0.0, q[k], l0g, &a00, &a01, &a02, &b0);
        leg_row(x0, x1, 0.0, q[size + k], l1g, &a10, &a11, &a12, &b1);
        (void)a02;
        (void)a12;
        double check = a00 + a01 + a10 + a11 + b0 + b1;
        hard_out[k] = 0;
        if (check - check != 0.0) {
            det_out[k] = NAN;
            sv_out[k] = sv_out[size + k] = NAN;
            cond_out[k] = NAN;
            serial_out[k] = NAN;
            continue;
        }
        double det = a00 * a11 - a01 * a10;
        det_out[k] = det;
        double l0 = sqrt(a00 * a00 + a01 * a01);
        double l1 = sqrt(a10 * a10 + a11 * a11);
        serial_out[k] = pk_min(fabs(b0) / l0, fabs(b1) / l1);
        double bound = fabs(det) / (l0 * l1) * 0.5;
        if (!(bound >= bound_limit)) {
            hard_out[k] = 1;
            continue;
        }
        double s0 = b0 / det, s1 = b1 / det;
        double ja = a11 * s0, jb = -a01 * s1;
        double jc = -a10 * s0, jd = a00 * s1;
        double sig1 = 0.5 * (hypot(ja + jd, jc - jb) + hypot(ja - jd, jb + jc));
        double sig2 = sig1 > 0.0 ? fabs(ja * jd - jb * jc) / sig1 : 0.0;
        double total = sig1 + sig2;
        if (total - total != 0.0) {
            hard_out[k] = 1;
            continue;
        }
        sv_out[k] = sig1;
        sv_out[size + k] = sig2;
        cond_out[k] = sig2 != 0.0 ? sig1 / sig2 : INFINITY;
    }
}

/* ------------------------------------------------------------------ Python face */

static PyObject *rod_velocity(PyObject *const *args, Py_ssize_t nargs, int n,
                              const char *fname) {
    if (nargs != 12) {
        PyErr_Format(PyExc_TypeError, "%s() takes 12 positional arguments (%zd given)", fname,
                     nargs);
        return NULL;
    }
    if (load_cos_third() < 0) return NULL;
    Py_buffer v[11];
    int held = 0;
    PyObject *result = NULL;
    Py_ssize_t x_shape[2] = {-1, n};
    if (pk_take(args[0], &v[held], "x", 'd', 0, 2, x_shape) < 0) goto done;
    held++;
    Py_ssize_t size = v[0].shape[0];
    struct { const char *name; char type; int w, ndim; Py_ssize_t d0, d1; } spec[10] = {
        {"q", 'd', 0, 2, n, size}, {"centre", 'd', 0, 2, n, n}, {"axis", 'd', 0, 2, n, n},
        {"slide", '?', 0, 1, n, -1}, {"rod", 'd', 0, 1, n, -1},
        {"det_out", 'd', 1, 1, size, -1}, {"sv_out", 'd', 1, 2, n, size},
        {"cond_out", 'd', 1, 1, size, -1}, {"serial_out", 'd', 1, 1, size, -1},
        {"hard_out", '?', 1, 1, size, -1}};
    for (int i = 0; i < 10; i++) {
        PyObject *obj = args[i < 5 ? i + 1 : i + 2]; /* args[6] is bound_limit */
        Py_ssize_t shape[2] = {spec[i].d0, spec[i].d1};
        if (pk_take(obj, &v[held], spec[i].name, spec[i].type, spec[i].w, spec[i].ndim,
                    shape) < 0)
            goto done;
        held++;
    }
    double limit = PyFloat_AsDouble(args[6]);
    if (limit == -1.0 && PyErr_Occurred()) goto done;
    double g[24];
    legs(v[2].buf, v[3].buf, v[4].buf, v[5].buf, n, g);
    Py_BEGIN_ALLOW_THREADS
    if (n == 3)
        velocity3(v[0].buf, size, v[1].buf, g, limit, v[6].buf, v[7].buf, v[8].buf, v[9].buf,
                  v[10].buf);
    else
        velocity2(v[0].buf, size, v[1].buf, g, limit, v[6].buf, v[7].buf, v[8].buf, v[9].buf,
                  v[10].buf);
    Py_END_ALLOW_THREADS
    result = Py_NewRef(Py_None);
done:
    for (int i = 0; i < held; i++) PyBuffer_Release(&v[i]);
    return result;
}

const char pk_rod_velocity3_doc[] =
    "rod_velocity3(x, q, centre, axis, slide, rod, bound_limit, det_out, sv_out, cond_out,\n"
    "              serial_out, hard_out)\n\n"
    "The C twin of pkmkit.machines.kernels.velocity3 (square spatial machines): x (N, 3),\n"
    "q (3, N), centre and axis (3, 3), slide (3,) bool, rod (3,); outputs det_out (N,),\n"
    "sv_out (3, N), cond_out, serial_out (N,), hard_out (N,) bool. C-contiguous arrays; runs\n"
    "without the GIL.";

const char pk_rod_velocity2_doc[] =
    "rod_velocity2(x, q, centre, axis, slide, rod, bound_limit, det_out, sv_out, cond_out,\n"
    "              serial_out, hard_out)\n\n"
    "The C twin of pkmkit.machines.kernels.velocity2 (square planar machines): as\n"
    "rod_velocity3 with n = 2.";

PyObject *pk_py_rod_velocity3(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    return rod_velocity(args, nargs, 3, "rod_velocity3");
}

PyObject *pk_py_rod_velocity2(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    return rod_velocity(args, nargs, 2, "rod_velocity2");
}
