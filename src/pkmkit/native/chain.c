/* The closure of joint-chain machines (and the inverse model of a complete one) by
 * Levenberg-Marquardt, one configuration per row: the C twin of
 * pkmkit.solve.chain_kernel._solve_rows and the functions it calls, statement for statement
 * and in the same order of operations (the same statuses, iterations and, with the same libm,
 * the same bits). Matrices are row-major: frames (E, 4, 4), jac (m, n), h and low (n, n). */
#include "kernels.h"

#include <string.h>

enum { OK = 0, NOT_CONVERGED = 3, INVALID_INPUT = 4, INCONSISTENT = 7 };

/* values[v] = u[position[v]] for the unknown variables (_fill_unknowns). */
static void fill_unknowns(double *values, const pk_chain *c, const double *u) {
    for (ptrdiff_t v = 0; v < c->n_var; v++)
        if (c->position[v] >= 0) values[v] = u[c->position[v]];
}

/* Rodrigues with the series of chains.rotvec_matrices (_rotvec_matrix). */
static void rotvec_matrix(double x, double y, double z, double *out) {
    double sq = x * x + y * y + z * z;
    double theta = sqrt(sq);
    double a, b;
    if (theta < 1e-4) {
        a = 1.0 - sq / 6.0 + sq * sq / 120.0;
        b = 0.5 - sq / 24.0 + sq * sq / 720.0;
    } else {
        a = sin(theta) / theta;
        b = (1.0 - cos(theta)) / sq;
    }
    out[0] = 1.0 - b * (y * y + z * z);
    out[4] = 1.0 - b * (x * x + z * z);
    out[8] = 1.0 - b * (x * x + y * y);
    out[1] = b * x * y - a * z;
    out[3] = b * x * y + a * z;
    out[2] = b * x * z + a * y;
    out[6] = b * x * z - a * y;
    out[5] = b * y * z - a * x;
    out[7] = b * y * z + a * x;
}

/* sign L (1/2 S(M) / c + v v' / (2 c^2)) of M into out (3, 3) (_rotation_rows). */
static void rotation_rows(const double *mm, double length, double sign, double *out) {
    double v[3];
    v[0] = 0.5 * (mm[7] - mm[5]);
    v[1] = 0.5 * (mm[2] - mm[6]);
    v[2] = 0.5 * (mm[3] - mm[1]);
    double trace = mm[0] + mm[4] + mm[8];
    double c = 0.25 * (1.0 + trace);
    double f1 = sign * 0.5 * length / c;
    double f2 = sign * 0.5 * length / (c * c);
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            double s = -mm[3 * i + j] + (i == j ? trace : 0.0);
            out[3 * i + j] = s * f1 + v[i] * v[j] * f2;
        }
    }
}

/* (rot, pos) <- (rot, pos) f for an element's frame f (4, 4) (_apply_frame); tmp (9,) no
 * longer used (the callers' scratch kept in the signature). */
static void apply_frame(double *rot, double *pos, const double *f, double *tmp) {
    double r[9], g[12];  /* local copies: no reloads for fear of aliasing (the same sums) */
    memcpy(r, rot, sizeof r);
    memcpy(g, f, sizeof g);
    (void)tmp;
    for (int i = 0; i < 3; i++)
        pos[i] += r[3 * i] * g[3] + r[3 * i + 1] * g[7] + r[3 * i + 2] * g[11];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            rot[3 * i + j] = r[3 * i] * g[j] + r[3 * i + 1] * g[4 + j]
                             + r[3 * i + 2] * g[8 + j];
}

/* One element of a walk: the frame, then the joint (its twist recorded when unknown). */
static void walk_element(const pk_chain *c, ptrdiff_t e, const double *values, double *rot,
                         double *pos, double *tmp, pk_chain_work *w, ptrdiff_t *n_twist) {
    apply_frame(rot, pos, c->frames + 16 * e, tmp);
    int64_t t = c->types[e];
    if (t == 0) return;
    int64_t var = c->evar[e];
    int64_t col = c->position[var];
    double q = values[var];
    if (col >= 0) {
        pk_chain_joint_twist(rot, pos, t, w->tw + 6 * *n_twist);
        w->tw_col[*n_twist] = col;
        *n_twist += 1;
    }
    pk_chain_joint_move(rot, pos, t, q);
}

