/* One pose per call on a joint-chain machine (machines/chain_one_native.py, issue 22 §1):
 * the machine's constants packed once into a capsule (chain_one_pack), then one call per
 * pose: chain_one_ik (the inverse model: plain-number check, first-order start, solve, the
 * legs' home-mode test, the retry from home, the turn wrapping, the head's branch rule, the
 * stroke test) and chain_one_fk (the direct model: start, closure, regularity bound, stroke
 * test, tool point and axis). Anything the batch path must decide (not plain numbers, no
 * convergence, a stroke, a mirror that left the legs' home modes, a bound that does not
 * certify the closure regular) returns None: the caller takes the batch path.
 *
 * The solve is chain.c's Levenberg-Marquardt loop (pk_chain_rows: the same stopping rules,
 * statuses, damping and, to the bit, the same gradient and normal matrix), with the normal
 * equations solved by block elimination: the residual of leg b (rows 6b..6b+5) depends on the
 * platform's 6 unknowns and leg b's own joints only, the tool rows on the platform and the
 * head's joints, so H = [[A, B'], [B, D]] with D block diagonal; each D_b (at most a few
 * joints) is factored alone, the Schur complement S = A - sum B_b' D_b^-1 B_b (6 x 6) gives
 * the platform's step, then each block's. The step agrees with the dense Cholesky's to
 * rounding (not to the bit): results agree with the batch rows to ~1e-15 (tests). A model
 * whose joints are shared between blocks is solved dense (pk_chain_rows). */
#include "chain_face.h"

#include <math.h>

enum { OK = 0, NOT_CONVERGED = 3 };

/* Columns of each block of rows (legs, then the tool rows of the inverse model). */
typedef struct {
    ptrdiff_t count;     /* blocks */
    int64_t *start;      /* (count + 1,) into cols */
    int64_t *cols;       /* the blocks' columns, each >= 6 */
    ptrdiff_t widest;    /* largest block */
    ptrdiff_t n_core;    /* the platform's 6 columns and the joints shared by blocks */
    int64_t *core;
} pk_blocks;

typedef struct {
    pk_chain inv, dir;
    pk_chain_options inv_o, dir_o;
    pk_blocks inv_b, dir_b;
    int structured;
    double *u_home_inv, *base, *inv_rates, tool;
    int64_t *slides, *turns, *act_turns, *act;
    double *signs, *turn_homes, *act_turn_homes, *lower, *upper;
    ptrdiff_t n_slides, n_turns, n_act_turns, n_act;
    int wrist, wide;
    int64_t w_turn, w_tilt;
    double w_home, w_centre, far;
    double *u_home_dir, *dir_rates, *residual_rates, *home_values;
    double singular_bound, max_coordinate;
    ptrdiff_t twists, m_dir;
    PyObject *empty, *ndarray, *n_obj, *u_obj, *six;
    void *owned[48];
    int n_owned;
} pk_one;

/* ---------------------------------------------------------------- the structured solve */

/* Lower Cholesky factor of the k x k matrix a (row-major, lower part read) into low; NaN
 * where not positive definite (chain.c's rule). */
static void factor(const double *a, double *low, ptrdiff_t k) {
    for (ptrdiff_t j = 0; j < k; j++) {
        double s = a[j * k + j];
        for (ptrdiff_t p = 0; p < j; p++) s -= low[j * k + p] * low[j * k + p];
        double d = s > 0.0 ? sqrt(s) : NAN;
        low[j * k + j] = d;
        for (ptrdiff_t i = j + 1; i < k; i++) {
            double t = a[i * k + j];
            for (ptrdiff_t p = 0; p < j; p++) t -= low[i * k + p] * low[j * k + p];
            low[i * k + j] = t / d;
        }
    }
}

/* x <- L^-1 x (stride sx between entries of x). */
static void forward(const double *low, ptrdiff_t k, double *x, ptrdiff_t sx) {
    for (ptrdiff_t i = 0; i < k; i++) {
        double t = x[i * sx];
        for (ptrdiff_t p = 0; p < i; p++) t -= low[i * k + p] * x[p * sx];
        x[i * sx] = t / low[i * k + i];
    }
}

/* x <- L^-T x. */
static void backward(const double *low, ptrdiff_t k, double *x) {
    for (ptrdiff_t i = k - 1; i >= 0; i--) {
        double t = x[i];
        for (ptrdiff_t p = i + 1; p < k; p++) t -= low[p * k + i] * x[p];
        x[i] = t / low[i * k + i];
    }
}

/* The damped Gauss-Newton step of pk_chain_rows, step = -(H + lam (diag H + floor))^-1 grad,
 * with H = J'J built block by block (the dense loop's sums: zero entries skipped, x + 0.0 is
 * x) and solved by the Schur complement onto the core columns (the platform's 6 and the
 * joints shared by several blocks): per block b (rows 6b..6b+5, its own columns) D_b = L_b
 * L_b', Y_b = L_b^-1 B_b, z_b = L_b^-1 g_b; S = A - sum Y_b'Y_b; x_C = S^-1 (g_C - sum
 * Y_b'z_b); x_b = L_b^-T (z_b - Y_b x_C). scratch: block_scratch doubles. */
