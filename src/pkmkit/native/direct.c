/* The full-pose direct model of one pose by Levenberg-Marquardt: the C twin of
 * pkmkit.machines.full_pose_direct_kernel.solve_row and the functions it calls, statement for
 * statement and in the same order of operations (the same statuses, iterations, stopping
 * tests and, with the same libm, the same bits). */
#include "kernels.h"

enum { OK = 0, NOT_CONVERGED = 3, INVALID_INPUT = 4, INCONSISTENT = 7 };
#define MAX_COORDINATE 1e9

/* (x, y, z, w) of a rotation vector (scipy's series below 1e-3 rad). */
static void rotvec_quaternion(double wx, double wy, double wz, double out[4]) {
    double angle = sqrt(wx * wx + wy * wy + wz * wz);
    double scale;
    if (angle <= 1e-3) {
        double a2 = angle * angle;
        scale = 0.5 - a2 / 48.0 + a2 * a2 / 3840.0;
    } else {
        scale = sin(0.5 * angle) / angle;
    }
    out[0] = wx * scale;
    out[1] = wy * scale;
    out[2] = wz * scale;
    out[3] = cos(0.5 * angle);
}

/* out[0:3] = the rotation vector of the unit quaternion (x, y, z, w), its angle in [0, pi]
 * (compose's tail; the Verne position solve's answer, position.c). */
void pk_quaternion_rotvec(double x, double y, double z, double w, double *out) {
    if (w < 0.0) {
        x = -x;
        y = -y;
        z = -z;
        w = -w;
    }
    double norm = sqrt(x * x + y * y + z * z);
    double angle = 2.0 * atan2(norm, w);
    double scale;
    if (angle <= 1e-3) {
        double a2 = angle * angle;
        scale = 2.0 + a2 / 12.0 + 7.0 * a2 * a2 / 2880.0;
    } else {
        scale = angle / sin(0.5 * angle);
    }
    out[0] = x * scale;
    out[1] = y * scale;
    out[2] = z * scale;
}

/* out[0:3] = rotation vector of exp(d) exp(p) (angle in [0, pi], as scipy). */
static void compose(double dx, double dy, double dz, double px, double py, double pz,
                    double *out) {
    double a[4], b[4];
    rotvec_quaternion(dx, dy, dz, a);
    rotvec_quaternion(px, py, pz, b);
    double ax = a[0], ay = a[1], az = a[2], aw = a[3];
    double bx = b[0], by = b[1], bz = b[2], bw = b[3];
    double x = aw * bx + ax * bw + ay * bz - az * by;
    double y = aw * by - ax * bz + ay * bw + az * bx;
    double z = aw * bz + ax * by - ay * bx + az * bw;
    double w = aw * bw - ax * bx - ay * by - az * bz;
    pk_quaternion_rotvec(x, y, z, w, out);
}

/* Base joints a_j(q) into base (m, 3) and rod lengths l_j(q) into length (m,) (_rods). */
static void rods(const double *q, const double *geom, ptrdiff_t m, double *base,
                 double *length) {
    for (ptrdiff_t j = 0; j < m; j++) {
        const double *gj = geom + 16 * j;
        double *bj = base + 3 * j;
        double qk = q[(ptrdiff_t)gj[14]];
        double kind = gj[13];
        length[j] = gj[12];
        if (kind == 0.0) { /* slide */
            for (int i = 0; i < 3; i++) bj[i] = gj[i] + qk * gj[6 + i];
        } else if (kind == 1.0) { /* strut */
            for (int i = 0; i < 3; i++) bj[i] = gj[i];
            length[j] += qk;
        } else { /* crank: Rodrigues about the axis through the pivot */
            double wx = gj[6], wy = gj[7], wz = gj[8];
            double rx = gj[0] - gj[9], ry = gj[1] - gj[10], rz = gj[2] - gj[11];
            double c = cos(qk), s = sin(qk);
            double along = (wx * rx + wy * ry + wz * rz) * (1.0 - c);
            bj[0] = gj[9] + rx * c + (wy * rz - wz * ry) * s + wx * along;
            bj[1] = gj[10] + ry * c + (wz * rx - wx * rz) * s + wy * along;
            bj[2] = gj[11] + rz * c + (wx * ry - wy * rx) * s + wz * along;
        }
    }
}

/* Residuals r (m,) and Jacobian jac (m, 6) at pose u (6,); the cost 1/2 |r|^2 (NaN or inf
 * when not finite, the Jacobian included) (_evaluate). */