/* Residual r (6L,) and Jacobian jac (m, n) of the closure at u (_evaluate); jac zeroed
 * whole (m rows). */
static void evaluate(const pk_chain *c, double *values, const double *u, double *r,
                     double *jac, pk_chain_work *w) {
    const ptrdiff_t n = c->n;
    double rx[9], rot[9], tmp[9], mm[9], rows[9], pos[3];
    fill_unknowns(values, c, u);
    rotvec_matrix(u[3], u[4], u[5], rx);
    for (ptrdiff_t i = 0; i < w->m * n; i++) jac[i] = 0.0;
    for (ptrdiff_t leg = 0; leg < c->n_legs; leg++) {
        ptrdiff_t base = 6 * leg;
        for (int i = 0; i < 3; i++) {
            pos[i] = 0.0;
            for (int j = 0; j < 3; j++) rot[3 * i + j] = i == j ? 1.0 : 0.0;
        }
        ptrdiff_t n_twist = 0;
        for (int64_t idx = c->offsets[leg]; idx < c->offsets[leg + 1]; idx++)
            walk_element(c, c->elements[idx], values, rot, pos, tmp, w, &n_twist);
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                mm[3 * i + j] = rot[3 * i] * rx[3 * j] + rot[3 * i + 1] * rx[3 * j + 1]
                                + rot[3 * i + 2] * rx[3 * j + 2];
        double cc = 0.25 * (1.0 + mm[0] + mm[4] + mm[8]);
        for (int i = 0; i < 3; i++) r[base + i] = pos[i] - u[i];
        double length = c->length;
        r[base + 3] = length * (0.5 * (mm[7] - mm[5])) / cc;
        r[base + 4] = length * (0.5 * (mm[2] - mm[6])) / cc;
        r[base + 5] = length * (0.5 * (mm[3] - mm[1])) / cc;
        for (int i = 0; i < 3; i++) {
            jac[(base + i) * n + i] = -1.0;
            for (int j = 0; j < 3; j++) tmp[3 * i + j] = mm[3 * j + i];
        }
        rotation_rows(tmp, length, -1.0, rows);
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) jac[(base + 3 + i) * n + 3 + j] = rows[3 * i + j];
        rotation_rows(mm, length, 1.0, rows);
        for (ptrdiff_t a = 0; a < n_twist; a++) {
            ptrdiff_t col = w->tw_col[a];
            const double *tw = w->tw + 6 * a;
            double w0 = tw[3], w1 = tw[4], w2 = tw[5];
            jac[(base + 0) * n + col] = tw[0] + w1 * pos[2] - w2 * pos[1];
            jac[(base + 1) * n + col] = tw[1] + w2 * pos[0] - w0 * pos[2];
            jac[(base + 2) * n + col] = tw[2] + w0 * pos[1] - w1 * pos[0];
            for (int i = 0; i < 3; i++)
                jac[(base + 3 + i) * n + col] = rows[3 * i] * w0 + rows[3 * i + 1] * w1
                                                + rows[3 * i + 2] * w2;
        }
    }
}

/* evaluate for chain_velocity.c (the closure's Jacobian at solved configurations). */
void pk_chain_evaluate(const pk_chain *c, double *values, const double *u, double *r,
                       double *jac, pk_chain_work *w) {
    evaluate(c, values, u, r, jac, w);
}

/* rotvec_matrix, apply_frame and rotation_rows for chain_velocity.c (the linearisation). */
void pk_chain_rotvec_matrix(double x, double y, double z, double *out) {
    rotvec_matrix(x, y, z, out);
}

void pk_chain_apply_frame(double *rot, double *pos, const double *f, double *tmp) {
    apply_frame(rot, pos, f, tmp);
}