static void block_step(const pk_blocks *bk, const double *jac, ptrdiff_t m, ptrdiff_t n,
                       const double *grad, double lam, double *step, double *scratch) {
    const ptrdiff_t nc = bk->n_core, w = bk->widest;
    const int64_t *core = bk->core;
    double *a = scratch, *sl = a + nc * nc, *xp = sl + nc * nc, *diag = xp + nc;
    double *hbb = diag + n, *store = hbb + w * w;
    for (ptrdiff_t p = 0; p < nc * nc; p++) a[p] = 0.0;
    for (ptrdiff_t i = 0; i < m; i++) {  /* A over every row, in row order */
        const double *row = jac + i * n;
        for (ptrdiff_t p = 0; p < nc; p++) {
            double v = row[core[p]];
            if (v == 0.0) continue;
            for (ptrdiff_t t = 0; t <= p; t++) a[p * nc + t] += v * row[core[t]];
        }
    }
    for (ptrdiff_t c = 0; c < n; c++) diag[c] = 0.0;
    for (ptrdiff_t p = 0; p < nc; p++) diag[core[p]] = a[p * nc + p];
    for (ptrdiff_t b = 0; b < bk->count; b++) {
        const int64_t *cols = bk->cols + bk->start[b];
        ptrdiff_t k = bk->start[b + 1] - bk->start[b];
        for (ptrdiff_t p = 0; p < k; p++) {
            double acc = 0.0;
            for (ptrdiff_t i = 6 * b; i < 6 * b + 6; i++)
                acc += jac[i * n + cols[p]] * jac[i * n + cols[p]];
            diag[cols[p]] = acc;
        }
    }
    double dmax = 0.0;
    for (ptrdiff_t c = 0; c < n; c++)
        if (diag[c] > dmax) dmax = diag[c];
    double floor_ = 1e-9 * dmax + 1e-300;
    for (ptrdiff_t p = 0; p < nc; p++) a[p * nc + p] += lam * (a[p * nc + p] + floor_);
    for (ptrdiff_t p = 0; p < nc; p++) xp[p] = grad[core[p]];
    /* free columns (in no block: zero Jacobian): no step */
    for (ptrdiff_t c = 0; c < n; c++) step[c] = -(grad[c] / (lam * (diag[c] + floor_)));
    for (ptrdiff_t b = 0; b < bk->count; b++) {
        const int64_t *cols = bk->cols + bk->start[b];
        ptrdiff_t k = bk->start[b + 1] - bk->start[b];
        const double *rows = jac + 6 * b * n;
        double *lbb = store + b * (w * w + nc * w + w), *y = lbb + w * w, *z = y + nc * w;
        for (ptrdiff_t p = 0; p < k; p++) {
            for (ptrdiff_t t = 0; t <= p; t++) {
                double acc = 0.0;
                for (int i = 0; i < 6; i++) acc += rows[i * n + cols[p]] * rows[i * n + cols[t]];
                hbb[p * k + t] = acc;
            }
            hbb[p * k + p] += lam * (hbb[p * k + p] + floor_);
            for (ptrdiff_t t = 0; t < nc; t++) {  /* B_b (k x nc) */
                double acc = 0.0;
                for (int i = 0; i < 6; i++) acc += rows[i * n + cols[p]] * rows[i * n + core[t]];
                y[p * nc + t] = acc;
            }
            z[p] = grad[cols[p]];
        }
        factor(hbb, lbb, k);
        for (ptrdiff_t t = 0; t < nc; t++) forward(lbb, k, y + t, nc);
        forward(lbb, k, z, 1);
        for (ptrdiff_t p = 0; p < nc; p++) {
            for (ptrdiff_t t = 0; t <= p; t++) {
                double acc = 0.0;
                for (ptrdiff_t q = 0; q < k; q++) acc += y[q * nc + p] * y[q * nc + t];
                a[p * nc + t] -= acc;
            }
            double acc = 0.0;
            for (ptrdiff_t q = 0; q < k; q++) acc += y[q * nc + p] * z[q];
            xp[p] -= acc;
        }
    }
    factor(a, sl, nc);
    forward(sl, nc, xp, 1);
    backward(sl, nc, xp);
    for (ptrdiff_t p = 0; p < nc; p++) step[core[p]] = -xp[p];
    for (ptrdiff_t b = 0; b < bk->count; b++) {
        const int64_t *cols = bk->cols + bk->start[b];
        ptrdiff_t k = bk->start[b + 1] - bk->start[b];
        double *lbb = store + b * (w * w + nc * w + w), *y = lbb + w * w, *z = y + nc * w;
        for (ptrdiff_t p = 0; p < k; p++) {
            double acc = z[p];
            for (ptrdiff_t t = 0; t < nc; t++) acc -= y[p * nc + t] * xp[t];
            z[p] = acc;
        }
        backward(lbb, k, z);
        for (ptrdiff_t p = 0; p < k; p++) step[cols[p]] = -z[p];
    }
}

/* Doubles of block_step's scratch. */
static ptrdiff_t block_scratch(const pk_blocks *bk, ptrdiff_t n) {
    ptrdiff_t nc = bk->n_core, w = bk->widest;
    return 2 * nc * nc + nc + n + w * w + bk->count * (w * w + nc * w + w);
}

/* sum a_i b_i in order. */
static double dot(const double *a, const double *b, ptrdiff_t n) {
    double acc = 0.0;
    for (ptrdiff_t i = 0; i < n; i++) acc += a[i] * b[i];
    return acc;
}

/* The loop of pk_chain_rows on one row u (n,), from known (n_var,), its normal equations by
 * block_step: status, residual, iterations out. */
