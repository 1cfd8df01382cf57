/* The one-pose solve of native/chain_one.c: chain.c's Levenberg-Marquardt loop on one row
 * with each iteration's normal equations solved by block elimination (the Schur complement
 * onto the platform's 6 unknowns and the joints several legs share; chain_one.c's comment). */
#include "chain_one.h"

#include <math.h>

enum { OK = 0, NOT_CONVERGED = 3 };

/* ---------------------------------------------------------------- the structured solve */

/* Lower Cholesky factor of the k x k matrix a (row-major, lower part read) into low, its
 * diagonal holding the reciprocals 1 / L_jj (multiplications, not divisions, in the
 * substitutions: the divider's latency was a fifth of the solve); NaN where not positive
 * definite (chain.c's rule). */
static void factor(const double *a, double *low, ptrdiff_t k) {
    for (ptrdiff_t j = 0; j < k; j++) {
        double s = a[j * k + j];
        for (ptrdiff_t p = 0; p < j; p++) s -= low[j * k + p] * low[j * k + p];
        double inv = s > 0.0 ? 1.0 / sqrt(s) : NAN;
        low[j * k + j] = inv;
        for (ptrdiff_t i = j + 1; i < k; i++) {
            double t = a[i * k + j];
            for (ptrdiff_t p = 0; p < j; p++) t -= low[i * k + p] * low[j * k + p];
            low[i * k + j] = t * inv;
        }
    }
}

/* x <- L^-1 x for the columns of x (k x cols, row-major): factor's low. */
static void forward(const double *low, ptrdiff_t k, double *x, ptrdiff_t cols) {
    for (ptrdiff_t i = 0; i < k; i++) {
        double *xi = x + i * cols;
        for (ptrdiff_t p = 0; p < i; p++) {
            double l = low[i * k + p];
            const double *xp = x + p * cols;
            for (ptrdiff_t c = 0; c < cols; c++) xi[c] -= l * xp[c];
        }
        double inv = low[i * k + i];
        for (ptrdiff_t c = 0; c < cols; c++) xi[c] *= inv;
    }
}

/* x <- L^-T x (factor's low). */
static void backward(const double *low, ptrdiff_t k, double *x) {
    for (ptrdiff_t i = k - 1; i >= 0; i--) {
        double t = x[i];
        for (ptrdiff_t p = i + 1; p < k; p++) t -= low[p * k + i] * x[p];
        x[i] = t * low[i * k + i];
    }
}

/* a . b for 6-vectors, in pairs (independent additions). */
static inline double dot6(const double *a, const double *b) {
    return ((a[0] * b[0] + a[1] * b[1]) + (a[2] * b[2] + a[3] * b[3]))
           + (a[4] * b[4] + a[5] * b[5]);
}

/* The layout of the scratch: the core block A (nc x nc), its damped factor, the core's
 * right-hand side, every column's squared norm, then per block D_b, its factor L_b, B_b then
 * Y_b (k x nc), z_b (k); the closure's two sets of panels (the current point's and the
 * trial's: per block its core and own columns, 6 rows each, chain_one_closure.c), the turns'
 * cache (3 per element). */
typedef struct {
    double *a, *sl, *xp, *diag, *blocks, *panels, *trial, *cache, *last;
    ptrdiff_t per_block;
} layout;

static layout lay_out(const pk_blocks *bk, ptrdiff_t n, double *scratch) {
    ptrdiff_t nc = bk->n_core, w = bk->widest;
    layout l;
    l.a = scratch, l.sl = l.a + nc * nc, l.xp = l.sl + nc * nc, l.diag = l.xp + nc;
    l.blocks = l.diag + n;
    l.per_block = 2 * w * w + w * nc + w;
    l.panels = l.blocks + bk->count * l.per_block;
    l.trial = l.panels + bk->count * bk->panel;
    l.cache = l.trial + bk->count * bk->panel;
    l.last = l.cache + 3 * bk->n_elements;
    return l;
}