void pk_chain_rotation_rows(const double *mm, double length, double sign, double *out) {
    rotation_rows(mm, length, sign, out);
}

/* The tool rows of the inverse model at rows base..base+5 (_tool_rows, _head_walk). */
static void tool_rows(const pk_chain *c, const double *values, const double *u,
                      const double *target, double tool, ptrdiff_t base, double *r,
                      double *jac, pk_chain_work *w) {
    const ptrdiff_t n = c->n;
    const double length = c->length;
    double rot[9], tmp[9], pos[3];
    rotvec_matrix(u[3], u[4], u[5], rot);
    for (int i = 0; i < 3; i++) pos[i] = u[i];
    ptrdiff_t n_twist = 0;
    for (ptrdiff_t idx = 0; idx < c->n_head; idx++)
        walk_element(c, c->head[idx], values, rot, pos, tmp, w, &n_twist);
    double a0 = rot[2], a1 = rot[5], a2 = rot[8];
    double p0 = pos[0] + tool * a0, p1 = pos[1] + tool * a1, p2 = pos[2] + tool * a2;
    r[base + 0] = p0 - target[0];
    r[base + 1] = p1 - target[1];
    r[base + 2] = p2 - target[2];
    r[base + 3] = length * (a0 - target[3]);
    r[base + 4] = length * (a1 - target[4]);
    r[base + 5] = length * (a2 - target[5]);
    double d0 = p0 - u[0], d1 = p1 - u[1], d2 = p2 - u[2];
    for (int i = 0; i < 3; i++) jac[(base + i) * n + i] = 1.0;
    jac[(base + 0) * n + 4] = d2;
    jac[(base + 0) * n + 5] = -d1;
    jac[(base + 1) * n + 3] = -d2;
    jac[(base + 1) * n + 5] = d0;
    jac[(base + 2) * n + 3] = d1;
    jac[(base + 2) * n + 4] = -d0;
    jac[(base + 3) * n + 4] = length * a2;
    jac[(base + 3) * n + 5] = -length * a1;
    jac[(base + 4) * n + 3] = -length * a2;
    jac[(base + 4) * n + 5] = length * a0;
    jac[(base + 5) * n + 3] = length * a1;
    jac[(base + 5) * n + 4] = -length * a0;
    for (ptrdiff_t k = 0; k < n_twist; k++) {
        ptrdiff_t col = w->tw_col[k];
        const double *tw = w->tw + 6 * k;
        double w0 = tw[3], w1 = tw[4], w2 = tw[5];
        jac[(base + 0) * n + col] = tw[0] + w1 * p2 - w2 * p1;
        jac[(base + 1) * n + col] = tw[1] + w2 * p0 - w0 * p2;
        jac[(base + 2) * n + col] = tw[2] + w0 * p1 - w1 * p0;
        jac[(base + 3) * n + col] = length * (w1 * a2 - w2 * a1);
        jac[(base + 4) * n + col] = length * (w2 * a0 - w0 * a2);
        jac[(base + 5) * n + col] = length * (w0 * a1 - w1 * a0);
    }
}

/* The closure, or the machine inverse's residual and Jacobian (_evaluate_any). */
static void evaluate_any(const pk_chain *c, double *values, const double *u, double *r,
                         double *jac, const double *target, double tool, pk_chain_work *w) {
    evaluate(c, values, u, r, jac, w);
    if (c->inverse) tool_rows(c, values, u, target, tool, 6 * c->n_legs, r, jac, w);
}

