/* The position inverse of a full-pose machine commanded by its position alone (three
 * actuators, the rods setting the orientation: the Verne-type module) by Levenberg-Marquardt:
 * the C twin of pkmkit.machines.full_pose_position_kernel.solve_rows and the functions it
 * calls, statement for statement and in the same order of operations (the same statuses,
 * iterations, stopping tests and, with the same libm, the same bits). The helpers shared with
 * the direct solve (compose, rods, the damped step, the stationarity test) are direct.c's.
 * With opts[9] = 1 (opts (10,): every actuator carries two slide rods, their branches in
 * geom[:, 15]) a row from the first-order start runs Newton's method on the rotation alone
 * (solve_paired) instead; the rows it does not answer are left INVALID_INPUT (NaN) for the
 * caller's Levenberg-Marquardt pass (out[:, 9]: 1 where it answered). */
#include "kernels.h"

enum { OK = 0, NOT_CONVERGED = 3, INVALID_INPUT = 4, INCONSISTENT = 7 };

/* Residuals r (m,) and Jacobian jac (m, 6) at unknowns u (6,) = (q, rotation vector) for
 * position p (3,); the cost 1/2 |r|^2 (NaN or inf when not finite, the Jacobian included)
 * (_evaluate). base, length: scratch for the base joints and rod lengths. */
static double evaluate(const double *u, const double *p, const double *geom, ptrdiff_t m,
                       double *base, double *length, double *r, double *jac) {
    pk_rod_joints(u, geom, m, base, length);
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
        double dx = p[0] + sx - bj[0];
        double dy = p[1] + sy - bj[1];
        double dz = p[2] + sz - bj[2];
        double dist = sqrt(dx * dx + dy * dy + dz * dz);
        r[j] = dist - length[j];
        cost += r[j] * r[j];
        double ux = dx / dist, uy = dy / dist, uz = dz / dist;
        double kind = gj[13], along;
        if (kind == 0.0) { /* slide: da/dq = its axis */
            along = ux * gj[6] + uy * gj[7] + uz * gj[8];
        } else if (kind == 1.0) { /* strut: dl/dq = 1 */
            along = 1.0;
        } else { /* crank: da/dq = w x (a - pivot) */
            double wx = gj[6], wy = gj[7], wz = gj[8];
            double ax = bj[0] - gj[9], ay = bj[1] - gj[10], az = bj[2] - gj[11];
            along = (ux * (wy * az - wz * ay) + uy * (wz * ax - wx * az)
                     + uz * (wx * ay - wy * ax));
        }
        for (int k = 0; k < 3; k++) jj[k] = 0.0;
        jj[(ptrdiff_t)gj[14]] = -along;
        jj[3] = sy * uz - sz * uy;
        jj[4] = sz * ux - sx * uz;
        jj[5] = sx * uy - sy * ux;
        check += jj[3] + jj[4] + jj[5] + along;
    }
    return 0.5 * cost + 0.0 * check; /* NaN when any Jacobian entry is not finite */
}

/* int(value) of a Numba option, as x86-64 converts it: a value that is not finite or beyond
 * the int64 range gives INT64_MIN. */
static int64_t numba_int(double value) {
    if (!(value > -9223372036854775808.0 && value < 9223372036854775808.0)) return INT64_MIN;
    return (int64_t)value;
}

/* max |r_j| (_largest). */
static double largest_of(const double *r, ptrdiff_t m) {
    double largest = 0.0;
    for (ptrdiff_t j = 0; j < m; j++) largest = pk_max(largest, fabs(r[j]));
    return largest;
}

/* One position p (3,) from u0 (6,): out (9,) = u (6), status, iterations, largest |residual|
 * (NaN when the start is invalid) (solve_row). */