/* dot6(v, c) for the platform's column t of a leg's panel (chain_one_closure.c: -1 at row t for
 * t < 3, the rotation rows' entries at rows 3..5 for t >= 3, zero elsewhere): the same sum as
 * dot6 on the column with its zeros, to the bit (a zero product added to a partial sum leaves
 * it unchanged), a sixth of its products. */
static inline double platform_dot(const double *v, const double *panel, ptrdiff_t t) {
    if (t < 3) return v[t] * panel[7 * t];
    const double *c = panel + 6 * t + 3;
    return v[3] * c[0] + (v[4] * c[1] + v[5] * c[2]);
}

/* normal()'s sums for leg block b from its panel (its 6 rows by columns: the platform's read
 * where the closure writes them, -1 on rows 0..2 and the rotation rows' 3 x 3 on rows 3..5,
 * then the shared core columns and the own ones). */
static inline void leg_normal(const pk_blocks *bk, const double *panel, const double *rb,
                              ptrdiff_t b, double *grad, const layout *l, ptrdiff_t nc) {
    const ptrdiff_t w = bk->widest;
    const int64_t *core = bk->core, *cols = bk->cols + bk->start[b];
    ptrdiff_t k = bk->start[b + 1] - bk->start[b];
    const double *ct = panel, *ot = panel + 6 * nc;
    double *hbb = l->blocks + b * l->per_block, *y = hbb + 2 * w * w, *a = l->a;
    for (int p = 0; p < 3; p++) {
        double d = panel[7 * p];
        a[p * nc + p] += d * d;
        grad[p] += d * rb[p];
    }
    for (int p = 3; p < 6; p++) {
        const double *cp = panel + 6 * p + 3;
        for (int t = 3; t <= p; t++) {
            const double *c = panel + 6 * t + 3;
            a[p * nc + t] += cp[0] * c[0] + (cp[1] * c[1] + cp[2] * c[2]);
        }
        grad[p] += platform_dot(rb, panel, p);
    }
    for (ptrdiff_t p = 6; p < nc; p++) {
        const double *g = ct + 6 * p;
        for (ptrdiff_t t = 0; t < 6; t++) a[p * nc + t] += platform_dot(g, panel, t);
        for (ptrdiff_t t = 6; t <= p; t++) a[p * nc + t] += dot6(g, ct + 6 * t);
        grad[core[p]] += dot6(g, rb);
    }
    for (ptrdiff_t p = 0; p < k; p++) {
        const double *o = ot + 6 * p;
        for (ptrdiff_t t = 0; t <= p; t++) hbb[p * k + t] = dot6(o, ot + 6 * t);
        for (ptrdiff_t t = 0; t < 6; t++) y[p * nc + t] = platform_dot(o, panel, t);
        for (ptrdiff_t t = 6; t < nc; t++) y[p * nc + t] = dot6(o, ct + 6 * t);
        grad[cols[p]] = dot6(o, rb);
        l->diag[cols[p]] = hbb[p * k + p];
    }
}

/* The normal equations' pieces at the Jacobian's panels (chain_one_closure.c) and the residual
 * r: A = J_C'J_C, per block D_b = J_b'J_b and B_b = J_b'J_C (own columns J_b), the gradient
 * J'r into grad and every column's squared norm into l.diag (zero for a column in no block: no
 * step). Sums by 6-row blocks: H, the gradient and the columns' norms are the dense loop's to
 * rounding. */