/* step = -H^-1 grad by Cholesky, NaN when H is not positive definite (_cholesky_solve). */
static void cholesky_solve(const double *h, const double *grad, double *low, double *step,
                           ptrdiff_t n) {
    for (ptrdiff_t j = 0; j < n; j++) {
        double s = h[j * n + j];
        for (ptrdiff_t p = 0; p < j; p++) s -= low[j * n + p] * low[j * n + p];
        double d = s > 0.0 ? sqrt(s) : NAN;
        low[j * n + j] = d;
        for (ptrdiff_t i = j + 1; i < n; i++) {
            double t = h[i * n + j];
            for (ptrdiff_t p = 0; p < j; p++) t -= low[i * n + p] * low[j * n + p];
            low[i * n + j] = t / d;
        }
    }
    for (ptrdiff_t i = 0; i < n; i++) {
        double t = grad[i];
        for (ptrdiff_t p = 0; p < i; p++) t -= low[i * n + p] * step[p];
        step[i] = t / low[i * n + i];
    }
    for (ptrdiff_t i = n - 1; i >= 0; i--) {
        double t = step[i];
        for (ptrdiff_t p = i + 1; p < n; p++) t -= low[p * n + i] * step[p];
        step[i] = t / low[i * n + i];
    }
    for (ptrdiff_t i = 0; i < n; i++) step[i] = -step[i];
}

/* (w, x, y, z) of a rotation vector (_quaternion). */
static void quaternion(double x, double y, double z, double *out) {
    double sq = x * x + y * y + z * z;
    double half = 0.5 * sqrt(sq);
    double scale;
    if (half < 1e-4)
        scale = 0.5 - sq / 48.0 + sq * sq / 3840.0;
    else
        scale = sin(half) / (2 * half);
    out[0] = cos(half);
    out[1] = scale * x;
    out[2] = scale * y;
    out[3] = scale * z;
}

/* u + step with the rotation composed on the left (_retract). */
static void retract(const double *u, const double *step, double *out, ptrdiff_t n) {
    for (ptrdiff_t i = 0; i < n; i++) out[i] = u[i] + step[i];
    double a[4], b[4];
    quaternion(step[3], step[4], step[5], a);
    quaternion(u[3], u[4], u[5], b);
    double w = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    double x = a[0] * b[1] + b[0] * a[1] + a[2] * b[3] - a[3] * b[2];
    double y = a[0] * b[2] + b[0] * a[2] + a[3] * b[1] - a[1] * b[3];
    double z = a[0] * b[3] + b[0] * a[3] + a[1] * b[2] - a[2] * b[1];
    if (w < 0) {
        x = -x;
        y = -y;
        z = -z;
    }
    w = fabs(w);
    double norm = sqrt(x * x + y * y + z * z);
    double scale;
    if (norm < 1e-8)
        scale = 2.0 / w * (1.0 + norm * norm / (3.0 * w * w));
    else
        scale = 2.0 * atan2(norm, w) / norm;
    out[3] = scale * x;
    out[4] = scale * y;
    out[5] = scale * z;
}

/* sum_i a_i b_i in order (_dot). */
static double dot(const double *a, const double *b, ptrdiff_t n) {
    double acc = 0.0;
    for (ptrdiff_t i = 0; i < n; i++) acc += a[i] * b[i];
    return acc;
}