static void solve_blocks(const pk_chain *c, const pk_blocks *bk, const double *known,
                         double *u, const pk_chain_options *o, const double *target,
                         double tool, pk_chain_work *w, double *scratch, int64_t *status,
                         double *residual, int64_t *iterations) {
    const ptrdiff_t n = c->n, m = w->m;
    double *values = w->values, *r = w->r, *jac = w->jac, *r_new = w->r_new;
    double *j_new = w->j_new, *u_new = w->u_new, *step = w->step, *grad = w->grad;
    *iterations = 0;
    *residual = NAN;
    for (ptrdiff_t i = 0; i < n; i++)
        if (!isfinite(u[i])) {
            *status = 4;
            return;
        }
    memcpy(values, known, (size_t)c->n_var * sizeof(double));
    pk_chain_evaluate_any(c, values, u, r, jac, target, tool, w);
    double cost = 0.5 * dot(r, r, m);
    int jac_finite = 1;
    for (ptrdiff_t i = 0; i < m * n; i++) jac_finite = jac_finite && isfinite(jac[i]);
    if (!(isfinite(cost) && jac_finite)) {
        *status = 4;
        return;
    }
    *status = NOT_CONVERGED;
    double lam = o->damping;
    double checkpoint = cost;
    int64_t count = 0;
    int stopped = 0;
    for (int64_t it = 0; it < o->max_iter; it++) {
        double biggest = 0.0;
        for (ptrdiff_t a = 0; a < n; a++) grad[a] = 0.0;
        /* the gradient and the columns' norms: the dense loop's sums, zero entries skipped
         * (x + 0.0 is x): the platform's columns over every row, a block's over its rows */
        for (ptrdiff_t p = 0; p < bk->n_core; p++) {
            ptrdiff_t a = bk->core[p];
            double g = 0.0, col = 0.0;
            for (ptrdiff_t i = 0; i < m; i++) {
                g += jac[i * n + a] * r[i];
                col += jac[i * n + a] * jac[i * n + a];
            }
            grad[a] = g;
            double cosine = fabs(g) / sqrt(col * (2.0 * cost));
            if (cosine > biggest) biggest = cosine;
        }
        for (ptrdiff_t b = 0; b < bk->count; b++) {
            for (int64_t q = bk->start[b]; q < bk->start[b + 1]; q++) {
                ptrdiff_t a = bk->cols[q];
                double g = 0.0, col = 0.0;
                for (ptrdiff_t i = 6 * b; i < 6 * b + 6; i++) {
                    g += jac[i * n + a] * r[i];
                    col += jac[i * n + a] * jac[i * n + a];
                }
                grad[a] = g;
                double cosine = fabs(g) / sqrt(col * (2.0 * cost));
                if (cosine > biggest) biggest = cosine;
            }
        }
        if (cost <= 0.5 * o->atol * o->atol || !(biggest > o->gtol)) {
            stopped = 1;
            break;
        }
        block_step(bk, jac, m, n, grad, lam, step, scratch);
        pk_chain_retract(u, step, u_new, n);
        pk_chain_evaluate_any(c, values, u_new, r_new, j_new, target, tool, w);
        double cost_new = 0.5 * dot(r_new, r_new, m);
        int accept = isfinite(cost_new) && cost_new <= cost * (1.0 + 1e-13);
        count += 1;
        if (accept) {
            memcpy(u, u_new, (size_t)n * sizeof(double));
            memcpy(r, r_new, (size_t)m * sizeof(double));
            double *swap = jac;  /* the new Jacobian is the current one */
            jac = j_new;
            j_new = swap;
            cost = cost_new;
            lam = pk_max(lam * 0.1, 1e-12);
        } else {
            lam *= 10.0;
        }
        double step_norm = sqrt(dot(step, step, n));
        double u_norm = sqrt(dot(u, u, n));
        int done = (accept && step_norm <= o->xtol * (1.0 + u_norm)) || lam > 1e12;
        if (count % 10 == 0) {
            if (cost > (1.0 - o->stall) * checkpoint
                && cost > 0.5 * (o->residual_tol * o->residual_tol))
                done = 1;
            checkpoint = cost;
        }
        if (done) {
            stopped = 1;
            break;
        }
    }
    *iterations = count;
    double worst = 0.0;
    for (ptrdiff_t i = 0; i < m; i++)
        if (fabs(r[i]) > worst || isnan(r[i])) worst = fabs(r[i]);
    *residual = worst;
    if (stopped) *status = worst <= o->residual_tol ? OK : 7;
}

/* ---------------------------------------------------------------- one call's work */

typedef struct {
    pk_chain_work w;
    double *scratch, *u, *u2, *values, *values2, *pred, *du, *low;
    int64_t *ints;
    void *memory;
} pk_one_work;

/* The work arrays of one call (the larger of the two models'), one allocation; 0 on success. */
static int work_alloc(const pk_one *s, pk_one_work *k) {
    ptrdiff_t n = s->inv.n, m = 6 * s->inv.n_legs + 6, nv = s->inv.n_var;
    ptrdiff_t wide = block_scratch(&s->inv_b, n), wide_dir = block_scratch(&s->dir_b, n);
    if (wide_dir > wide) wide = wide_dir;
    size_t cells = (size_t)(nv + 2 * m + 2 * m * n + 3 * n + 2 * n * n + 6 * s->twists)
                   + (size_t)wide + (size_t)(4 * n + 2 * nv + 2 * n);
    size_t ints = (size_t)(n + s->twists);
    k->memory = malloc(sizeof(double) * cells + sizeof(int64_t) * ints);
    if (!k->memory) return -1;
    double *next = k->memory;
    k->w.m = m;
    k->w.values = next, next += nv;
    k->w.r = next, next += m;
    k->w.jac = next, next += m * n;
    k->w.r_new = next, next += m;
    k->w.j_new = next, next += m * n;
    k->w.u_new = next, next += n;
    k->w.step = next, next += n;
    k->w.grad = next, next += n;
    k->w.h = next, next += n * n;
    k->w.low = next, next += n * n;
    k->w.tw = next, next += 6 * s->twists;
    k->scratch = next, next += wide;
    k->u = next, next += n;
    k->u2 = next, next += n;
    k->pred = next, next += n;
    k->du = next, next += n;
    k->values = next, next += nv;
    k->values2 = next, next += nv;
    k->low = next, next += 2 * n;  /* unused slack */
    k->ints = (int64_t *)next;
    k->w.nz = k->ints;
    k->w.tw_col = k->ints + n;
    return 0;
}

/* One solve of model c (its blocks bk), structured or dense as packed. */
static void solve(const pk_one *s, const pk_chain *c, const pk_blocks *bk,
                  const pk_chain_options *o, const double *known, double *u,
                  const double *target, double tool, pk_one_work *k, int64_t *status,
                  double *residual, int64_t *iterations) {
    k->w.m = 6 * c->n_legs + (c->inverse ? 6 : 0);
    if (s->structured) {
        solve_blocks(c, bk, known, u, o, target, tool, &k->w, k->scratch, status, residual,
                     iterations);
    } else {
        *residual = NAN;
        *iterations = 0;
        pk_chain_rows(c, known, 1, u, 1, o, status, residual, iterations, target, &tool, &k->w);
    }
}

/* ---------------------------------------------------------------- the inverse model */

static int in_home_modes(const pk_one *s, const double *u) {
    for (ptrdiff_t i = 0; i < s->n_slides; i++)
        if (!(u[s->slides[i]] * s->signs[i] > 0)) return 0;
    for (ptrdiff_t i = 0; i < s->n_turns; i++)
        if (!(cos(u[s->turns[i]] - s->turn_homes[i]) > 0)) return 0;
    return 1;
}

/* values (n_var,) <- u[6:] with the revolute actuators on the turn nearest home. */
static void wrapped(const pk_one *s, const double *u, double *values) {
    memcpy(values, u + 6, (size_t)s->inv.n_var * sizeof(double));
    for (ptrdiff_t i = 0; i < s->n_act_turns; i++) {
        int64_t v = s->act_turns[i];
        double d = values[v] - s->act_turn_homes[i];
        values[v] = s->act_turn_homes[i] + atan2(sin(d), cos(d));
    }
}