static inline void normal(const pk_blocks *bk, ptrdiff_t n_legs, const double *panels,
                          const double *r, ptrdiff_t n, double *grad, const layout *l,
                          ptrdiff_t nc) {
    const ptrdiff_t w = bk->widest;
    const int64_t *core = bk->core;
    for (ptrdiff_t p = 0; p < nc * nc; p++) l->a[p] = 0.0;
    for (ptrdiff_t c = 0; c < n; c++) grad[c] = l->diag[c] = 0.0;
    for (ptrdiff_t b = 0; b < bk->count; b++) {
        const double *panel = panels + b * bk->panel, *rb = r + 6 * b;
        if (b < n_legs) {
            leg_normal(bk, panel, rb, b, grad, l, nc);
            continue;
        }
        const int64_t *cols = bk->cols + bk->start[b];
        ptrdiff_t k = bk->start[b + 1] - bk->start[b];
        const double *ct = panel, *ot = panel + 6 * nc;
        double *hbb = l->blocks + b * l->per_block, *y = hbb + 2 * w * w;
        for (ptrdiff_t p = 0; p < nc; p++) {
            for (ptrdiff_t t = 0; t <= p; t++) l->a[p * nc + t] += dot6(ct + 6 * p, ct + 6 * t);
            grad[core[p]] += dot6(ct + 6 * p, rb);
        }
        for (ptrdiff_t p = 0; p < k; p++) {
            for (ptrdiff_t t = 0; t <= p; t++) hbb[p * k + t] = dot6(ot + 6 * p, ot + 6 * t);
            for (ptrdiff_t t = 0; t < nc; t++) y[p * nc + t] = dot6(ot + 6 * p, ct + 6 * t);
            grad[cols[p]] = dot6(ot + 6 * p, rb);
            l->diag[cols[p]] = hbb[p * k + p];
        }
    }
    for (ptrdiff_t p = 0; p < nc; p++) l->diag[core[p]] = l->a[p * nc + p];
}

/* The damped Gauss-Newton step of pk_chain_rows, step = -(H + lam (diag H + floor))^-1 grad,
 * from normal()'s pieces, by the Schur complement onto the core columns (the platform's 6
 * and the joints shared by several blocks): per block b D_b = L_b L_b', Y_b = L_b^-1 B_b,
 * z_b = L_b^-1 g_b; S = A - sum Y_b'Y_b; x_C = S^-1 (g_C - sum Y_b'z_b); x_b = L_b^-T (z_b -
 * Y_b x_C). */
static inline void block_step(const pk_blocks *bk, ptrdiff_t n, const double *grad,
                              double lam, double *step, const layout *l, ptrdiff_t nc) {
    const ptrdiff_t w = bk->widest;
    const int64_t *core = bk->core;
    double *s = l->sl, *xp = l->xp;
    double dmax = 0.0;
    for (ptrdiff_t c = 0; c < n; c++)
        if (l->diag[c] > dmax) dmax = l->diag[c];
    double floor_ = 1e-9 * dmax + 1e-300;
    for (ptrdiff_t c = 0; c < n; c++) step[c] = -(grad[c] / (lam * (l->diag[c] + floor_)));
    for (ptrdiff_t p = 0; p < nc; p++) {  /* the upper part too (zeros, never read) */
        for (ptrdiff_t t = 0; t < p; t++) s[p * nc + t] = l->a[p * nc + t];
        for (ptrdiff_t t = p + 1; t < nc; t++) s[p * nc + t] = 0.0;
        s[p * nc + p] = l->a[p * nc + p] + lam * (l->a[p * nc + p] + floor_);
        xp[p] = grad[core[p]];
    }
    for (ptrdiff_t b = 0; b < bk->count; b++) {
        const int64_t *cols = bk->cols + bk->start[b];
        ptrdiff_t k = bk->start[b + 1] - bk->start[b];
        double *hbb = l->blocks + b * l->per_block, *lbb = hbb + w * w;
        double *y = lbb + w * w, *z = y + w * nc;
        for (ptrdiff_t p = 0; p < k; p++) {
            hbb[p * k + p] += lam * (hbb[p * k + p] + floor_);
            z[p] = grad[cols[p]];
        }
        factor(hbb, lbb, k);
        forward(lbb, k, y, nc);
        forward(lbb, k, z, 1);
        for (ptrdiff_t q = 0; q < k; q++) {  /* S -= Y'Y, xp -= Y'z: row by row of Y */
            const double *yq = y + q * nc;
            for (ptrdiff_t p = 0; p < nc; p++) {  /* whole rows (vectorised; lower part read) */
                double v = yq[p];
                for (ptrdiff_t t = 0; t < nc; t++) s[p * nc + t] -= v * yq[t];
                xp[p] -= v * z[q];
            }
        }
    }
    factor(s, s, nc);  /* in place: each entry read before it is written */
    forward(s, nc, xp, 1);
    backward(s, nc, xp);
    for (ptrdiff_t p = 0; p < nc; p++) step[core[p]] = -xp[p];
    for (ptrdiff_t b = 0; b < bk->count; b++) {
        const int64_t *cols = bk->cols + bk->start[b];
        ptrdiff_t k = bk->start[b + 1] - bk->start[b];
        double *lbb = l->blocks + b * l->per_block + w * w;
        double *y = lbb + w * w, *z = y + w * nc;
        for (ptrdiff_t p = 0; p < k; p++) {
            double acc = z[p];
            for (ptrdiff_t t = 0; t < nc; t++) acc -= y[p * nc + t] * xp[t];
            z[p] = acc;
        }
        backward(lbb, k, z);
        for (ptrdiff_t p = 0; p < k; p++) step[cols[p]] = -z[p];
    }
}