void pk_chain_rows(const pk_chain *c, const double *known, ptrdiff_t known_rows, double *u,
                   ptrdiff_t rows, const pk_chain_options *o, int64_t *status,
                   double *residual, int64_t *iterations, const double *targets,
                   const double *tools, pk_chain_work *w) {
    const ptrdiff_t n = c->n, m = w->m;
    double *values = w->values, *r = w->r, *jac = w->jac, *r_new = w->r_new;
    double *j_new = w->j_new, *u_new = w->u_new, *step = w->step, *grad = w->grad;
    double *h = w->h, *low = w->low;
    int64_t *nz = w->nz;
    for (ptrdiff_t k = 0; k < rows; k++) {
        double *uk = u + n * k;
        int finite = 1;
        for (ptrdiff_t i = 0; i < n; i++) finite = finite && isfinite(uk[i]);
        if (!finite) {
            status[k] = INVALID_INPUT;
            continue;
        }
        memcpy(values, known + c->n_var * (known_rows > 1 ? k : 0),
               (size_t)c->n_var * sizeof(double));
        ptrdiff_t row = c->inverse ? k : 0;
        const double *target = targets + 6 * row;
        double tool = tools[row];
        evaluate_any(c, values, uk, r, jac, target, tool, w);
        double cost = 0.5 * dot(r, r, m);
        int jac_finite = 1;
        for (ptrdiff_t i = 0; i < m * n; i++) jac_finite = jac_finite && isfinite(jac[i]);
        if (!(isfinite(cost) && jac_finite)) {
            status[k] = INVALID_INPUT;
            continue;
        }
        status[k] = NOT_CONVERGED;
        double lam = o->damping;
        double checkpoint = cost;
        int64_t count = 0;
        int stopped = 0;
        for (int64_t it = 0; it < o->max_iter; it++) {
            double biggest = 0.0;
            for (ptrdiff_t a = 0; a < n; a++) {
                double g = 0.0, col = 0.0;
                for (ptrdiff_t i = 0; i < m; i++) {
                    g += jac[i * n + a] * r[i];
                    col += jac[i * n + a] * jac[i * n + a];
                }
                grad[a] = g;
                double cosine = fabs(g) / sqrt(col * (2.0 * cost));
                if (cosine > biggest) biggest = cosine;
            }
            if (cost <= 0.5 * o->atol * o->atol || !(biggest > o->gtol)) {
                stopped = 1;
                break;
            }
            for (ptrdiff_t i = 0; i < n * n; i++) h[i] = 0.0;
            for (ptrdiff_t i = 0; i < m; i++) {
                ptrdiff_t count_nz = 0;
                for (ptrdiff_t a = 0; a < n; a++)
                    if (jac[i * n + a] != 0.0) nz[count_nz++] = a;
                for (ptrdiff_t p = 0; p < count_nz; p++) {
                    ptrdiff_t a = nz[p];
                    double v = jac[i * n + a];
                    for (ptrdiff_t t = 0; t <= p; t++) h[a * n + nz[t]] += v * jac[i * n + nz[t]];
                }
            }
            double dmax = 0.0;
            for (ptrdiff_t a = 0; a < n; a++) {
                for (ptrdiff_t b = 0; b < a; b++) h[b * n + a] = h[a * n + b];
                if (h[a * n + a] > dmax) dmax = h[a * n + a];
            }
            double floor_ = 1e-9 * dmax + 1e-300;
            for (ptrdiff_t a = 0; a < n; a++) h[a * n + a] += lam * (h[a * n + a] + floor_);
            cholesky_solve(h, grad, low, step, n);
            retract(uk, step, u_new, n);
            evaluate_any(c, values, u_new, r_new, j_new, target, tool, w);
            double cost_new = 0.5 * dot(r_new, r_new, m);
            int accept = pk_lm_accept(cost, cost_new, &lam);
            count += 1;
            if (accept) {
                memcpy(uk, u_new, (size_t)n * sizeof(double));
                memcpy(r, r_new, (size_t)m * sizeof(double));
                memcpy(jac, j_new, (size_t)(m * n) * sizeof(double));
                cost = cost_new;
            }
            if (pk_lm_done(o, accept, step, uk, n, lam, cost, count, &checkpoint)) {
                stopped = 1;
                break;
            }
        }
        iterations[k] = count;
        double worst = 0.0;
        for (ptrdiff_t i = 0; i < m; i++)
            if (fabs(r[i]) > worst || isnan(r[i])) worst = fabs(r[i]);
        residual[k] = worst;
        if (stopped) status[k] = worst <= o->residual_tol ? OK : INCONSISTENT;
    }
}

/* evaluate_any and retract for chain_one.c (the one-pose solve by block elimination). */
void pk_chain_evaluate_any(const pk_chain *c, double *values, const double *u, double *r,
                           double *jac, const double *target, double tool, pk_chain_work *w) {
    evaluate_any(c, values, u, r, jac, target, tool, w);
}

void pk_chain_retract(const double *u, const double *step, double *out, ptrdiff_t n) {
    retract(u, step, out, n);
}