static double evaluate(const double *u, const double *geom, ptrdiff_t m, const double *base,
                       const double *length, double *r, double *jac) {
    double rot[9];
    pk_rotation(u[3], u[4], u[5], rot);
    double cost = 0.0, check = 0.0;
    for (ptrdiff_t j = 0; j < m; j++) {
        const double *gj = geom + 16 * j;
        const double *bj = base + 3 * j;
        double *jj = jac + 6 * j;
        double bx = gj[3], by = gj[4], bz = gj[5];
        double sx = rot[0] * bx + rot[1] * by + rot[2] * bz;
        double sy = rot[3] * bx + rot[4] * by + rot[5] * bz;
        double sz = rot[6] * bx + rot[7] * by + rot[8] * bz;
        double dx = u[0] + sx - bj[0];
        double dy = u[1] + sy - bj[1];
        double dz = u[2] + sz - bj[2];
        double dist = sqrt(dx * dx + dy * dy + dz * dz);
        r[j] = dist - length[j];
        cost += r[j] * r[j];
        double ux = dx / dist, uy = dy / dist, uz = dz / dist;
        jj[0] = ux;
        jj[1] = uy;
        jj[2] = uz;
        jj[3] = sy * uz - sz * uy;
        jj[4] = sz * ux - sx * uz;
        jj[5] = sx * uy - sy * ux;
        check += jj[3] + jj[4] + jj[5] + ux + uy + uz;
    }
    return 0.5 * cost + 0.0 * check; /* NaN when any Jacobian entry is not finite */
}

/* step (6,) = -(J'J + lam (D + eps I))^-1 J'r by Cholesky; h (36,) scratch (_step). */
static void lm_step(const double *jac, const double *r, ptrdiff_t m, double lam, double *step,
                    double *h) {
    double biggest = 0.0;
    for (int i = 0; i < 6; i++) {
        double acc = 0.0;
        for (ptrdiff_t j = 0; j < m; j++) acc += jac[6 * j + i] * r[j];
        step[i] = acc;
        for (int k = 0; k <= i; k++) {
            acc = 0.0;
            for (ptrdiff_t j = 0; j < m; j++) acc += jac[6 * j + i] * jac[6 * j + k];
            h[6 * i + k] = acc;
        }
        biggest = pk_max(biggest, h[6 * i + i]);
    }
    double floor_ = 1e-9 * biggest + 1e-300;
    for (int i = 0; i < 6; i++) h[6 * i + i] += lam * (h[6 * i + i] + floor_);
    for (int i = 0; i < 6; i++) { /* lower Cholesky factor in place, reciprocal diagonal */
        for (int k = 0; k <= i; k++) {
            double acc = h[6 * i + k];
            for (int p = 0; p < k; p++) acc -= h[6 * i + p] * h[6 * k + p];
            if (i == k)
                h[6 * i + i] = acc > 0.0 ? sqrt(acc) : NAN;
            else
                h[6 * i + k] = acc * h[6 * k + k];
        }
        h[6 * i + i] = 1.0 / h[6 * i + i];
    }
    for (int i = 0; i < 6; i++) {
        double acc = -step[i];
        for (int p = 0; p < i; p++) acc -= h[6 * i + p] * step[p];
        step[i] = acc * h[6 * i + i];
    }
    for (int i = 5; i >= 0; i--) {
        double acc = step[i];
        for (int p = i + 1; p < 6; p++) acc -= h[6 * p + i] * step[p];
        step[i] = acc * h[6 * i + i];
    }
}

/* Whether every Jacobian column is orthogonal to r within the cosine gtol (_stationary). */
static int stationary(const double *jac, const double *r, ptrdiff_t m, double cost,
                      double gtol) {
    double largest = 0.0;
    for (int i = 0; i < 6; i++) {
        double grad = 0.0, col = 0.0;
        for (ptrdiff_t j = 0; j < m; j++) {
            grad += jac[6 * j + i] * r[j];
            col += jac[6 * j + i] * jac[6 * j + i];
        }
        double cosine = fabs(grad) / sqrt(col * (2.0 * cost));
        if (cosine == cosine && cosine > largest) largest = cosine;
    }
    return !(largest > gtol);
}

/* int(value) of a Numba option: NaN and negative values give no iteration. */
static long iteration_limit(double value) {
    if (!(value >= 0.0)) return 0;
    if (value >= 2147483647.0) return 2147483647L;
    return (long)value;
}