/* Doubles of the solve's scratch (layout). */
ptrdiff_t pk_one_block_scratch(const pk_blocks *bk, ptrdiff_t n) {
    layout l = lay_out(bk, n, NULL);
    return 2 * bk->n_core * bk->n_core + bk->n_core + n + bk->count * l.per_block
           + 2 * bk->count * bk->panel + 3 * bk->n_elements + n;
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
    double *values = w->values, *r = w->r, *r_new = w->r_new;
    double *u_new = w->u_new, *step = w->step, *grad = w->grad;
    layout l = lay_out(bk, n, scratch);
    double *jac = l.panels, *j_new = l.trial;  /* the Jacobian by its blocks' panels */
    const ptrdiff_t cells = bk->count * bk->panel;
    *iterations = 0;
    *residual = NAN;
    for (ptrdiff_t i = 0; i < n; i++)
        if (!isfinite(u[i])) {
            *status = 4;
            return;
        }
    memcpy(values, known, (size_t)c->n_var * sizeof(double));
    pk_one_panels_init(c, bk, jac);
    pk_one_panels_init(c, bk, j_new);
    for (ptrdiff_t i = 0; i < 3 * bk->n_elements; i++) l.cache[i] = NAN;
    pk_one_closure(c, bk, values, u, r, jac, target, tool, l.cache);
    double cost = 0.5 * dot(r, r, m);
    /* x - x is 0 for a finite x, NaN else (the panels hold every entry of the Jacobian that is
     * not a structural zero): eight independent sums, vectorised */
    double spread[8] = {0, 0, 0, 0, 0, 0, 0, 0}, spread_all = 0.0;
    ptrdiff_t i8 = 0;
    for (; i8 + 8 <= cells; i8 += 8)
        for (int j = 0; j < 8; j++) spread[j] += jac[i8 + j] - jac[i8 + j];
    for (; i8 < cells; i8++) spread[0] += jac[i8] - jac[i8];
    for (int j = 0; j < 8; j++) spread_all += spread[j];
    if (!(isfinite(cost) && spread_all == 0.0)) {
        *status = 4;
        return;
    }
    *status = NOT_CONVERGED;
    double lam = o->damping;
    double checkpoint = cost;
    int64_t count = 0;
    int stopped = 0;
    for (int64_t it = 0; it < o->max_iter; it++) {
        if (bk->n_core == 6)  /* the platform alone: the sums' bounds known (unrolled) */
            normal(bk, c->n_legs, jac, r, n, grad, &l, 6);
        else
            normal(bk, c->n_legs, jac, r, n, grad, &l, bk->n_core);
        /* chain.c's test, biggest cosine > gtol with biggest the largest of 0 and the columns'
         * (NaN skipped), decided at the first column above gtol */
        int moving = 0.0 > o->gtol;
        if (!(cost <= 0.5 * o->atol * o->atol))
            for (ptrdiff_t a = 0; a < n && !moving; a++)
                moving = fabs(grad[a]) / sqrt(l.diag[a] * (2.0 * cost)) > o->gtol;
        if (cost <= 0.5 * o->atol * o->atol || !moving) {
            stopped = 1;
            break;
        }
        if (bk->n_core == 6)
            block_step(bk, n, grad, lam, step, &l, 6);
        else
            block_step(bk, n, grad, lam, step, &l, bk->n_core);
        pk_chain_retract(u, step, u_new, n);
        pk_one_closure(c, bk, values, u_new, r_new, j_new, target, tool, l.cache);
        double cost_new = 0.5 * dot(r_new, r_new, m);
        int accept = pk_lm_accept(cost, cost_new, &lam);
        count += 1;
        if (accept) {
            memcpy(u, u_new, (size_t)n * sizeof(double));
            memcpy(r, r_new, (size_t)m * sizeof(double));
            double *swap = jac;  /* the new Jacobian is the current one */
            jac = j_new;
            j_new = swap;
            cost = cost_new;
        }
        if (pk_lm_done(o, accept, step, u, n, lam, cost, count, &checkpoint)) {
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
    if (jac != l.panels) memcpy(l.panels, jac, sizeof(double) * (size_t)cells);
    memcpy(l.last, u, (size_t)n * sizeof(double));
}

/* The panels in scratch: after pk_one_solve_blocks the Jacobian at the returned u (its last
 * accepted evaluation, the same bits as an evaluation there), after pk_one_evaluate u's;
 * *last (NULL: not wanted) that u, kept by pk_one_solve_blocks. */
double *pk_one_panels(const pk_blocks *bk, ptrdiff_t n, double *scratch, const double **last) {
    layout l = lay_out(bk, n, scratch);
    if (last) *last = l.last;
    return l.panels;
}

/* The closure's residual r and panels at u alone (values filled), in scratch's panels. */
double *pk_one_evaluate(const pk_chain *c, const pk_blocks *bk, double *values,
                        const double *u, double *r, const double *target, double tool,
                        double *scratch) {
    layout l = lay_out(bk, c->n, scratch);
    for (ptrdiff_t i = 0; i < c->n; i++) l.last[i] = NAN;  /* not a solve's */
    pk_one_panels_init(c, bk, l.panels);
    for (ptrdiff_t i = 0; i < 3 * bk->n_elements; i++) l.cache[i] = NAN;
    pk_one_closure(c, bk, values, u, r, l.panels, target, tool, l.cache);
    return l.panels;
}

/* The lower part of J'J (n x n, row-major, the upper part zero) from the panels: per block the
 * products of its columns (core and own) summed block after block. */
void pk_one_gram(const pk_blocks *bk, const double *panels, ptrdiff_t n, double *h) {
    const ptrdiff_t nc = bk->n_core;
    memset(h, 0, sizeof(double) * (size_t)(n * n));
    for (ptrdiff_t b = 0; b < bk->count; b++) {
        const double *panel = panels + b * bk->panel;
        ptrdiff_t k = bk->start[b + 1] - bk->start[b];
        for (ptrdiff_t p = 0; p < nc + k; p++) {
            int64_t gp = p < nc ? bk->core[p] : bk->cols[bk->start[b] + p - nc];
            for (ptrdiff_t t = 0; t < nc + k; t++) {
                int64_t gt = t < nc ? bk->core[t] : bk->cols[bk->start[b] + t - nc];
                if (gt <= gp) h[gp * n + gt] += dot6(panel + 6 * p, panel + 6 * t);
            }
        }
    }
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
    return pk_one_closure_plan(s, c, bk);
}