static int within(const pk_one *s, const double *values) {
    for (ptrdiff_t v = 0; v < s->inv.n_var; v++)
        if (!(s->lower[v] <= values[v] && values[v] <= s->upper[v])) return 0;
    return 1;
}

static double turn_offset(double angle) { return PK_PI - pk_pymod(PK_PI - angle, 2.0 * PK_PI); }

/* The inverse of target (6,) (axis unit) from start (n,) or the first-order start (NULL):
 * 1 with values, u (the kept solution), *iterations, *residual filled; 0 where the batch path
 * must decide. machines/chain_one.py's _inverse_values and _nearest_branch, statement for
 * statement. */
static int inverse(const pk_one *s, const double *target, const double *start, pk_one_work *k,
                   double *values, double *u, int64_t *iterations, double *residual) {
    const pk_chain *c = &s->inv;
    ptrdiff_t n = c->n;
    int64_t status;
    if (start == NULL) {
        double d[6];
        for (int i = 0; i < 3; i++) {
            d[i] = (target[i] - s->tool * target[3 + i]) - s->base[i];
            d[3 + i] = target[3 + i] - s->base[3 + i];
        }
        for (ptrdiff_t i = 0; i < n; i++) {
            double acc = d[0] * s->inv_rates[6 * i];
            for (int j = 1; j < 6; j++) acc = acc + d[j] * s->inv_rates[6 * i + j];
            u[i] = s->u_home_inv[i] + acc;
        }
    } else {
        memcpy(u, start, (size_t)n * sizeof(double));
    }
    solve(s, c, &s->inv_b, &s->inv_o, s->u_home_inv + 6, u, target, s->tool, k, &status,
          residual, iterations);
    int first = status == OK && in_home_modes(s, u);
    if (!first) {
        memcpy(u, s->u_home_inv, (size_t)n * sizeof(double));
        solve(s, c, &s->inv_b, &s->inv_o, s->u_home_inv + 6, u, target, s->tool, k, &status,
              residual, iterations);
        if (status != OK) return 0;
    }
    wrapped(s, u, values);
    if (!s->wrist) return 1;
    /* the head's branch rule */
    double offset = turn_offset(u[6 + s->w_turn] - s->w_home);
    int far = fabs(offset) > s->far;
    int kept_inside = within(s, values);
    if (!(far || (s->wide && !kept_inside))) return 1;
    double *other = k->u2, *other_values = k->values2;
    memcpy(other, u, (size_t)n * sizeof(double));
    other[6 + s->w_turn] += PK_PI;
    other[6 + s->w_tilt] = 2.0 * s->w_centre - other[6 + s->w_tilt];
    int64_t other_iterations;
    double other_residual;
    solve(s, c, &s->inv_b, &s->inv_o, s->u_home_inv + 6, other, target, s->tool, k, &status,
          &other_residual, &other_iterations);
    if (status != OK) return 0;
    wrapped(s, other, other_values);
    int closer = fabs(turn_offset(other[6 + s->w_turn] - s->w_home)) < fabs(offset);
    int flipped_inside = within(s, other_values);
    *iterations += other_iterations;
    if ((flipped_inside && !kept_inside) || (flipped_inside == kept_inside && closer)) {
        if (first && !in_home_modes(s, other)) return 0;
        memcpy(u, other, (size_t)n * sizeof(double));
        memcpy(values, other_values, (size_t)c->n_var * sizeof(double));
        *residual = other_residual;
    }
    return 1;
}

/* ---------------------------------------------------------------- the direct model */

/* The tool point and axis into pose (6,): the head walked from the platform u[:6]. */
static void tool_pose(const pk_one *s, const double *values, const double *u, double *pose) {
    const pk_chain *c = &s->dir;
    double rot[9], pos[3], tmp[9];
    pk_chain_rotvec_matrix(u[3], u[4], u[5], rot);
    for (int i = 0; i < 3; i++) pos[i] = u[i];
    for (ptrdiff_t idx = 0; idx < c->n_head; idx++) {
        int64_t e = c->head[idx];
        pk_chain_apply_frame(rot, pos, c->frames + 16 * e, tmp);
        int64_t t = c->types[e];
        if (t == 0) continue;
        double q = values[c->evar[e]];
        if (t == 1) {
            double cq = cos(q), sq = sin(q);
            for (int i = 0; i < 3; i++) {
                double x = rot[3 * i], y = rot[3 * i + 1];
                rot[3 * i] = cq * x + sq * y;
                rot[3 * i + 1] = cq * y - sq * x;
            }
        } else {
            pos[0] += q * rot[2];
            pos[1] += q * rot[5];
            pos[2] += q * rot[8];
        }
    }
    for (int i = 0; i < 3; i++) {
        pose[i] = pos[i] + s->tool * rot[3 * i + 2];
        pose[3 + i] = rot[3 * i + 2];
    }
}

/* 1 / sqrt(||J||_F^2 ||L^-1||_F^2) with L L' = J'J (chain_one_kernel._factor, _bound). */
static double regular_bound(const double *jac, ptrdiff_t m, ptrdiff_t n, double *low,
                            double *inv) {
    double fro = 0.0;
    for (ptrdiff_t i = 0; i < m * n; i++) fro += jac[i] * jac[i];
    for (ptrdiff_t j = 0; j < n; j++) {
        for (ptrdiff_t i = j; i < n; i++) {
            double acc = 0.0;
            for (ptrdiff_t q = 0; q < m; q++) acc += jac[q * n + i] * jac[q * n + j];
            for (ptrdiff_t p = 0; p < j; p++) acc -= low[i * n + p] * low[j * n + p];
            if (i == j)
                low[j * n + j] = acc > 0.0 ? sqrt(acc) : NAN;
            else
                low[i * n + j] = acc / low[j * n + j];
        }
    }
    double total = 0.0;
    for (ptrdiff_t j = 0; j < n; j++) {
        for (ptrdiff_t i = j; i < n; i++) {
            double acc = i == j ? 1.0 : 0.0;
            for (ptrdiff_t p = j; p < i; p++) acc -= low[i * n + p] * inv[p * n + j];
            inv[i * n + j] = acc / low[i * n + i];
            total += inv[i * n + j] * inv[i * n + j];
        }
    }
    return 1.0 / sqrt(fro * total);
}

/* The direct model of q (n_act,): 1 with pose (6,) and values (n_var,) filled, 0 where the
 * batch path must decide (chain_one_kernel.direct_one and chain_one.direct). */
