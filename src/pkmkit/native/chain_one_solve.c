/* The one-pose solve of native/chain_one.c: chain.c's Levenberg-Marquardt loop on one row
 * with each iteration's normal equations solved by block elimination (the Schur complement
 * onto the platform's 6 unknowns and the joints several legs share; chain_one.c's comment). */
#include "chain_one.h"

#include <math.h>

enum { OK = 0, NOT_CONVERGED = 3 };

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
ptrdiff_t pk_one_block_scratch(const pk_blocks *bk, ptrdiff_t n) {
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
void pk_one_solve_blocks(const pk_chain *c, const pk_blocks *bk, const double *known,
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

/* The blocks of model c: each leg's unknown joints (and the head's when inverse) not shared
 * with another block; the shared ones join the platform's 6 columns in the core. -2 when out
 * of memory. */
int pk_one_find_blocks(pk_one *s, const pk_chain *c, pk_blocks *bk) {
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