void pk_solve_row(const double *q, ptrdiff_t n, const double *u0, int has_guess,
                  const double *geom, ptrdiff_t m, const double *home, const double *opts,
                  double *out, pk_work *work) {
    double *base = work->base, *length = work->length, *r = work->r, *r_new = work->r_new;
    double *jac = work->jac, *jac_new = work->jac_new;
    double u[6] = {0.0}, u_new[6], step[6], h[36];
    out[6] = INVALID_INPUT;
    out[7] = 0.0;
    out[8] = NAN;
    int valid = 1;
    for (ptrdiff_t k = 0; k < n; k++)
        if (!(fabs(q[k]) <= MAX_COORDINATE)) valid = 0;
    if (has_guess) {
        for (int i = 0; i < 6; i++) u[i] = u0[i];
    } else if (valid) { /* first-order guess: home (+) J(home)(q - q_home) */
        for (int i = 0; i < 6; i++) {
            double acc = 0.0;
            for (ptrdiff_t k = 0; k < n; k++) acc += home[6 + n + i * n + k] * (q[k] - home[6 + k]);
            step[i] = acc;
        }
        for (int i = 0; i < 3; i++) u[i] = home[i] + step[i];
        compose(step[3], step[4], step[5], home[3], home[4], home[5], u + 3);
    }
    for (int i = 0; i < 6; i++) {
        out[i] = valid ? u[i] : NAN;
        if (!(u[i] == u[i]) || fabs(u[i]) == INFINITY) valid = 0;
    }
    if (!valid) return;
    long max_iter = iteration_limit(opts[0]);
    double xtol = opts[1], atol = opts[2], gtol = opts[3];
    double stall = opts[4], residual_tol = opts[5], lam = opts[6];
    rods(q, geom, m, base, length);
    double cost = evaluate(u, geom, m, base, length, r, jac);
    if (!(cost == cost && cost < INFINITY)) return;
    double checkpoint = cost;
    int stopped = 0;
    long iterations = 0;
    for (long it = 0; it < max_iter; it++) {
        if (cost <= 0.5 * atol * atol || stationary(jac, r, m, cost, gtol)) {
            stopped = 1;
            break;
        }
        lm_step(jac, r, m, lam, step, h);
        for (int i = 0; i < 3; i++) u_new[i] = u[i] + step[i];
        compose(step[3], step[4], step[5], u[3], u[4], u[5], u_new + 3);
        double cost_new = evaluate(u_new, geom, m, base, length, r_new, jac_new);
        int accept = cost_new == cost_new && cost_new < INFINITY
                     && cost_new <= cost * (1.0 + 1e-13);
        iterations += 1;
        if (accept) {
            for (int i = 0; i < 6; i++) u[i] = u_new[i];
            for (ptrdiff_t j = 0; j < m; j++) {
                r[j] = r_new[j];
                for (int i = 0; i < 6; i++) jac[6 * j + i] = jac_new[6 * j + i];
            }
            cost = cost_new;
            lam = pk_max(lam * 0.1, 1e-12);
        } else {
            lam *= 10.0;
        }
        double step_norm = 0.0, u_norm = 0.0;
        for (int i = 0; i < 6; i++) {
            step_norm += step[i] * step[i];
            u_norm += u[i] * u[i];
        }
        int done = (accept && sqrt(step_norm) <= xtol * (1.0 + sqrt(u_norm))) || lam > 1e12;
        if (iterations % 10 == 0) {
            if (cost > (1.0 - stall) * checkpoint && cost > 0.5 * residual_tol * residual_tol)
                done = 1;
            checkpoint = cost;
        }
        if (done) {
            stopped = 1;
            break;
        }
    }
    double largest = 0.0;
    for (ptrdiff_t j = 0; j < m; j++) largest = pk_max(largest, fabs(r[j]));
    for (int i = 0; i < 6; i++) out[i] = u[i];
    out[7] = (double)iterations;
    out[8] = largest;
    if (!stopped)
        out[6] = NOT_CONVERGED;
    else if (largest <= residual_tol)
        out[6] = OK;
    else
        out[6] = INCONSISTENT;
}

/* The helpers above for the position inverse (position.c): the same functions, not copies. */
void pk_compose(double dx, double dy, double dz, double px, double py, double pz,
                double *out) {
    compose(dx, dy, dz, px, py, pz, out);
}

void pk_rod_joints(const double *q, const double *geom, ptrdiff_t m, double *base,
                   double *length) {
    rods(q, geom, m, base, length);
}

void pk_lm_step(const double *jac, const double *r, ptrdiff_t m, double lam, double *step,
                double *h) {
    lm_step(jac, r, m, lam, step, h);
}

int pk_stationary(const double *jac, const double *r, ptrdiff_t m, double cost, double gtol) {
    return stationary(jac, r, m, cost, gtol);
}