static int direct(const pk_one *s, const double *q, int check, pk_one_work *k, double *values,
                  double *pose) {
    const pk_chain *c = &s->dir;
    ptrdiff_t n_u = c->n, m = s->m_dir, n = s->n_act;
    double *u = k->u, *pred = k->pred, *du = k->du, delta[64];
    if (n > 64) return 0;
    memcpy(values, s->home_values, (size_t)c->n_var * sizeof(double));
    for (ptrdiff_t j = 0; j < n; j++) {
        values[s->act[j]] = q[j];
        delta[j] = q[j] - s->home_values[s->act[j]];
    }
    /* the start: home moved to first order, or home where that closes worse */
    for (ptrdiff_t i = 0; i < n_u; i++) {
        double acc = 0.0;
        for (ptrdiff_t j = 0; j < n; j++) acc += delta[j] * s->dir_rates[i * n + j];
        du[i] = acc;
    }
    pk_chain_retract(s->u_home_dir, du, pred, n_u);
    k->w.m = m;
    memcpy(k->values2, values, (size_t)c->n_var * sizeof(double));
    pk_chain_evaluate(c, k->values2, pred, k->w.r, k->w.jac, &k->w);
    double home_cost = 0.0;
    for (ptrdiff_t i = 0; i < m; i++) {
        double acc = 0.0;
        for (ptrdiff_t j = 0; j < n; j++) acc += delta[j] * s->residual_rates[i * n + j];
        home_cost += acc * acc;
    }
    int worse = !(dot(k->w.r, k->w.r, m) <= home_cost);
    memcpy(u, worse ? s->u_home_dir : pred, (size_t)n_u * sizeof(double));
    int64_t status, iterations;
    double residual;
    double no_target[6] = {0, 0, 0, 0, 0, 0};
    solve(s, c, &s->dir_b, &s->dir_o, values, u, no_target, 0.0, k, &status, &residual,
          &iterations);
    if (status != OK) return 0;
    for (ptrdiff_t v = 0; v < c->n_var; v++)
        if (c->position[v] >= 0) values[v] = u[c->position[v]];
    if (check) {
        k->w.m = m;
        memcpy(k->values2, values, (size_t)c->n_var * sizeof(double));
        pk_chain_evaluate(c, k->values2, u, k->w.r, k->w.jac, &k->w);
        double bound = regular_bound(k->w.jac, m, n_u, k->w.h, k->w.low);
        if (!(bound >= s->singular_bound)) return 0;
    }
    tool_pose(s, values, u, pose);
    return 1;
}

/* ---------------------------------------------------------------- the module face */

/* width plain finite numbers within +-max_coordinate from a list, tuple (floats and ints) or
 * a 1-D float64 / float32 array into out: 1, else 0 (the batch path; no error set). */
static int plain(const pk_one *s, PyObject *x, ptrdiff_t width, double *out) {
    if (PyList_CheckExact(x) || PyTuple_CheckExact(x)) {
        if (PySequence_Fast_GET_SIZE(x) != width) return 0;
        PyObject **items = PySequence_Fast_ITEMS(x);
        for (ptrdiff_t i = 0; i < width; i++) {
            PyObject *v = items[i];
            if (PyFloat_CheckExact(v)) {
                out[i] = PyFloat_AS_DOUBLE(v);
            } else if (PyLong_CheckExact(v)) {
                out[i] = PyLong_AsDouble(v);
                if (out[i] == -1.0 && PyErr_Occurred()) {
                    PyErr_Clear();
                    return 0;
                }
            } else {
                return 0;
            }
        }
    } else if (PyObject_TypeCheck(x, (PyTypeObject *)s->ndarray)) {
        Py_buffer view;
        if (PyObject_GetBuffer(x, &view, PyBUF_RECORDS_RO) < 0) {
            PyErr_Clear();
            return 0;
        }
        const char *f = view.format ? view.format : "B";
        if (f[0] == '@' || f[0] == '=' || (PY_LITTLE_ENDIAN && f[0] == '<')) f++;
        int ok = view.ndim == 1 && view.shape[0] == width && f[1] == 0
                 && ((f[0] == 'd' && view.itemsize == 8) || (f[0] == 'f' && view.itemsize == 4));
        if (ok) {
            const char *p = view.buf;
            for (ptrdiff_t i = 0; i < width; i++, p += view.strides[0])
                out[i] = f[0] == 'd' ? *(const double *)p : (double)*(const float *)p;
        }
        PyBuffer_Release(&view);
        if (!ok) return 0;
    } else {
        return 0;
    }
    for (ptrdiff_t i = 0; i < width; i++)
        if (!(fabs(out[i]) <= s->max_coordinate)) return 0;
    return 1;
}

/* A new float64 array of `count` values (numpy.empty through the packed callable). */
static PyObject *new_array(const pk_one *s, PyObject *size, const double *data, ptrdiff_t count) {
    PyObject *arr = PyObject_CallOneArg(s->empty, size);
    if (!arr) return NULL;
    Py_buffer view;
    if (PyObject_GetBuffer(arr, &view, PyBUF_C_CONTIGUOUS | PyBUF_WRITABLE) < 0) {
        Py_DECREF(arr);
        return NULL;
    }
    memcpy(view.buf, data, (size_t)count * sizeof(double));
    PyBuffer_Release(&view);
    return arr;
}

static const char CAPSULE[] = "pkmkit.chain_one";

static pk_one *capsule_state(PyObject *capsule) {
    return PyCapsule_GetPointer(capsule, CAPSULE);
}

const char pk_chain_one_ik_doc[] =
    "chain_one_ik(packed, x, ignore, full, start=None)\n\n"
    "The inverse model of one plain pose x (6 numbers: list, tuple or 1-D float array) of the\n"
    "machine packed by chain_one_pack: q (n,), or with full (q, u (6 + n_var,), iterations,\n"
    "residual); None where the batch path must decide (machines/chain_one_native.py).\n"
    "ignore: keep a solution beyond a stroke; start: 6 + n_var plain numbers (a previous\n"
    "solution) instead of the first-order start.";

