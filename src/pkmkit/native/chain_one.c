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
 * rounding (not to the bit): results agree with the batch rows to ~1e-13 (tests). Joints
 * that several blocks share (the TriMule's psi1) join the platform's 6 columns in the core
 * (chain_one_solve.c), whose closure (chain_one_closure.c) writes each block's nonzero
 * Jacobian columns straight into the panels the solve reads (chain.c's operations: the same
 * bits). chain_one_pack.c packs the constants. chain_one_ik_jacobian (m.jacobian(x)) hands
 * the inverse's last Jacobian, when it was evaluated at the kept solution, to the velocity
 * kernel (chain_one_velocity.c). */
#include "chain_one.h"

#include <math.h>

enum { OK = 0 };

/* sum a_i b_i in order. */
static double dot(const double *a, const double *b, ptrdiff_t n) {
    double acc = 0.0;
    for (ptrdiff_t i = 0; i < n; i++) acc += a[i] * b[i];
    return acc;
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
    ptrdiff_t wide = pk_one_block_scratch(&s->inv_b, n);
    ptrdiff_t wide_dir = pk_one_block_scratch(&s->dir_b, n);
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
        pk_one_solve_blocks(c, bk, known, u, o, target, tool, &k->w, k->scratch, status, residual,
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

/* The answer's stroke test (strokes "flag" / "refuse"): within the strokes (widened by
 * STROKE_TOL) and not within EDGE_BAND of a widened limit. This solve agrees with the batch
 * rows to ~1e-13, not to the bit, so a value at the band's edge is the batch path's (it judged
 * otherwise: no StrokeWarning / OutOfStrokeError where the general path gave them, 3 of 20
 * edges on the Tripteor X7). The band is narrower than STROKE_TOL so that a joint sitting on
 * its limit (the Tripteor's Q5 at home, on its 0 deg limit) keeps the fast path. */
#define EDGE_BAND 5e-13
static int judged_within(const pk_one *s, const double *values) {
    for (ptrdiff_t v = 0; v < s->inv.n_var; v++)
        if (!(s->lower[v] + EDGE_BAND < values[v] && values[v] < s->upper[v] - EDGE_BAND))
            return 0;
    return 1;
}

static double turn_offset(double angle) { return PK_PI - pk_pymod(PK_PI - angle, 2.0 * PK_PI); }

/* The kind's closed-form starts (chain_starts.closed_starts, closed_direct_starts): the
 * TriMule's in chain_one_trimule.c, the Tripteor's in chain_one_tripteor.c; 1, or 0 where it
 * declines. */
static int closed_start(const pk_one *s, const double *target, double branch, double *u) {
    if (s->closed == PK_CLOSED_TRIPTEOR)
        return pk_one_tripteor_start(s->cl, s->tool, target, branch, u);
    return pk_one_trimule_start(s->cl, s->tool, target, branch, u);
}

static int closed_direct(const pk_one *s, const double *q, double *u) {
    return s->closed == PK_CLOSED_TRIPTEOR ? pk_one_tripteor_direct(s->cl, q, u)
                                           : pk_one_trimule_direct(s->cl, q, u);
}

/* The inverse of target (6,) (axis unit) from start (n,) or the first-order start (NULL):
 * 1 with values, u (the kept solution), *iterations, *residual filled; 0 where the batch path
 * must decide. machines/chain_one.py's _inverse_values and _nearest_branch, statement for
 * statement. */
static int inverse(const pk_one *s, const double *target, const double *start, pk_one_work *k,
                   double *values, double *u, int64_t *iterations, double *residual) {
    const pk_chain *c = &s->inv;
    ptrdiff_t n = c->n;
    int64_t status;
    if (start == NULL && s->closed && closed_start(s, target, 0.0, u)) {
        /* the kind's closed-form start (the batch path's, chain_starts.inverse_starts) */
    } else if (start == NULL) {
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
    int again = !first;
    if (again && start != NULL && s->closed && closed_start(s, target, 0.0, u)) {
        /* a caller's start failed: the closed-form start next (warm_starts._solve_from_closed) */
        solve(s, c, &s->inv_b, &s->inv_o, s->u_home_inv + 6, u, target, s->tool, k, &status,
              residual, iterations);
        again = !(status == OK && in_home_modes(s, u));
    }
    if (again) {
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
    if (s->closed) {  /* the other branch's closed form where it answers (the batch path's) */
        double b = sin(u[6 + s->w_tilt] - s->w_centre) < 0 ? 1.0 : -1.0;
        if (closed_start(s, target, b, k->du)) memcpy(other, k->du, (size_t)n * sizeof(double));
    }
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
        pk_chain_joint_move(rot, pos, t, q);
    }
    for (int i = 0; i < 3; i++) {
        pose[i] = pos[i] + s->tool * rot[3 * i + 2];
        pose[3 + i] = rot[3 * i + 2];
    }
}

/* 1 / sqrt(||J||_F^2 ||L^-1||_F^2) with L L' = J'J (chain_one_kernel._factor, _bound): J'J
 * summed over each row's nonzero entries (nz: n indices; dense_gram, the dense solve) or
 * block by block from the solve's panels (pk_one_gram), ||J||_F^2 its trace, L's diagonal
 * and L^-1's by reciprocals (multiplications: the rounding of the bound, which has a margin of
 * 2, not of the answer). L^-1 = X by rows, X_i = (e_i - sum_{p<i} L_ip X_p) / L_ii, each row's
 * entries independent sums (vectorised; the column-by-column substitution, one chain of
 * dependent subtractions per entry, was a fifth of the call, and the separate pass for
 * ||J||_F^2 another 7 %, session 32). */
static void dense_gram(const double *jac, ptrdiff_t m, ptrdiff_t n, double *low, int64_t *nz) {
    for (ptrdiff_t i = 0; i < n * n; i++) low[i] = 0.0;
    for (ptrdiff_t i = 0; i < m; i++) {
        const double *row = jac + i * n;
        ptrdiff_t count = 0;
        for (ptrdiff_t a = 0; a < n; a++)
            if (row[a] != 0.0) nz[count++] = a;
        for (ptrdiff_t p = 0; p < count; p++) {
            double v = row[nz[p]];
            double *target = low + nz[p] * n;
            for (ptrdiff_t t = 0; t <= p; t++) target[nz[t]] += v * row[nz[t]];
        }
    }
}

/* The bound from J'J's lower part in low (n x n; overwritten by L), inv (n x n) scratch. */
static double regular_bound(double *low, ptrdiff_t n, double *inv) {
    double fro = 0.0;
    for (ptrdiff_t j = 0; j < n; j++) fro += low[j * n + j];
    for (ptrdiff_t j = 0; j < n; j++) {  /* in place: J'J's lower part into L */
        double acc = low[j * n + j];
        for (ptrdiff_t p = 0; p < j; p++) acc -= low[j * n + p] * low[j * n + p];
        double d = acc > 0.0 ? 1.0 / sqrt(acc) : NAN;
        low[j * n + j] = d;
        for (ptrdiff_t i = j + 1; i < n; i++) {
            double t = low[i * n + j];
            for (ptrdiff_t p = 0; p < j; p++) t -= low[i * n + p] * low[j * n + p];
            low[i * n + j] = t * d;
        }
    }
    double total = 0.0;
    for (ptrdiff_t i = 0; i < n; i++) {
        double *xi = inv + i * n;
        for (ptrdiff_t c = 0; c <= i; c++) xi[c] = c == i ? 1.0 : 0.0;
        for (ptrdiff_t p = 0; p < i; p++) {  /* X_p is zero beyond its diagonal */
            double l = low[i * n + p];
            const double *xp = inv + p * n;
            for (ptrdiff_t c = 0; c <= p; c++) xi[c] -= l * xp[c];
        }
        double d = low[i * n + i];
        for (ptrdiff_t c = 0; c <= i; c++) {
            xi[c] *= d;
            total += xi[c] * xi[c];
        }
    }
    return 1.0 / sqrt(fro * total);
}

/* The direct model's default start into u: home moved to first order towards q (delta its
 * change, values every joint's), or home where that closes worse (chain_starts.default_start).
 * Always 1. */
static int first_order_start(const pk_one *s, const pk_chain *c, pk_one_work *k,
                             const double *values, const double *delta, double *u) {
    ptrdiff_t n_u = c->n, m = s->m_dir, n = s->n_act;
    double *pred = k->pred, *du = k->du;
    for (ptrdiff_t i = 0; i < n_u; i++) {
        double acc = 0.0;
        for (ptrdiff_t j = 0; j < n; j++) acc += delta[j] * s->dir_rates[i * n + j];
        du[i] = acc;
    }
    pk_chain_retract(s->u_home_dir, du, pred, n_u);
    k->w.m = m;
    memcpy(k->values2, values, (size_t)c->n_var * sizeof(double));
    if (s->structured)  /* the closure alone (chain_one_closure.c) */
        pk_one_evaluate(c, &s->dir_b, k->values2, pred, k->w.r, NULL, 0.0, k->scratch);
    else
        pk_chain_evaluate(c, k->values2, pred, k->w.r, k->w.jac, &k->w);
    double home_cost = 0.0;
    for (ptrdiff_t i = 0; i < m; i++) {
        double acc = 0.0;
        for (ptrdiff_t j = 0; j < n; j++) acc += delta[j] * s->residual_rates[i * n + j];
        home_cost += acc * acc;
    }
    int worse = !(dot(k->w.r, k->w.r, m) <= home_cost);
    memcpy(u, worse ? s->u_home_dir : pred, (size_t)n_u * sizeof(double));
    return 1;
}

/* The direct model of q (n_act,): 1 with pose (6,) and values (n_var,) filled, 0 where the
 * batch path must decide (chain_one_kernel.direct_one and chain_one.direct). */
static int direct(const pk_one *s, const double *q, int check, pk_one_work *k, double *values,
                  double *pose, int64_t *iterations) {
    const pk_chain *c = &s->dir;
    ptrdiff_t n_u = c->n, m = s->m_dir, n = s->n_act;
    double *u = k->u, delta[64];
    if (n > 64) return 0;
    memcpy(values, s->home_values, (size_t)c->n_var * sizeof(double));
    for (ptrdiff_t j = 0; j < n; j++) {
        values[s->act[j]] = q[j];
        delta[j] = q[j] - s->home_values[s->act[j]];
    }
    if (s->closed && n == 5 && closed_direct(s, q, k->u2)) {
        /* the kind's closed-form start (the batch path's, chain_starts.closed_direct_starts) */
        memcpy(u, k->u2, 6 * sizeof(double));
        for (ptrdiff_t v = 0; v < c->n_var; v++)
            if (c->position[v] >= 0) u[c->position[v]] = k->u2[6 + v];
    } else if (!first_order_start(s, c, k, values, delta, u)) {
        return 0;
    }
    int64_t status;
    double residual;
    double no_target[6] = {0, 0, 0, 0, 0, 0};
    solve(s, c, &s->dir_b, &s->dir_o, values, u, no_target, 0.0, k, &status, &residual,
          iterations);
    if (status != OK) return 0;
    for (ptrdiff_t v = 0; v < c->n_var; v++)
        if (c->position[v] >= 0) values[v] = u[c->position[v]];
    if (check) {  /* J'J from the solve's last Jacobian (at u: its panels), or evaluated */
        if (s->structured) {
            pk_one_gram(&s->dir_b, pk_one_panels(&s->dir_b, n_u, k->scratch, NULL), n_u, k->w.h);
        } else {
            k->w.m = m;
            memcpy(k->values2, values, (size_t)c->n_var * sizeof(double));
            pk_chain_evaluate(c, k->values2, u, k->w.r, k->w.jac, &k->w);
            dense_gram(k->w.jac, m, n_u, k->w.h, k->w.nz);
        }
        double bound = regular_bound(k->w.h, n_u, k->w.low);
        if (!(bound >= s->singular_bound)) return 0;
    }
    tool_pose(s, values, u, pose);
    return 1;
}

/* ---------------------------------------------------------------- the module face */

static pk_one *capsule_state(PyObject *capsule) {
    return PyCapsule_GetPointer(capsule, PK_ONE_CAPSULE);
}

/* x (6 plain numbers) into target, its axis normalised: 1; 0 where the batch path must decide
 * (not plain numbers, a zero axis); -1 with an error set. */
static int read_target(const pk_one *s, PyObject *obj, double *target) {
    double x[6];
    int got = pk_plain_numbers(obj, 6, s->max_coordinate, x); /* plain_numbers.c */
    if (got != PK_PLAIN_TAKEN) return got < 0 ? -1 : 0;
    double norm = sqrt(x[3] * x[3] + x[4] * x[4] + x[5] * x[5]);
    if (!(norm > 0)) return 0;
    for (int i = 0; i < 3; i++) {
        target[i] = x[i];
        target[3 + i] = x[3 + i] / norm;
    }
    return 1;
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
    double target[6];
    int got = read_target(s, args[1], target);
    if (got <= 0) return got < 0 ? NULL : Py_NewRef(Py_None);
    int ignore = PyObject_IsTrue(args[2]), full = PyObject_IsTrue(args[3]);
    if (ignore < 0 || full < 0) return NULL;
    pk_one_work k;
    if (work_alloc(s, &k) < 0) return PyErr_NoMemory();
    double *start = NULL;
    if (nargs == 5 && args[4] != Py_None) {
        start = k.pred;
        got = pk_plain_numbers(args[4], n, s->max_coordinate, start);
        if (got != PK_PLAIN_TAKEN) {
            free(k.memory);
            return got < 0 ? NULL : Py_NewRef(Py_None);
        }
    }
    double *values = k.values, *u = k.u, q[64];
    int64_t iterations = 0;
    double residual = NAN;
    int found;
    Py_BEGIN_ALLOW_THREADS
    found = inverse(s, target, start, &k, values, u, &iterations, &residual)
            && (ignore || judged_within(s, values)) && s->n_act <= 64;
    if (found)
        for (ptrdiff_t j = 0; j < s->n_act; j++) q[j] = values[s->act[j]];
    Py_END_ALLOW_THREADS
    PyObject *out = NULL;
    if (!found) {
        free(k.memory);
        Py_RETURN_NONE;
    }
    PyObject *qa = pk_new_array(q, s->n_act, 0);
    if (qa && full) {
        PyObject *ua = pk_new_array(u, 6 + nv, 0);
        PyObject *count = PyLong_FromLongLong((long long)iterations);
        PyObject *worst = PyFloat_FromDouble(residual);
        out = ua && count && worst ? PyTuple_New(4) : NULL;
        if (out) {  /* the tuple takes the four references */
            PyTuple_SET_ITEM(out, 0, qa);
            PyTuple_SET_ITEM(out, 1, ua);
            PyTuple_SET_ITEM(out, 2, count);
            PyTuple_SET_ITEM(out, 3, worst);
        } else {
            Py_DECREF(qa);
            Py_XDECREF(ua);
            Py_XDECREF(count);
            Py_XDECREF(worst);
        }
    } else {
        out = qa;
    }
    free(k.memory);
    return out;
}

const char pk_chain_one_fk_doc[] =
    "chain_one_fk(packed, q, ignore, check, counts=False)\n\n"
    "The direct model of one plain configuration q (n numbers) of the machine packed by\n"
    "chain_one_pack: the tool point and axis (6,), or None where the batch path must decide\n"
    "(machines/chain_one_native.py). check: certify the closure regular (else None).\n"
    "counts: (pose, the closure solve's iterations) instead (tests, bench).";

PyObject *pk_py_chain_one_fk(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 4 && nargs != 5) {
        PyErr_SetString(PyExc_TypeError, "chain_one_fk(packed, q, ignore, check, counts=False)");
        return NULL;
    }
    pk_one *s = capsule_state(args[0]);
    if (!s) return NULL;
    double q[64], pose[6];
    if (s->n_act > 64) Py_RETURN_NONE;
    int got = pk_plain_numbers(args[1], s->n_act, s->max_coordinate, q);
    if (got != PK_PLAIN_TAKEN) return got < 0 ? NULL : Py_NewRef(Py_None);
    int ignore = PyObject_IsTrue(args[2]), check = PyObject_IsTrue(args[3]);
    int counts = nargs == 5 ? PyObject_IsTrue(args[4]) : 0;
    if (ignore < 0 || check < 0 || counts < 0) return NULL;
    pk_one_work k;
    if (work_alloc(s, &k) < 0) return PyErr_NoMemory();
    int found;
    int64_t iterations = 0;
    Py_BEGIN_ALLOW_THREADS
    found = direct(s, q, check, &k, k.values, pose, &iterations) &&
            (ignore || judged_within(s, k.values));
    Py_END_ALLOW_THREADS
    free(k.memory);
    if (!found) Py_RETURN_NONE;
    if (!counts) return pk_new_array(pose, 6, 0);
    return Py_BuildValue("(NL)", pk_new_array(pose, 6, 0), (long long)iterations);
}

/* The legs' rows of the inverse model's Jacobian (6 L x n, row-major) from its panels. */
static void legs_dense(const pk_one *s, const double *panels, double *jac) {
    const pk_blocks *bk = &s->inv_b;
    const ptrdiff_t n = s->inv.n;
    memset(jac, 0, sizeof(double) * (size_t)(6 * s->inv.n_legs * n));
    for (ptrdiff_t b = 0; b < s->inv.n_legs; b++) {
        ptrdiff_t k = bk->start[b + 1] - bk->start[b];
        for (ptrdiff_t p = 0; p < bk->n_core + k; p++) {
            int64_t col = p < bk->n_core ? bk->core[p] : bk->cols[bk->start[b] + p - bk->n_core];
            for (int i = 0; i < 6; i++)
                jac[(6 * b + i) * n + col] = panels[b * bk->panel + 6 * p + i];
        }
    }
}

PyObject *pk_py_chain_one_ik_jacobian(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs < 5 || nargs > 7) {
        PyErr_SetString(PyExc_TypeError, "chain_one_ik_jacobian(packed, pack, x, threshold, "
                        "guard[, singular[, record]])");
        return NULL;
    }
    int singular = nargs == 5 ? 0 : PyObject_IsTrue(args[5]); /* -1: the check below */
    int record = nargs == 7 ? PyObject_IsTrue(args[6]) : 0;   /* the record layout alone */
    pk_one *s = capsule_state(args[0]);
    if (!s) return NULL;
    double threshold = PyFloat_AsDouble(args[3]), guard = PyFloat_AsDouble(args[4]);
    if (PyErr_Occurred()) return NULL;
    double target[6], q[64];
    int got = read_target(s, args[2], target);
    if (got <= 0) return got < 0 ? NULL : Py_NewRef(record ? Py_False : Py_None);
    pk_one_work k;
    if (work_alloc(s, &k) < 0) return PyErr_NoMemory();
    const ptrdiff_t n = s->inv.n;
    int64_t iterations = 0;
    double residual = NAN, *u = k.u;
    int found, fresh = 0;
    Py_BEGIN_ALLOW_THREADS
    found = inverse(s, target, NULL, &k, k.values, u, &iterations, &residual) && s->n_act <= 64;
    if (found) {
        for (ptrdiff_t j = 0; j < s->n_act; j++) q[j] = k.values[s->act[j]];
        if (s->structured) {  /* the last solve's panels, if at u */
            const double *last, *panels = pk_one_panels(&s->inv_b, n, k.scratch, &last);
            fresh = memcmp(last, u, (size_t)n * sizeof(double)) == 0;
            if (fresh) legs_dense(s, panels, k.w.jac);
        }
    }
    Py_END_ALLOW_THREADS
    PyObject *qa = found && !record ? pk_new_array(q, s->n_act, 0) : NULL, *answer = NULL;
    if (found && (qa || record)) { /* record: the array alone (q its last row) */
        answer = residual > guard ? Py_NewRef(Py_False)
                 : pk_one_velocity_array(args[1], u, threshold, fresh ? k.w.jac : NULL,
                                         s->inv.position, n, singular, record ? q : NULL);
        if (qa && answer) Py_SETREF(answer, PyTuple_Pack(2, qa, answer));
    }
    Py_XDECREF(qa);
    free(k.memory);
    return found || PyErr_Occurred() ? answer : Py_NewRef(record ? Py_False : Py_None);
}

const char pk_chain_one_structured_doc[] =
    "chain_one_structured(packed)\n\n"
    "Whether the packed machine's solves run by block elimination (else dense).";

PyObject *pk_py_chain_one_structured(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 1 && PyErr_Format(PyExc_TypeError, "chain_one_structured(packed)") == NULL) return NULL;
    pk_one *s = capsule_state(args[0]);
    if (!s) return NULL;
    return PyBool_FromLong(s->structured);
}