static void solve_row(const double *p, const double *u0, const double *geom, ptrdiff_t m,
                      const double *opts, double *out, pk_work *work) {
    double *base = work->base, *length = work->length, *r = work->r, *r_new = work->r_new;
    double *jac = work->jac, *jac_new = work->jac_new;
    double u[6], u_new[6], step[6], h[36];
    /* _start */
    out[6] = INVALID_INPUT;
    out[7] = 0.0;
    out[8] = NAN;
    int valid = 1;
    for (int i = 0; i < 6; i++) {
        u[i] = u0[i];
        out[i] = u0[i];
        if (!(u0[i] == u0[i]) || fabs(u0[i]) == INFINITY) valid = 0;
    }
    if (!valid) return;
    int64_t max_iter = numba_int(opts[0]);
    double xtol = opts[1], atol = opts[2], gtol = opts[3];
    double stall = opts[4], residual_tol = opts[5], lam = opts[6];
    int64_t crawl_iter = numba_int(opts[7]);
    double crawl_residual = opts[8];
    double cost = evaluate(u, p, geom, m, base, length, r, jac);
    if (!(cost == cost && cost < INFINITY)) return;
    double checkpoint = cost;
    int stopped = 0;
    int64_t iterations = 0;
    for (int64_t it = 0; it < max_iter; it++) {
        if (cost <= 0.5 * atol * atol || pk_stationary(jac, r, m, cost, gtol)) {
            stopped = 1;
            break;
        }
        pk_lm_step(jac, r, m, lam, step, h);
        for (int i = 0; i < 3; i++) u_new[i] = u[i] + step[i];
        pk_compose(step[3], step[4], step[5], u[3], u[4], u[5], u_new + 3);
        double cost_new = evaluate(u_new, p, geom, m, base, length, r_new, jac_new);
        int accept = cost_new == cost_new && cost_new < INFINITY
                     && cost_new <= cost * (1.0 + 1e-13);
        iterations += 1;
        if (accept) { /* _take */
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
        int done = 0;
        if (accept) { /* _short */
            double step_norm = 0.0, u_norm = 0.0;
            for (int i = 0; i < 6; i++) {
                step_norm += step[i] * step[i];
                u_norm += u[i] * u[i];
            }
            done = sqrt(step_norm) <= xtol * (1.0 + sqrt(u_norm));
        }
        done = done || lam > 1e12;
        if (iterations % 10 == 0) {
            if (cost > (1.0 - stall) * checkpoint && cost > 0.5 * residual_tol * residual_tol)
                done = 1;
            checkpoint = cost;
        }
        if (done) {
            stopped = 1;
            break;
        }
        if (iterations == crawl_iter && largest_of(r, m) > crawl_residual)
            break; /* far from any solution: NOT_CONVERGED now */
    }
    /* _finish */
    double largest = largest_of(r, m);
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

/* The engine's default start u0 (6,) for position p (3,) (first_order): q = q_home +
 * J_p^-1 (p - p_home), then the rotation of the twist J(home)(q - q_home) composed with
 * home's. */
static void first_order(const double *p, const double *home, const double *jt_inv,
                        double *u0) {
    const int n = 3;
    double dq[3], w[3];
    for (int i = 0; i < 3; i++) {
        double acc = 0.0;
        for (int k = 0; k < 3; k++) acc += jt_inv[3 * i + k] * (p[k] - home[k]);
        dq[i] = acc;
    }
    for (int i = 0; i < 3; i++) u0[i] = home[6 + i] + dq[i];
    for (int i = 0; i < 3; i++) {
        double acc = 0.0;
        for (int k = 0; k < n; k++) acc += (u0[k] - home[6 + k]) * home[6 + n + (3 + i) * n + k];
        w[i] = acc;
    }
    pk_compose(w[0], w[1], w[2], home[3], home[4], home[5], u0 + 3);
}

/* The reduced closure of a machine whose every actuator carries two slide rods at rotation
 * rot (3, 3) row-major for position p (3,): each rod's coordinate on its branch (geom[:, 15])
 * into qrod (m,), the disagreements f (3,) (first rod - second) and their derivatives jac (3, 3)
 * in the rotation; 0 when a rod cannot close or a value is not finite (_paired). */
static int paired(const double *p, const double *rot, const double *geom, ptrdiff_t m,
                  double *qrod, double *f, double *jac) {
    for (int k = 0; k < 3; k++) {
        f[k] = 0.0;
        for (int i = 0; i < 3; i++) jac[3 * k + i] = 0.0;
    }
    double seen[3] = {0.0, 0.0, 0.0};
    double check = 0.0;
    for (ptrdiff_t j = 0; j < m; j++) {
        const double *gj = geom + 16 * j;
        double bx = gj[3], by = gj[4], bz = gj[5];
        double ex = gj[6], ey = gj[7], ez = gj[8];
        double sx = rot[0] * bx + rot[1] * by + rot[2] * bz;
        double sy = rot[3] * bx + rot[4] * by + rot[5] * bz;
        double sz = rot[6] * bx + rot[7] * by + rot[8] * bz;
        double vx = p[0] + sx - gj[0];
        double vy = p[1] + sy - gj[1];
        double vz = p[2] + sz - gj[2];
        double along = ex * vx + ey * vy + ez * vz;
        double radicand = gj[12] * gj[12] - (vx * vx + vy * vy + vz * vz) + along * along;
        if (!(radicand > 0.0)) return 0;
        double q = along + gj[15] * sqrt(radicand);
        qrod[j] = q;
        double dx = vx - q * ex, dy = vy - q * ey, dz = vz - q * ez;
        double cosine = along - q;
        ptrdiff_t k = (ptrdiff_t)gj[14];
        double sign = seen[k] == 0.0 ? 1.0 : -1.0;
        seen[k] = 1.0;
        double *jk = jac + 3 * k;
        double scale = sign / cosine; /* one division per rod */
        f[k] += sign * q;
        jk[0] += scale * (sy * dz - sz * dy);
        jk[1] += scale * (sz * dx - sx * dz);
        jk[2] += scale * (sx * dy - sy * dx);
        check += jk[0] + jk[1] + jk[2] + q;
    }
    return check == check && fabs(check) < INFINITY;
}

/* step (3,) = -jac^-1 f by Cramer's rule; 0 when jac is singular or not finite
 * (_newton_step). */
static int newton_step(const double *f, const double *jac, double *step) {
    double a = jac[0], b = jac[1], c = jac[2];
    double d = jac[3], e = jac[4], g = jac[5];
    double h = jac[6], i = jac[7], k = jac[8];
    double c0 = e * k - g * i, c1 = g * h - d * k, c2 = d * i - e * h;
    double det = a * c0 + b * c1 + c * c2;
    if (!(fabs(det) > 1e-300 && fabs(det) < INFINITY)) return 0;
    step[0] = -(f[0] * c0 + f[1] * (c * i - b * k) + f[2] * (b * g - c * e)) / det;
    step[1] = -(f[0] * c1 + f[1] * (a * k - c * h) + f[2] * (c * d - a * g)) / det;
    step[2] = -(f[0] * c2 + f[1] * (b * h - a * i) + f[2] * (a * e - b * d)) / det;
    return 1;
}

enum { PAIRED_ITER = 8 };
#define PAIRED_STEP 1e-9
#define PAIRED_TOL 1e-12
#define PAIRED_SERIES 0.05

/* qt (4,) = (x, y, z, w), the unit quaternion of rotation vector (dx, dy, dz): the half
 * angle's cosine and sine / angle by their Taylor series up to a half angle of PAIRED_SERIES
 * (the first term left out below 1e-20 of the sum), the C library's above (_step_quaternion). */
static void step_quaternion(double dx, double dy, double dz, double *qt) {
    double angle = sqrt(dx * dx + dy * dy + dz * dz);
    double h = 0.5 * angle, c, s;
    if (h <= PAIRED_SERIES) {
        double h2 = h * h;
        c = 1.0 - h2 * (0.5 - h2 * (1.0 / 24.0 - h2 * (1.0 / 720.0 - h2 / 40320.0)));
        s = 0.5 * (1.0 - h2 * (1.0 / 6.0 - h2 * (1.0 / 120.0 - h2 * (1.0 / 5040.0
                                                                       - h2 / 362880.0))));
    } else {
        c = cos(h);
        s = sin(h) / angle;
    }
    qt[0] = dx * s;
    qt[1] = dy * s;
    qt[2] = dz * s;
    qt[3] = c;
}

/* qt <- a qt (Hamilton product, as compose's), normalised (_turn). */
static void turn(const double *a, double *qt) {
    double ax = a[0], ay = a[1], az = a[2], aw = a[3];
    double bx = qt[0], by = qt[1], bz = qt[2], bw = qt[3];
    double x = aw * bx + ax * bw + ay * bz - az * by;
    double y = aw * by - ax * bz + ay * bw + az * bx;
    double z = aw * bz + ax * by - ay * bx + az * bw;
    double w = aw * bw - ax * bx - ay * by - az * bz;
    double norm = sqrt(x * x + y * y + z * z + w * w);
    qt[0] = x / norm;
    qt[1] = y / norm;
    qt[2] = z / norm;
    qt[3] = w / norm;
}

/* rot (3, 3) row-major of the unit quaternion qt (_quaternion_matrix). */
static void quaternion_matrix(const double *qt, double *rot) {
    double x = qt[0], y = qt[1], z = qt[2], w = qt[3];
    rot[0] = 1.0 - 2.0 * (y * y + z * z);
    rot[1] = 2.0 * (x * y - z * w);
    rot[2] = 2.0 * (x * z + y * w);
    rot[3] = 2.0 * (x * y + z * w);
    rot[4] = 1.0 - 2.0 * (x * x + z * z);
    rot[5] = 2.0 * (y * z - x * w);
    rot[6] = 2.0 * (x * z - y * w);
    rot[7] = 2.0 * (y * z + x * w);
    rot[8] = 1.0 - 2.0 * (x * x + y * y);
}

/* The first-order start's rotation as a unit quaternion qt (4,) for position p (3,): the
 * twist J(home)(q - q_home) of first_order's q turned onto home's rotation
 * (_first_order_quaternion). */
static void first_order_quaternion(const double *p, const double *home, const double *jt_inv,
                                   double *qt) {
    const int n = 3;
    double dq[3], w[3], a[4];
    for (int i = 0; i < 3; i++) {
        double acc = 0.0;
        for (int k = 0; k < 3; k++) acc += jt_inv[3 * i + k] * (p[k] - home[k]);
        dq[i] = acc;
    }
    for (int i = 0; i < 3; i++) {
        double acc = 0.0;
        for (int k = 0; k < n; k++) acc += dq[k] * home[6 + n + (3 + i) * n + k];
        w[i] = acc;
    }
    step_quaternion(home[3], home[4], home[5], qt);
    step_quaternion(w[0], w[1], w[2], a);
    turn(a, qt);
}

/* The start table (opts[10:], position_start.pack): a header of START_HEADER values — cells
 * per side, the degree, the cell's side, the corner of the first cell in the plane's
 * coordinates, the plane's origin (3) and axes (3 + 3) — then per cell (row-major) and per
 * term a^i b^j (i ascending, then j) the three vector components of the solution's unit
 * quaternion; a cell with a node the solve left is NaN. */
enum { START_HEADER = 13, START_MAX_DEGREE = 15 };

ptrdiff_t pk_start_table_size(const double *table, ptrdiff_t n) {
    if (n < START_HEADER) return -1;
    double cells = table[0], degree = table[1];
    if (!(cells >= 1.0 && cells <= 1024.0 && cells == floor(cells))
        || !(degree >= 0.0 && degree <= START_MAX_DEGREE && degree == floor(degree))
        || !(table[2] > 0.0 && table[2] < INFINITY))
        return -1;
    ptrdiff_t c = (ptrdiff_t)cells, d = (ptrdiff_t)degree;
    ptrdiff_t size = START_HEADER + c * c * ((d + 1) * (d + 2) / 2) * 3;
    return size == n ? n : -1;
}

/* The start qt (4,) of position p (3,) from the start table: 1 when p's projection on the
 * table's plane falls in a cell whose fit is finite and gives a vector part shorter than 1
 * (then w = sqrt(1 - |v|^2)), else 0 (_table_start). */
static int table_start(const double *p, const double *table, double *qt) {
    double cells = table[0], side = table[2], corner = table[3];
    ptrdiff_t c = (ptrdiff_t)cells, d = (ptrdiff_t)table[1];
    double rx = p[0] - table[4], ry = p[1] - table[5], rz = p[2] - table[6];
    double tu = (rx * table[7] + ry * table[8] + rz * table[9] - corner) / side;
    double tv = (rx * table[10] + ry * table[11] + rz * table[12] - corner) / side;
    if (!(tu >= 0.0 && tu < cells && tv >= 0.0 && tv < cells)) return 0;
    ptrdiff_t iu = (ptrdiff_t)tu, iv = (ptrdiff_t)tv;
    double a = tu - (double)iu - 0.5, b = tv - (double)iv - 0.5;
    ptrdiff_t terms = (d + 1) * (d + 2) / 2;
    const double *coef = table + START_HEADER + (iu * c + iv) * terms * 3;
    double v[3] = {0.0, 0.0, 0.0};
    for (ptrdiff_t i = d; i >= 0; i--) {
        ptrdiff_t at = i * (d + 1) - i * (i - 1) / 2; /* the first term of a^i */
        double inner[3] = {0.0, 0.0, 0.0};
        for (ptrdiff_t j = d - i; j >= 0; j--) {
            const double *cj = coef + 3 * (at + j);
            for (int k = 0; k < 3; k++) inner[k] = inner[k] * b + cj[k];
        }
        for (int k = 0; k < 3; k++) v[k] = v[k] * a + inner[k];
    }
    double rest = 1.0 - (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(rest > 0.0)) return 0; /* NaN too: a cell the table left */
    qt[0] = v[0];
    qt[1] = v[1];
    qt[2] = v[2];
    qt[3] = sqrt(rest);
    return 1;
}

/* Newton's method on the rotation alone (a unit quaternion, left increments) from qt (4,):
 * 1 and out (9,) = u (q, rotation vector), OK, steps, largest rod residual when it converges;
 * 0 (out untouched) otherwise (solve_paired). */
static int solve_paired(const double *p, double *qt, const double *geom, ptrdiff_t m,
                        double *out, double *qrod) {
    double step[3], f[3], jac[9], a[4], rot[9];
    int64_t steps = 0;
    int converged = 0;
    while (steps < PAIRED_ITER) {
        quaternion_matrix(qt, rot);
        if (!paired(p, rot, geom, m, qrod, f, jac) || !newton_step(f, jac, step)) return 0;
        step_quaternion(step[0], step[1], step[2], a);
        turn(a, qt);
        steps += 1;
        if (sqrt(step[0] * step[0] + step[1] * step[1] + step[2] * step[2]) <= PAIRED_STEP) {
            converged = 1;
            break;
        }
    }
    if (!converged) return 0;
    quaternion_matrix(qt, rot);
    if (!paired(p, rot, geom, m, qrod, f, jac)) return 0;
    double q[3], seen[3] = {0.0, 0.0, 0.0};
    for (ptrdiff_t j = 0; j < m; j++) {
        ptrdiff_t k = (ptrdiff_t)geom[16 * j + 14];
        if (seen[k] == 0.0) {
            q[k] = qrod[j];
            seen[k] = 1.0;
        } else {
            q[k] = q[k] + 0.5 * (qrod[j] - q[k]); /* first + mean offset (combine) */
        }
    }
    double largest = 0.0;
    for (ptrdiff_t j = 0; j < m; j++) {
        const double *gj = geom + 16 * j;
        double qk = q[(ptrdiff_t)gj[14]];
        double dx = p[0] - gj[0] - qk * gj[6];
        double dy = p[1] - gj[1] - qk * gj[7];
        double dz = p[2] - gj[2] - qk * gj[8];
        double bx = gj[3], by = gj[4], bz = gj[5];
        dx += rot[0] * bx + rot[1] * by + rot[2] * bz;
        dy += rot[3] * bx + rot[4] * by + rot[5] * bz;
        dz += rot[6] * bx + rot[7] * by + rot[8] * bz;
        largest = pk_max(largest, fabs(sqrt(dx * dx + dy * dy + dz * dz) - gj[12]));
    }
    if (!(largest <= PAIRED_TOL)) return 0;
    for (int k = 0; k < 3; k++) out[k] = q[k];
    pk_quaternion_rotvec(qt[0], qt[1], qt[2], qt[3], out + 3);
    out[6] = OK;
    out[7] = (double)steps;
    out[8] = largest;
    return 1;
}

void pk_position_rows(const double *p, ptrdiff_t rows, const double *u0, int has_guess,
                      const unsigned char *skip, const double *geom, ptrdiff_t m,
                      const double *home, const double *jt_inv, const double *opts,
                      ptrdiff_t n_opts, double *out, ptrdiff_t n_out, pk_work *work) {
    double start[6];
    int use_paired = n_opts > 9 && opts[9] == 1.0 && !has_guess;
    const double *table = use_paired && n_opts > 10 ? opts + 10 : NULL;
    for (ptrdiff_t k = 0; k < rows; k++) {
        double *row = out + n_out * k;
        if (has_guess) {
            for (int i = 0; i < 6; i++) start[i] = u0[6 * k + i];
        } else if (skip[k]) {
            for (int i = 0; i < 6; i++) start[i] = NAN;
        } else if (!use_paired) {
            first_order(p + 3 * k, home, jt_inv, start);
        }
        if (!use_paired) {
            solve_row(p + 3 * k, start, geom, m, opts, row, work);
            if (n_out > 9) row[9] = 0.0;
            continue;
        }
        int done = 0;
        if (!skip[k]) {
            double qt[4];
            if (!table || !table_start(p + 3 * k, table, qt))
                first_order_quaternion(p + 3 * k, home, jt_inv, qt);
            done = solve_paired(p + 3 * k, qt, geom, m, row, work->length);
        }
        if (!done) { /* left to the caller's Levenberg-Marquardt pass */
            for (int i = 0; i < 6; i++) row[i] = NAN;
            row[6] = INVALID_INPUT;
            row[7] = 0.0;
            row[8] = NAN;
        }
        if (n_out > 9) row[9] = done ? 1.0 : 0.0;
    }
}