PyObject *pk_py_chain_one_ik(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs < 4 || nargs > 5) {
        PyErr_SetString(PyExc_TypeError, "chain_one_ik(packed, x, ignore, full, start=None)");
        return NULL;
    }
    pk_one *s = capsule_state(args[0]);
    if (!s) return NULL;
    ptrdiff_t n = s->inv.n, nv = s->inv.n_var;
    double x[6], target[6];
    if (!plain(s, args[1], 6, x)) Py_RETURN_NONE;
    int ignore = PyObject_IsTrue(args[2]), full = PyObject_IsTrue(args[3]);
    if (ignore < 0 || full < 0) return NULL;
    double norm = sqrt(x[3] * x[3] + x[4] * x[4] + x[5] * x[5]);
    if (!(norm > 0)) Py_RETURN_NONE;
    for (int i = 0; i < 3; i++) {
        target[i] = x[i];
        target[3 + i] = x[3 + i] / norm;
    }
    pk_one_work k;
    if (work_alloc(s, &k) < 0) return PyErr_NoMemory();
    double *start = NULL;
    if (nargs == 5 && args[4] != Py_None) {
        start = k.pred;
        if (!plain(s, args[4], n, start)) {
            free(k.memory);
            Py_RETURN_NONE;
        }
    }
    double *values = k.values, *u = k.u, q[64];
    int64_t iterations = 0;
    double residual = NAN;
    int found;
    Py_BEGIN_ALLOW_THREADS
    found = inverse(s, target, start, &k, values, u, &iterations, &residual)
            && (ignore || within(s, values)) && s->n_act <= 64;
    if (found)
        for (ptrdiff_t j = 0; j < s->n_act; j++) q[j] = values[s->act[j]];
    Py_END_ALLOW_THREADS
    PyObject *out = NULL;
    if (!found) {
        free(k.memory);
        Py_RETURN_NONE;
    }
    PyObject *qa = new_array(s, s->n_obj, q, s->n_act);
    if (qa && full) {
        PyObject *ua = new_array(s, s->u_obj, u, 6 + nv);
        out = ua ? Py_BuildValue("(NNLd)", qa, ua, (long long)iterations, residual) : NULL;
        if (!out) {
            Py_DECREF(qa);
            Py_XDECREF(ua);
        }
    } else {
        out = qa;
    }
    free(k.memory);
    return out;
}

const char pk_chain_one_fk_doc[] =
    "chain_one_fk(packed, q, ignore, check)\n\n"
    "The direct model of one plain configuration q (n numbers) of the machine packed by\n"
    "chain_one_pack: the tool point and axis (6,), or None where the batch path must decide\n"
    "(machines/chain_one_native.py). check: certify the closure regular (else None).";

PyObject *pk_py_chain_one_fk(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 4) {
        PyErr_SetString(PyExc_TypeError, "chain_one_fk(packed, q, ignore, check)");
        return NULL;
    }
    pk_one *s = capsule_state(args[0]);
    if (!s) return NULL;
    double q[64], pose[6];
    if (s->n_act > 64 || !plain(s, args[1], s->n_act, q)) Py_RETURN_NONE;
    int ignore = PyObject_IsTrue(args[2]), check = PyObject_IsTrue(args[3]);
    if (ignore < 0 || check < 0) return NULL;
    pk_one_work k;
    if (work_alloc(s, &k) < 0) return PyErr_NoMemory();
    int found;
    Py_BEGIN_ALLOW_THREADS
    found = direct(s, q, check, &k, k.values, pose) && (ignore || within(s, k.values));
    Py_END_ALLOW_THREADS
    free(k.memory);
    if (!found) Py_RETURN_NONE;
    return new_array(s, s->six, pose, 6);
}

/* ---------------------------------------------------------------- packing */

static int check_count(Py_ssize_t nargs, Py_ssize_t expected, const char *name) {
    if (nargs != expected) {
        PyErr_Format(PyExc_TypeError, "%s() takes %zd positional arguments (%zd given)", name,
                     expected, nargs);
        return -1;
    }
    return 0;
}

static void release_state(PyObject *capsule) {
    pk_one *s = PyCapsule_GetPointer(capsule, CAPSULE);
    if (!s) return;
    for (int i = 0; i < s->n_owned; i++) free(s->owned[i]);
    Py_XDECREF(s->empty);
    Py_XDECREF(s->ndarray);
    Py_XDECREF(s->n_obj);
    Py_XDECREF(s->u_obj);
    Py_XDECREF(s->six);
    free(s);
}

/* A copy of argument obj (type 'd' or 'i', ndim dimensions, `count` entries when >= 0; its
 * count into *got). */
static void *copy_of(pk_one *s, held_buffers *held, PyObject *obj, const char *name, char type,
                     int ndim, Py_ssize_t count, Py_ssize_t *got) {
    void *data = grab(held, obj, name, type, 0, ndim);
    if (!data) return NULL;
    Py_buffer *view = &held->views[held->count - 1];
    Py_ssize_t items = view->len / 8;
    if (count >= 0 && items != count) {
        PyErr_Format(PyExc_ValueError, "%s: %zd entries expected, not %zd", name, count, items);
        return NULL;
    }
    void *copy = malloc((size_t)(items > 0 ? items : 1) * 8);
    if (!copy) {
        PyErr_NoMemory();
        return NULL;
    }
    memcpy(copy, data, (size_t)items * 8);
    s->owned[s->n_owned++] = copy;
    if (got) *got = items;
    return copy;
}

/* The blocks of model c: each leg's unknown joints (and the head's when inverse) not shared
 * with another block; the shared ones join the platform's 6 columns in the core. -2 when out
 * of memory. */
static int find_blocks(pk_one *s, const pk_chain *c, pk_blocks *bk) {
    ptrdiff_t count = c->n_legs + (c->inverse ? 1 : 0);
    int64_t *start = malloc(sizeof(int64_t) * (size_t)(count + 1));
    int64_t *cols = malloc(sizeof(int64_t) * (size_t)(c->n + 1));
    int64_t *core = malloc(sizeof(int64_t) * (size_t)(c->n + 1));
    int64_t *owner = malloc(sizeof(int64_t) * (size_t)(c->n + 1));
    if (!start || !cols || !core || !owner) {
        free(start), free(cols), free(core), free(owner);
        return -2;
    }
    s->owned[s->n_owned++] = start;
    s->owned[s->n_owned++] = cols;
    s->owned[s->n_owned++] = core;
    for (ptrdiff_t a = 0; a < c->n; a++) owner[a] = a < 6 ? -2 : -1;  /* -2: core */
    for (int pass = 0; pass < 2; pass++) {  /* owners, then the blocks' own columns */
        ptrdiff_t used = 0, widest = 0;
        for (ptrdiff_t b = 0; b < count; b++) {
            start[b] = used;
            const int64_t *list = b < c->n_legs ? c->elements + c->offsets[b] : c->head;
            ptrdiff_t length = b < c->n_legs ? c->offsets[b + 1] - c->offsets[b] : c->n_head;
            for (ptrdiff_t i = 0; i < length; i++) {
                int64_t e = list[i];
                int64_t col = c->types[e] == 0 ? -1 : c->position[c->evar[e]];
                if (col < 0) continue;
                if (pass == 0) {
                    owner[col] = owner[col] == -1 || owner[col] == b ? b : -2;
                } else if (owner[col] == b) {
                    owner[col] = -3;  /* listed */
                    cols[used++] = col;
                }
            }
            if (used - start[b] > widest) widest = used - start[b];
        }
        start[count] = used;
        bk->widest = widest;
    }
    ptrdiff_t nc = 0;
    for (ptrdiff_t a = 0; a < c->n; a++)
        if (owner[a] == -2) core[nc++] = a;
    free(owner);
    bk->count = count;
    bk->start = start;
    bk->cols = cols;
    bk->core = core;
    bk->n_core = nc;
    return 0;
}

const char pk_chain_one_pack_doc[] =
    "chain_one_pack(frames, types, evar, elements, offsets, head, inv_position, dir_position,\n"
    "               length, inv_options, dir_options, u_home_inv, base, inv_rates, tool,\n"
    "               slides, signs, turns, turn_homes, act_turns, act_turn_homes, lower, upper,\n"
    "               act, wrist, far, u_home_dir, dir_rates, residual_rates, home_values,\n"
    "               singular_bound, max_coordinate, structured, empty, ndarray)\n\n"
    "A joint-chain machine's one-pose constants, copied into a capsule for chain_one_ik and\n"
    "chain_one_fk (machines/chain_one_native.py builds the arguments). wrist: (5,) turn\n"
    "variable, its home, tilt variable, its home, whether the turn reaches a quarter turn, or\n"
    "(0,) for none. structured: block elimination (else the dense solve of chain_rows).";

PyObject *pk_py_chain_one_pack(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    (void)take_chain;  /* chain_face.h's, unused here */
    if (check_count(nargs, 35, "chain_one_pack") < 0) return NULL;
    pk_one *s = calloc(1, sizeof(pk_one));
    if (!s) return PyErr_NoMemory();
    held_buffers held = {.count = 0};
    Py_ssize_t n_elem, n_leg_el, n_off, n_head, n_var, got;
    double *frames = copy_of(s, &held, args[0], "frames", 'd', 3, -1, &got);
    if (!frames) goto fail;
    n_elem = got / 16;
    int64_t *types = copy_of(s, &held, args[1], "types", 'i', 1, n_elem, NULL);
    int64_t *evar = types ? copy_of(s, &held, args[2], "evar", 'i', 1, n_elem, NULL) : NULL;
    int64_t *elements = evar ? copy_of(s, &held, args[3], "elements", 'i', 1, -1, &n_leg_el)
                             : NULL;
    int64_t *offsets = elements ? copy_of(s, &held, args[4], "offsets", 'i', 1, -1, &n_off)
                                : NULL;
    int64_t *head = offsets ? copy_of(s, &held, args[5], "head", 'i', 1, -1, &n_head) : NULL;
    int64_t *inv_pos = head ? copy_of(s, &held, args[6], "inv_position", 'i', 1, -1, &n_var)
                            : NULL;
    int64_t *dir_pos = inv_pos ? copy_of(s, &held, args[7], "dir_position", 'i', 1, n_var, NULL)
                               : NULL;
    if (!dir_pos) goto fail;
    let_go(&held);
    if (n_off < 1) {
        PyErr_SetString(PyExc_ValueError, "offsets: one entry at least");
        goto fail;
    }
    if (in_range(types, n_elem, 0, 3, "types") < 0
        || in_range(elements, n_leg_el, 0, n_elem, "elements") < 0
        || in_range(head, n_head, 0, n_elem, "head") < 0
        || in_range(offsets, n_off, 0, n_leg_el + 1, "offsets") < 0
        || in_range(inv_pos, n_var, 6, 6 + n_var, "inv_position") < 0
        || in_range(dir_pos, n_var, -1, 6 + n_var, "dir_position") < 0)
        goto fail;
    for (Py_ssize_t e = 0; e < n_elem; e++)
        if (types[e] != 0 && (evar[e] < 0 || evar[e] >= n_var)) {
            PyErr_Format(PyExc_ValueError, "evar[%zd] out of range", e);
            goto fail;
        }
    for (Py_ssize_t leg = 0; leg + 1 < n_off; leg++)
        if (offsets[leg + 1] < offsets[leg]) {
            PyErr_SetString(PyExc_ValueError, "offsets must not decrease");
            goto fail;
        }
    ptrdiff_t n_dir = 6;
    for (Py_ssize_t v = 0; v < n_var; v++)
        if (dir_pos[v] >= 0) n_dir++;
    for (Py_ssize_t v = 0; v < n_var; v++)
        if (dir_pos[v] >= n_dir) {
            PyErr_SetString(PyExc_ValueError, "dir_position: columns beyond the unknowns");
            goto fail;
        }
    double length = PyFloat_AsDouble(args[8]);
    if (length == -1.0 && PyErr_Occurred()) goto fail;
    pk_chain base_chain = {frames, types, evar, elements, offsets, inv_pos, head,
                           n_off - 1, n_var, 6 + n_var, n_head, length, 1};
    s->inv = base_chain;
    s->dir = base_chain;
    s->dir.position = dir_pos;
    s->dir.n = n_dir;
    s->dir.inverse = 0;
    s->m_dir = 6 * (n_off - 1);
    s->twists = n_leg_el + n_head + 1;
    double *opts[2];
    for (int i = 0; i < 2; i++) {
        opts[i] = copy_of(s, &held, args[9 + i], "options", 'd', 1, 7, NULL);
        if (!opts[i]) goto fail;
        let_go(&held);
        pk_chain_options *o = i == 0 ? &s->inv_o : &s->dir_o;
        o->max_iter = (int64_t)opts[i][0];
        o->xtol = opts[i][1], o->atol = opts[i][2], o->gtol = opts[i][3];
        o->stall = opts[i][4], o->residual_tol = opts[i][5], o->damping = opts[i][6];
    }
    Py_ssize_t n_s, n_t, n_at, n_act, n_w;
    s->u_home_inv = copy_of(s, &held, args[11], "u_home_inv", 'd', 1, 6 + n_var, NULL);
    s->base = s->u_home_inv ? copy_of(s, &held, args[12], "base", 'd', 1, 6, NULL) : NULL;
    s->inv_rates = s->base ? copy_of(s, &held, args[13], "inv_rates", 'd', 2, 6 * (6 + n_var),
                                     NULL) : NULL;
    if (!s->inv_rates) goto fail;
    let_go(&held);
    s->tool = PyFloat_AsDouble(args[14]);
    if (s->tool == -1.0 && PyErr_Occurred()) goto fail;
    s->slides = copy_of(s, &held, args[15], "slides", 'i', 1, -1, &n_s);
    s->signs = s->slides ? copy_of(s, &held, args[16], "signs", 'd', 1, n_s, NULL) : NULL;
    s->turns = s->signs ? copy_of(s, &held, args[17], "turns", 'i', 1, -1, &n_t) : NULL;
    s->turn_homes = s->turns ? copy_of(s, &held, args[18], "turn_homes", 'd', 1, n_t, NULL) : NULL;
    s->act_turns = s->turn_homes ? copy_of(s, &held, args[19], "act_turns", 'i', 1, -1, &n_at)
                                 : NULL;
    s->act_turn_homes = s->act_turns ? copy_of(s, &held, args[20], "act_turn_homes", 'd', 1,
                                               n_at, NULL) : NULL;
    s->lower = s->act_turn_homes ? copy_of(s, &held, args[21], "lower", 'd', 1, n_var, NULL)
                                 : NULL;
    s->upper = s->lower ? copy_of(s, &held, args[22], "upper", 'd', 1, n_var, NULL) : NULL;
    s->act = s->upper ? copy_of(s, &held, args[23], "act", 'i', 1, -1, &n_act) : NULL;
    double *wrist = s->act ? copy_of(s, &held, args[24], "wrist", 'd', 1, -1, &n_w) : NULL;
    if (!wrist) goto fail;
    let_go(&held);
    s->n_slides = n_s, s->n_turns = n_t, s->n_act_turns = n_at, s->n_act = n_act;
    if (in_range(s->slides, n_s, 6, 6 + n_var, "slides") < 0
        || in_range(s->turns, n_t, 6, 6 + n_var, "turns") < 0
        || in_range(s->act_turns, n_at, 0, n_var, "act_turns") < 0
        || in_range(s->act, n_act, 0, n_var, "act") < 0)
        goto fail;
    if (n_act < 1 || n_act > 64 || (n_w != 0 && n_w != 5)) {
        PyErr_SetString(PyExc_ValueError, "1 to 64 actuators; wrist (5,) or (0,)");
        goto fail;
    }
    s->wrist = n_w == 5;
    if (s->wrist) {
        s->w_turn = (int64_t)wrist[0], s->w_home = wrist[1], s->w_tilt = (int64_t)wrist[2];
        s->w_centre = wrist[3], s->wide = wrist[4] != 0.0;
        if (s->w_turn < 0 || s->w_turn >= n_var || s->w_tilt < 0 || s->w_tilt >= n_var) {
            PyErr_SetString(PyExc_ValueError, "wrist: variables out of range");
            goto fail;
        }
    }
    s->far = PyFloat_AsDouble(args[25]);
    if (s->far == -1.0 && PyErr_Occurred()) goto fail;
    s->u_home_dir = copy_of(s, &held, args[26], "u_home_dir", 'd', 1, n_dir, NULL);
    s->dir_rates = s->u_home_dir ? copy_of(s, &held, args[27], "dir_rates", 'd', 2,
                                           n_dir * n_act, NULL) : NULL;
    s->residual_rates = s->dir_rates ? copy_of(s, &held, args[28], "residual_rates", 'd', 2,
                                               s->m_dir * n_act, NULL) : NULL;
    s->home_values = s->residual_rates ? copy_of(s, &held, args[29], "home_values", 'd', 1,
                                                 n_var, NULL) : NULL;
    if (!s->home_values) goto fail;
    let_go(&held);
    s->singular_bound = PyFloat_AsDouble(args[30]);
    if (s->singular_bound == -1.0 && PyErr_Occurred()) goto fail;
    s->max_coordinate = PyFloat_AsDouble(args[31]);
    if (s->max_coordinate == -1.0 && PyErr_Occurred()) goto fail;
    s->structured = PyObject_IsTrue(args[32]);
    if (s->structured < 0) goto fail;
    int found_inv = find_blocks(s, &s->inv, &s->inv_b);
    int found_dir = found_inv == -2 ? -2 : find_blocks(s, &s->dir, &s->dir_b);
    if (found_inv == -2 || found_dir == -2) {
        PyErr_NoMemory();
        goto fail;
    }
    if (!PyType_Check(args[34]) || !PyCallable_Check(args[33])) {
        PyErr_SetString(PyExc_TypeError, "empty: numpy.empty; ndarray: numpy.ndarray");
        goto fail;
    }
    s->empty = Py_NewRef(args[33]);
    s->ndarray = Py_NewRef(args[34]);
    s->n_obj = PyLong_FromSsize_t(n_act);
    s->u_obj = PyLong_FromSsize_t(6 + n_var);
    s->six = PyLong_FromLong(6);
    if (!s->n_obj || !s->u_obj || !s->six) goto fail;
    PyObject *capsule = PyCapsule_New(s, CAPSULE, release_state);
    if (!capsule) goto fail;
    return capsule;
fail:
    let_go(&held);
    for (int i = 0; i < s->n_owned; i++) free(s->owned[i]);
    Py_XDECREF(s->empty);
    Py_XDECREF(s->ndarray);
    Py_XDECREF(s->n_obj);
    Py_XDECREF(s->u_obj);
    Py_XDECREF(s->six);
    free(s);
    return NULL;
}

const char pk_chain_one_structured_doc[] =
    "chain_one_structured(packed)\n\n"
    "Whether the packed machine's solves run by block elimination (else dense).";

PyObject *pk_py_chain_one_structured(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (check_count(nargs, 1, "chain_one_structured") < 0) return NULL;
    pk_one *s = capsule_state(args[0]);
    if (!s) return NULL;
    return PyBool_FromLong(s->structured);
}
