/* The velocity model of a joint-chain machine at one configuration, in one call from Python
 * (issue 22 section 1; machines/chain_one_velocity.py): at a given inverse solution u =
 * (platform pose, every joint variable), the closure's Jacobian (chain.c's evaluate) with
 * respect to the platform, the passive joints and the legs' actuators; the closure rates
 * dU = -C_U^+ C_q by a QR of C_U that exploits its blocks; the tool twist per actuator J (6, n)
 * and its homogenised copy, J's singular values (svd.c) and condition number; the lower bound
 * 1 / (|C_U|_F |C_U^+|_F) of sigma_min / sigma_max of C_U that certifies the closure regular.
 *
 * Blocks: the rows of a leg involve the platform, the leg's own joints and any joint it shares
 * with another leg (the TriMule's legs share their base pivot). A column of a joint met in one
 * leg only is that leg's *local* column; the platform's and the shared joints' are *global*.
 * Householder reflections on each leg's 6 rows triangularise its local columns (R_l, and S_l
 * on the global columns), the rows left over (6 - p_l per leg, zero on every local column)
 * are triangularised on the global columns (R_g): the QR of C_U with its columns permuted,
 * each reflection touching 6 rows. The right-hand sides (C_q) are reflected along, so
 * R_g dU_g = -b_g and R_l dU_l = -b_l - S_l dU_g give the least-squares solution (backward
 * stable, as the batch path's pseudo-inverse: equal to it to rounding x the closure's
 * condition number). |C_U^+|_F = |R^-1|_F with R^-1 = [[D^-1, -D^-1 S R_g^-1], [0, R_g^-1]].
 *
 * Layout: each leg's 6 rows are gathered into a compact column-major panel (its local
 * columns, the global ones, the legs' actuators') whose reflections run on fixed 6-row loops
 * and skip the columns zero on the leg's rows; the rows left go to one panel for R_g; every
 * triangular solve (the rates, R_g^-1, each leg's rows of R^-1) runs row by row over all its
 * right-hand sides at once (independent sums and divisions).
 *
 * Python face: chain_velocity_pack(...) -> a capsule of the machine's constants (copied) and
 * scratch, built once per machine; chain_one_velocity(pack, u, out) -> the bound (a float),
 * out filled; chain_one_jacobian(pack, u, threshold) -> a new array (None, False), the form
 * m.jacobian(x) calls on the C inverse's solution array. Holds the GIL (the scratch is the
 * capsule's: a few microseconds of work). */
#include "chain_face.h"

#define CAPSULE "pkmkit.native.chain_one_velocity"

/* chain_one_velocity_doc.c: the Python face's docstrings */
extern const char pk_chain_velocity_pack_doc[], pk_chain_one_velocity_doc[];
extern const char pk_chain_one_jacobian_doc[];
PyObject *pk_one_velocity_array(PyObject *pack, const double *u, double threshold,
                                const double *given, const int64_t *given_position,
                                ptrdiff_t given_n, int singular, const double *q);

/* svd.c: the singular values of one small matrix (k <= 6), round-robin Jacobi */
void pk_singular_values_fast(const double *mat, ptrdiff_t r, ptrdiff_t c, double *out);
PyObject *pk_numpy_empty(void); /* velocity.c: numpy.empty */

typedef struct {
    pk_chain c;               /* position: column of each variable in the closure's Jacobian */
    pk_chain_work w;
    ptrdiff_t n_u, n_loop, n_act, n_head, n_global, n_elem;
    double tool;
    const int64_t *head_position, *loop_columns;
    const int64_t *slides, *turns; /* places in u of the legs' slides and revolute joints */
    const double *signs, *homes;   /* their home signs and values */
    ptrdiff_t n_slides, n_turns;
    int64_t *leg_cols;        /* (L, 6) each leg's local columns */
    int64_t *leg_count;       /* (L,) */
    int64_t *global_cols;     /* (n_global,) */
    double *values, *full_u, *r, *jac, *du, *rg_inv, *head_tw, *work, *norms;
    double *panels;           /* (L, 6 + n_u + n_loop, 6) each leg's columns (closure_rates) */
    double *rest;             /* (n_u + n_loop, 6L) the rows left by the legs' reflections */
    double *solve;            /* right-hand sides: (n_u, n_u + n_loop), (6, 6 + n_u + 32) */
    ptrdiff_t size;           /* 12 n + min(6, n) + 1 + (n_u - 6) n */
    int64_t *head_col;
    void *memory;             /* every array above, one allocation */
    void *owned[14];          /* the copied arrays */
} chain_velocity;

static void pack_free(PyObject *capsule) {
    chain_velocity *v = PyCapsule_GetPointer(capsule, CAPSULE);
    if (v) {
        for (int i = 0; i < 14; i++) free(v->owned[i]);
        free(v->memory);
        free(v);
    }
}

/* Householder QR of the columns 0..np-1 of a column-major panel a (column j at a + j * ld,
 * rows 0..nr-1), the reflections applied to the panel's columns rest (nrest) too; R left in
 * place (a[i + j * ld], i <= j). 0 where a pivot column is zero. */
static int reflect(double *a, ptrdiff_t ld, ptrdiff_t nr, ptrdiff_t np, const int64_t *rest,
                   ptrdiff_t nrest) {
    for (ptrdiff_t j = 0; j < np; j++) {
        double *col = a + j * ld;
        double norm = 0.0;
        for (ptrdiff_t i = j; i < nr; i++) norm += col[i] * col[i];
        norm = sqrt(norm);
        if (!(norm > 0.0)) return 0;
        double alpha = col[j] >= 0 ? -norm : norm;
        double v0 = col[j] - alpha;
        double vtv = v0 * v0;
        for (ptrdiff_t i = j + 1; i < nr; i++) vtv += col[i] * col[i];
        col[j] = v0;
        double scale = 2.0 / vtv;
        for (ptrdiff_t k = j + 1; k < np + nrest; k++) {
            double *other = a + (k < np ? k : rest[k - np]) * ld;
            double s = 0.0;
            for (ptrdiff_t i = j; i < nr; i++) s += col[i] * other[i];
            s *= scale;
            for (ptrdiff_t i = j; i < nr; i++) other[i] -= s * col[i];
        }
        col[j] = alpha;
    }
    return 1;
}

/* reflect on a leg's panel (6 rows, leading dimension 6) with the Householder vector held
 * on all 6 rows (zeros above the pivot): fixed-length loops the compiler unrolls, the same
 * sums and updates as reflect's (a zero term adds +-0.0, a zero update subtracts it). */
static int reflect_leg(double *a, ptrdiff_t np, const int64_t *rest, ptrdiff_t nrest) {
    for (ptrdiff_t j = 0; j < np; j++) {
        double *col = a + 6 * j, h[6];
        double norm = 0.0;
        for (ptrdiff_t i = j; i < 6; i++) norm += col[i] * col[i];
        norm = sqrt(norm);
        if (!(norm > 0.0)) return 0;
        double alpha = col[j] >= 0 ? -norm : norm;
        double v0 = col[j] - alpha;
        double vtv = v0 * v0;
        for (ptrdiff_t i = j + 1; i < 6; i++) vtv += col[i] * col[i];
        for (int i = 0; i < 6; i++) h[i] = i < j ? 0.0 : col[i];
        h[j] = v0;
        double scale = 2.0 / vtv;
        for (ptrdiff_t k = j + 1; k < np + nrest; k++) {
            double *other = a + 6 * (k < np ? k : rest[k - np]);
            double s = 0.0;
            for (int i = 0; i < 6; i++) s += h[i] * other[i];
            s *= scale;
            for (int i = 0; i < 6; i++) other[i] -= s * h[i];
        }
        col[j] = alpha;
    }
    return 1;
}

/* x (np, w) row-major = R^-1 x in place for the upper-triangular R (np, np) of a
 * column-major panel: row by row from the last, each row's w columns at once (independent
 * sums and divisions, each column's in the order of its own back substitution). */
static void solve_rows(const double *a, ptrdiff_t ld, ptrdiff_t np, double *x, ptrdiff_t w) {
    for (ptrdiff_t i = np - 1; i >= 0; i--) {
        double *xi = x + i * w;
        for (ptrdiff_t k = i + 1; k < np; k++) {
            const double r = a[i + k * ld], *xk = x + k * w;
            for (ptrdiff_t c = 0; c < w; c++) xi[c] -= r * xk[c];
        }
        const double d = a[i + i * ld];
        for (ptrdiff_t c = 0; c < w; c++) xi[c] /= d;
    }
}

/* The tool frame walked along the head from the platform pose u[:6] (chain_kernel._head_walk
 * with the head actuators' places): rot (3, 3), pos (3,); the head actuators' spatial twists
 * into v->head_tw, their actuator index into v->head_col. Returns their count. */
static ptrdiff_t head_walk(const chain_velocity *v, const double *u, double *rot, double *pos) {
    const pk_chain *c = &v->c;
    double tmp[9];
    pk_chain_rotvec_matrix(u[3], u[4], u[5], rot);
    for (int i = 0; i < 3; i++) pos[i] = u[i];
    ptrdiff_t n_twist = 0;
    for (ptrdiff_t idx = 0; idx < v->n_head; idx++) {
        int64_t e = c->head[idx];
        pk_chain_apply_frame(rot, pos, c->frames + 16 * e, tmp);
        int64_t type = c->types[e];
        if (type == 0) continue;
        int64_t var = c->evar[e];
        int64_t col = v->head_position[var];
        double q = v->values[var];
        if (col >= 0) {
            pk_chain_joint_twist(rot, pos, type, v->head_tw + 6 * n_twist);
            v->head_col[n_twist++] = col;
        }
        pk_chain_joint_move(rot, pos, type, q);
    }
    return n_twist;
}

/* Column c of J (6, n): the velocity v + w x point and w of a spatial twist. */
static void point_column(const double *twist, const double *point, double *jac, ptrdiff_t n,
                         ptrdiff_t c) {
    double w0 = twist[3], w1 = twist[4], w2 = twist[5];
    jac[0 * n + c] = twist[0] + (w1 * point[2] - w2 * point[1]);
    jac[1 * n + c] = twist[1] + (w2 * point[0] - w0 * point[2]);
    jac[2 * n + c] = twist[2] + (w0 * point[1] - w1 * point[0]);
    jac[3 * n + c] = w0;
    jac[4 * n + c] = w1;
    jac[5 * n + c] = w2;
}

/* Each leg's 6 rows of the closure's Jacobian (jac: row-major, leading dimension ld, column
 * at[col] of each of the kernel's columns col) gathered into its panel (column-major, 6
 * rows): its local columns, then every global column, then the leg actuators' (a column the
 * leg's rows do not involve copied as zeros and left out of the reflections: rest, nrest);
 * adds the squares of C_U's entries on those rows to *fro. */
static ptrdiff_t gather(const chain_velocity *v, const double *jac, ptrdiff_t ld,
                        const int64_t *at, ptrdiff_t leg, double *panel, int64_t *rest,
                        double *fro) {
    const ptrdiff_t n_g = v->n_global, p = v->leg_count[leg];
    const int64_t *piv = v->leg_cols + 6 * leg;
    const double *rows = jac + 6 * leg * ld;
    double sum = *fro;
    for (ptrdiff_t j = 0; j < p; j++)
        for (int i = 0; i < 6; i++) {
            double x = rows[i * ld + at[piv[j]]];
            panel[6 * j + i] = x;
            sum += x * x;
        }
    ptrdiff_t nrest = 0;
    for (ptrdiff_t g = 0; g < n_g + v->n_loop; g++) {
        ptrdiff_t col = at[g < n_g ? v->global_cols[g] : v->n_u + g - n_g];
        double *dst = panel + 6 * (p + g);
        int nonzero = 0;
        for (int i = 0; i < 6; i++) {
            double x = rows[i * ld + col];
            dst[i] = x;
            nonzero |= x != 0.0;
            if (g < n_g) sum += x * x;
        }
        if (nonzero) rest[nrest++] = p + g;
    }
    *fro = sum;
    return nrest;
}

/* The closure rates du (n_u, n_loop) from jac, ld, at (gather's; module comment); the bound, 0.0
 * where a pivot vanishes or too few rows are left (the caller takes the batch path). Each
 * leg's panel keeps R_l, S_l and its right-hand sides; v->rest (rows left, column-major with
 * leading dimension 6L) R_g and its right-hand sides. */
static double closure_rates(chain_velocity *v, const double *jac, ptrdiff_t ld,
                            const int64_t *at) {
    const pk_chain *c = &v->c;
    const ptrdiff_t n_loop = v->n_loop, n_g = v->n_global, ld_g = 6 * c->n_legs;
    const ptrdiff_t width = 6 * (6 + n_g + n_loop);
    double *rg = v->rest, fro = 0.0;
    int64_t rest[64];
    ptrdiff_t n_reduced = 0;
    for (ptrdiff_t leg = 0; leg < c->n_legs; leg++) {
        double *panel = v->panels + leg * width;
        ptrdiff_t p = v->leg_count[leg];
        ptrdiff_t nrest = gather(v, jac, ld, at, leg, panel, rest, &fro);
        if (!reflect_leg(panel, p, rest, nrest)) return 0.0;
        for (ptrdiff_t i = p; i < 6; i++, n_reduced++) /* the rows left */
            for (ptrdiff_t g = 0; g < n_g + n_loop; g++)
                rg[g * ld_g + n_reduced] = panel[6 * (p + g) + i];
    }
    if (n_reduced < n_g) return 0.0;
    for (ptrdiff_t k = 0; k < n_loop; k++) rest[k] = n_g + k;
    if (!reflect(rg, ld_g, n_reduced, n_g, rest, n_loop)) return 0.0;
    /* global unknowns: R_g du_g = -b_g; then each leg's: R_l du_l = -b_l - S_l du_g */
    double *x = v->solve, *y = v->solve + n_g * (n_g > n_loop ? n_g : n_loop);
    for (ptrdiff_t i = 0; i < n_g; i++)
        for (ptrdiff_t k = 0; k < n_loop; k++) x[i * n_loop + k] = -rg[(n_g + k) * ld_g + i];
    solve_rows(rg, ld_g, n_g, x, n_loop);
    for (ptrdiff_t i = 0; i < n_g; i++)
        for (ptrdiff_t k = 0; k < n_loop; k++)
            v->du[v->global_cols[i] * n_loop + k] = x[i * n_loop + k];
    for (ptrdiff_t leg = 0; leg < c->n_legs; leg++) {
        const double *panel = v->panels + leg * width;
        const int64_t *piv = v->leg_cols + 6 * leg;
        ptrdiff_t p = v->leg_count[leg];
        for (ptrdiff_t i = 0; i < p; i++) {
            double *yi = y + i * n_loop;
            for (ptrdiff_t k = 0; k < n_loop; k++) yi[k] = -panel[6 * (p + n_g + k) + i];
            for (ptrdiff_t g = 0; g < n_g; g++) {
                const double sg = panel[6 * (p + g) + i], *xg = x + g * n_loop;
                for (ptrdiff_t k = 0; k < n_loop; k++) yi[k] -= sg * xg[k];
            }
        }
        solve_rows(panel, 6, p, y, n_loop);
        for (ptrdiff_t i = 0; i < p; i++)
            for (ptrdiff_t k = 0; k < n_loop; k++) v->du[piv[i] * n_loop + k] = y[i * n_loop + k];
    }
    /* |R^-1|_F^2: R_g^-1, then each leg's rows of R^-1, R_l^-1 [I, -S_l R_g^-1] */
    double total = 0.0;
    double *inv = v->rg_inv; /* R_g^-1 (n_g, n_g) */
    for (ptrdiff_t i = 0; i < n_g * n_g; i++) inv[i] = 0.0;
    for (ptrdiff_t i = 0; i < n_g; i++) inv[i * n_g + i] = 1.0;
    solve_rows(rg, ld_g, n_g, inv, n_g);
    for (ptrdiff_t i = 0; i < n_g * n_g; i++) total += inv[i] * inv[i];
    for (ptrdiff_t leg = 0; leg < c->n_legs; leg++) {
        const double *panel = v->panels + leg * width;
        ptrdiff_t p = v->leg_count[leg], w = p + n_g;
        for (ptrdiff_t i = 0; i < p; i++) {
            double *yi = y + i * w;
            for (ptrdiff_t j = 0; j < w; j++) yi[j] = j == i ? 1.0 : 0.0;
            for (ptrdiff_t g = 0; g < n_g; g++) { /* S_l R_g^-1, R_g^-1 upper triangular */
                const double sg = panel[6 * (p + g) + i], *row = inv + g * n_g;
                if (sg != 0.0)
                    for (ptrdiff_t j = g; j < n_g; j++) yi[p + j] += sg * row[j];
            }
        }
        solve_rows(panel, 6, p, y, w);
        for (ptrdiff_t i = 0; i < p * w; i++) total += y[i] * y[i];
    }
    double bound = 1.0 / sqrt(fro * total);
    return bound > 0.0 ? bound : 0.0; /* NaN (a non-finite entry) refused too */
}

/* The velocity model at u (6 + n_var): out = [J (6, n) | J_homogeneous (6, n) | singular
 * values (min(6, n)) | condition | passive rates (n_u - 6, n)] (the singular values and
 * the condition NaN unless `singular`: singular_stage fills them later); returns the bound
 * (0.0: out not filled), or -1.0 where u is not in the legs' home assembly modes (each slide of its
 * home sign, each revolute leg joint within a quarter turn of home: chain_one_kernel.
 * in_home_modes), where the batch path's direct model may reach another closure. */
/* The singular stage: J_homogeneous's singular values and condition number into out, from the
 * J_homogeneous in out (velocity's layout). */
static void singular_stage(chain_velocity *v, double *out) {
    const ptrdiff_t n = v->n_act, k = n < 6 ? n : 6;
    double *sv = out + 12 * n;
    if (n <= 6) /* round-robin Jacobi (its work holds 6 x 6) */
        pk_singular_values_fast(out + 6 * n, 6, n, sv);
    else
        pk_singular_values_one(out + 6 * n, 6, n, sv, v->work, v->norms);
    sv[k] = sv[0] / sv[k - 1];
}

static double velocity(chain_velocity *v, const double *u, double *out, int singular,
                       const double *given, const int64_t *given_position, ptrdiff_t given_n,
                       ptrdiff_t rates_at) { /* the passive rates at out + rates_at */
    const pk_chain *c = &v->c;
    const ptrdiff_t n = v->n_act, n_loop = v->n_loop, n_u = v->n_u;
    for (ptrdiff_t k = 0; k < v->n_slides; k++)
        if (!(u[v->slides[k]] * v->signs[k] > 0)) return -1.0;
    for (ptrdiff_t k = 0; k < v->n_turns; k++)
        if (!(cos(u[v->turns[k]] - v->homes[k]) > 0)) return -1.0;
    for (ptrdiff_t i = 0; i < 6; i++) v->full_u[i] = u[i];
    for (ptrdiff_t var = 0; var < c->n_var; var++) {
        v->values[var] = u[6 + var];
        if (c->position[var] >= 0) v->full_u[c->position[var]] = u[6 + var];
    }
    int64_t at[256]; /* the column read for each of the kernel's columns (more: the batch path) */
    if (n_u + n_loop > 256) return 0.0;
    for (ptrdiff_t i = 0; i < n_u + n_loop; i++) at[i] = i;
    if (given) { /* the legs' rows at u from the caller (given_n columns, given_position) */
        for (ptrdiff_t var = 0; var < c->n_var; var++)
            if (c->position[var] >= 0) at[c->position[var]] = given_position[var];
    } else {
        pk_chain_evaluate(c, v->values, v->full_u, v->r, v->jac, &v->w);
    }
    double bound = closure_rates(v, given ? given : v->jac, given ? given_n : n_u + n_loop, at);
    if (!(bound > 0.0)) return 0.0;
    double rot[9], pos[3], point[3], twist[6];
    ptrdiff_t n_twist = head_walk(v, u, rot, pos);
    for (int i = 0; i < 3; i++) point[i] = pos[i] + v->tool * rot[3 * i + 2];
    double *jac = out, *j_h = out + 6 * n;
    ptrdiff_t k = n < 6 ? n : 6;
    double *sv = j_h + 6 * n, *rates = out + rates_at;
    for (double *pad = sv + k + 1; pad < rates; pad++) *pad = 0.0; /* the record layout's */
    if (n_loop + n_twist < n) /* an actuator without a column below (none on these machines) */
        for (ptrdiff_t i = 0; i < 6 * n; i++) jac[i] = 0.0;
    for (ptrdiff_t i = 0; i < (n_u - 6) * n; i++) rates[i] = 0.0;
    const double *du = v->du;
    for (ptrdiff_t j = 0; j < n_loop; j++) { /* a leg actuator: the platform's twist */
        ptrdiff_t col = v->loop_columns[j];
        double w0 = du[3 * n_loop + j], w1 = du[4 * n_loop + j], w2 = du[5 * n_loop + j];
        twist[0] = du[0 * n_loop + j] + (u[1] * w2 - u[2] * w1);
        twist[1] = du[1 * n_loop + j] + (u[2] * w0 - u[0] * w2);
        twist[2] = du[2 * n_loop + j] + (u[0] * w1 - u[1] * w0);
        twist[3] = w0;
        twist[4] = w1;
        twist[5] = w2;
        point_column(twist, point, jac, n, col);
        for (ptrdiff_t a = 0; a < n_u - 6; a++) rates[a * n + col] = du[(6 + a) * n_loop + j];
    }
    for (ptrdiff_t t = 0; t < n_twist; t++) point_column(v->head_tw + 6 * t, point, jac, n,
                                                         v->head_col[t]);
    for (ptrdiff_t i = 0; i < 6 * n; i++) j_h[i] = i < 3 * n ? jac[i] : jac[i] * c->length;
    if (singular) singular_stage(v, out);
    else
        for (ptrdiff_t i = 0; i <= k; i++) sv[i] = NAN; /* the singular stage not run */
    return bound;
}

/* ---------------------------------------------------------------- module face */

static int copy_array(held_buffers *held, PyObject *obj, const char *name, char type, int ndim,
                      void **dst, Py_ssize_t *count) {
    void *src = grab(held, obj, name, type, 0, ndim);
    if (!src) return -1;
    Py_buffer *view = &held->views[held->count - 1];
    *count = view->len / view->itemsize;
    *dst = malloc((size_t)view->len + 8);
    if (!*dst) {
        PyErr_NoMemory();
        return -1;
    }
    memcpy(*dst, src, (size_t)view->len);
    return 0;
}

/* The pack's checks beyond take_chain's: index ranges and block sizes; -1 on error. */
static int check_pack(const chain_velocity *v, Py_ssize_t n_head, Py_ssize_t n_hp,
                      Py_ssize_t n_cl, const int64_t *column_leg) {
    const pk_chain *c = &v->c;
    if (n_head != v->n_head || n_hp != c->n_var || n_cl != v->n_u || v->n_u < 6
        || v->n_u > 6 * c->n_legs || v->n_loop > 32 || v->n_act < 1) {
        PyErr_SetString(PyExc_ValueError, "chain_velocity_pack: head_position (n_var,), "
                        "column_leg (n_u,) with 6 <= n_u <= 6L, at most 32 leg actuators");
        return -1;
    }
    if (in_range(c->position, c->n_var, -1, v->n_u + v->n_loop, "position") < 0
        || in_range(c->head, n_head, 0, v->n_elem, "head") < 0
        || in_range(v->head_position, c->n_var, -1, v->n_act, "head_position") < 0
        || in_range(v->loop_columns, v->n_loop, 0, v->n_act, "loop_columns") < 0
        || in_range(column_leg, v->n_u, -1, c->n_legs, "column_leg") < 0)
        return -1;
    for (ptrdiff_t idx = 0; idx < n_head; idx++) {
        int64_t e = c->head[idx];
        if (c->types[e] != 0 && (c->evar[e] < 0 || c->evar[e] >= c->n_var)) {
            PyErr_SetString(PyExc_ValueError, "head: an element's variable out of range");
            return -1;
        }
    }
    return 0;
}

/* Lay the scratch and the columns' blocks out in one allocation; -1 on error. */
static int lay_out(chain_velocity *v, const int64_t *column_leg, ptrdiff_t twists) {
    const pk_chain *c = &v->c;
    ptrdiff_t m = 6 * c->n_legs, ld = v->n_u + v->n_loop, L = c->n_legs;
    v->size = 12 * v->n_act + (v->n_act < 6 ? v->n_act : 6) + 1 + (v->n_u - 6) * v->n_act;
    size_t doubles = (size_t)(c->n_var + ld + m + m * ld + v->n_u * v->n_loop
                              + v->n_u * v->n_u + 6 * twists + 6 * v->n_head
                              + 6 * (v->n_act + 6) + v->n_act + 6 + L * 6 * (6 + ld)
                              + m * ld + v->n_u * ld
                              + 6 * (6 + v->n_u + 32));
    size_t ints = (size_t)(twists + v->n_head + 6 * L + L + v->n_u);
    char *memory = malloc(doubles * sizeof(double) + ints * sizeof(int64_t));
    if (!memory) {
        PyErr_NoMemory();
        return -1;
    }
    v->memory = memory;
    double *d = (double *)memory;
    v->values = d; d += c->n_var;
    v->full_u = d; d += ld;
    v->r = d; d += m;
    v->jac = d; d += m * ld;
    v->du = d; d += v->n_u * v->n_loop;
    v->rg_inv = d; d += v->n_u * v->n_u;
    v->w.tw = d; d += 6 * twists;
    v->head_tw = d; d += 6 * v->n_head;
    v->work = d; d += 6 * (v->n_act + 6);
    v->norms = d; d += v->n_act + 6;
    v->panels = d; d += L * 6 * (6 + ld);
    v->rest = d; d += m * ld;
    v->solve = d; d += v->n_u * ld + 6 * (6 + v->n_u + 32);
    int64_t *k = (int64_t *)d;
    v->w.tw_col = k; k += twists;
    v->head_col = k; k += v->n_head;
    v->leg_cols = k; k += 6 * L;
    v->leg_count = k; k += L;
    v->global_cols = k;
    v->w.m = m;
    v->n_global = 0;
    for (ptrdiff_t leg = 0; leg < L; leg++) v->leg_count[leg] = 0;
    for (ptrdiff_t j = 0; j < v->n_u; j++) {
        int64_t leg = j < 6 ? -1 : column_leg[j];
        if (leg >= 0 && v->leg_count[leg] < 6) v->leg_cols[6 * leg + v->leg_count[leg]++] = j;
        else v->global_cols[v->n_global++] = j;
    }
    if (v->n_global > 32) {
        PyErr_SetString(PyExc_ValueError, "chain_velocity_pack: more than 32 global columns");
        return -1;
    }
    return 0;
}

PyObject *pk_py_chain_velocity_pack(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 17) {
        PyErr_Format(PyExc_TypeError, "chain_velocity_pack() takes 17 positional arguments "
                     "(%zd given)", nargs);
        return NULL;
    }
    held_buffers held = {.count = 0};
    chain_velocity *v = calloc(1, sizeof *v);
    if (!v) return PyErr_NoMemory();
    void **arrays = v->owned;
    pk_chain *c = &v->c;
    Py_ssize_t n_elem, n_leg_elements, counts[14];
    if (take_chain(&held, args, c, &n_elem, &n_leg_elements) < 0) goto fail;
    let_go(&held);
    const char *names[10] = {"frames", "types", "evar", "elements", "offsets", "position",
                             "head", "head_position", "loop_columns", "column_leg"};
    const char kinds[10] = {'d', 'i', 'i', 'i', 'i', 'i', 'i', 'i', 'i', 'i'};
    for (int i = 0; i < 10; i++)
        if (copy_array(&held, args[i], names[i], kinds[i], i == 0 ? 3 : 1, &arrays[i],
                       &counts[i]) < 0)
            goto fail;
    let_go(&held);
    c->frames = arrays[0];
    c->types = arrays[1];
    c->evar = arrays[2];
    c->elements = arrays[3];
    c->offsets = arrays[4];
    c->position = arrays[5];
    c->head = arrays[6];
    v->head_position = arrays[7];
    v->loop_columns = arrays[8];
    const char *more[4] = {"slides", "signs", "turns", "homes"};
    for (int i = 0; i < 4; i++)
        if (copy_array(&held, args[13 + i], more[i], i % 2 ? 'd' : 'i', 1, &arrays[10 + i],
                       &counts[10 + i]) < 0)
            goto fail;
    let_go(&held);
    v->slides = arrays[10];
    v->signs = arrays[11];
    v->turns = arrays[12];
    v->homes = arrays[13];
    v->n_slides = counts[10];
    v->n_turns = counts[12];
    v->n_elem = n_elem;
    v->n_head = counts[6];
    v->n_loop = counts[8];
    v->n_u = PyLong_AsSsize_t(args[10]);
    if (v->n_u == -1 && PyErr_Occurred()) goto fail;
    c->length = PyFloat_AsDouble(args[11]);
    if (c->length == -1.0 && PyErr_Occurred()) goto fail;
    v->tool = PyFloat_AsDouble(args[12]);
    if (v->tool == -1.0 && PyErr_Occurred()) goto fail;
    c->n = v->n_u + v->n_loop;
    c->n_head = counts[6];
    v->n_act = v->n_loop;
    for (Py_ssize_t var = 0; var < c->n_var; var++)
        if (v->head_position[var] >= 0) v->n_act++;
    if (check_pack(v, counts[6], counts[7], counts[9], arrays[9]) < 0) goto fail;
    if (counts[11] != v->n_slides || counts[13] != v->n_turns
        || in_range(v->slides, v->n_slides, 0, 6 + c->n_var, "slides") < 0
        || in_range(v->turns, v->n_turns, 0, 6 + c->n_var, "turns") < 0) {
        if (!PyErr_Occurred())
            PyErr_SetString(PyExc_ValueError, "signs (homes) as long as slides (turns)");
        goto fail;
    }
    if (lay_out(v, arrays[9], n_leg_elements + 1) < 0) goto fail;
    PyObject *capsule = PyCapsule_New(v, CAPSULE, pack_free);
    if (!capsule) goto fail;
    return capsule;
fail:
    let_go(&held);
    for (int i = 0; i < 14; i++) free(arrays[i]);
    free(v->memory);
    free(v);
    return NULL;
}

/* out's size check (velocity's layout); the out pointer, or NULL with an error set. */
static double *take_out(const chain_velocity *v, held_buffers *held, PyObject *obj) {
    double *out = grab(held, obj, "out", 'd', 1, 1);
    if (!out) return NULL;
    ptrdiff_t n = v->n_act, k = n < 6 ? n : 6;
    Py_ssize_t need = 12 * n + k + 1 + (v->n_u - 6) * n;
    if (extent(held, 0, 0) != need && extent(held, 0, 0) != v->n_act * (13 + (k < n ? 1 : 2)
                                                                       + v->n_u - 6)) {
        PyErr_Format(PyExc_ValueError, "out: %zd floats expected, not %zd", need,
                     extent(held, 0, 0));
        return NULL;
    }
    return out;
}

/* chain_one_velocity(pack, None, out): the singular stage; returns the condition number. */
static PyObject *singular_only(chain_velocity *v, PyObject *obj) {
    held_buffers held = {.count = 0};
    double *out = take_out(v, &held, obj);
    if (!out) {
        let_go(&held);
        return NULL;
    }
    singular_stage(v, out);
    ptrdiff_t n = v->n_act, k = n < 6 ? n : 6;
    double condition = out[12 * n + k];
    let_go(&held);
    return PyFloat_FromDouble(condition);
}

/* u (width <= 256) from a list of floats or a C-contiguous float64 1-D buffer; -1 with an
 * error. */
static int take_u(PyObject *obj, Py_ssize_t width, double *u) {
    if (width > 256) {
        PyErr_SetString(PyExc_ValueError, "u: at most 250 variables");
        return -1;
    }
    if (PyList_CheckExact(obj)) {
        if (PyList_GET_SIZE(obj) != width) {
            PyErr_Format(PyExc_TypeError, "u: %zd floats expected", width);
            return -1;
        }
        for (Py_ssize_t i = 0; i < width; i++) {
            PyObject *item = PyList_GET_ITEM(obj, i);
            u[i] = PyFloat_CheckExact(item) ? PyFloat_AS_DOUBLE(item) : PyFloat_AsDouble(item);
            if (u[i] == -1.0 && PyErr_Occurred()) return -1;
        }
        return 0;
    }
    held_buffers held = {.count = 0};
    const double *src = grab(&held, obj, "u", 'd', 0, 1);
    if (!src) {
        let_go(&held);
        return -1;
    }
    if (extent(&held, 0, 0) != width) {
        let_go(&held);
        PyErr_Format(PyExc_TypeError, "u: %zd floats expected", width);
        return -1;
    }
    memcpy(u, src, (size_t)width * sizeof(double));
    let_go(&held);
    return 0;
}

/* The pack argument's state, NULL with a TypeError. */
static chain_velocity *pack_state(PyObject *obj) {
    chain_velocity *v = PyCapsule_IsValid(obj, CAPSULE) ? PyCapsule_GetPointer(obj, CAPSULE) : NULL;
    if (!v) PyErr_SetString(PyExc_TypeError, "pack: a chain_velocity_pack() result expected");
    return v;
}

PyObject *pk_py_chain_one_velocity(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 3 && nargs != 4) {
        PyErr_Format(PyExc_TypeError, "chain_one_velocity() takes 3 or 4 positional arguments "
                     "(%zd given)", nargs);
        return NULL;
    }
    int singular = nargs == 3 ? 1 : PyObject_IsTrue(args[3]);
    if (singular < 0) return NULL;
    chain_velocity *v = pack_state(args[0]);
    if (!v) return NULL;
    if (args[1] == Py_None) /* the singular stage alone, on out's J_homogeneous */
        return singular_only(v, args[2]);
    double u[256];
    if (take_u(args[1], 6 + v->c.n_var, u) < 0) return NULL;
    held_buffers held = {.count = 0};
    double *out = take_out(v, &held, args[2]);
    if (!out) {
        let_go(&held);
        return NULL;
    }
    double bound = velocity(v, u, out, singular, NULL, NULL, 0, v->size - (v->n_u - 6) * v->n_act);
    let_go(&held);
    return PyFloat_FromDouble(bound);
}

PyObject *pk_py_chain_one_jacobian(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 3 && nargs != 4) {
        PyErr_Format(PyExc_TypeError, "chain_one_jacobian() takes 3 or 4 positional arguments "
                     "(%zd given)", nargs);
        return NULL;
    }
    int singular = nargs == 3 ? 0 : PyObject_IsTrue(args[3]);
    if (singular < 0) return NULL;
    chain_velocity *v = pack_state(args[0]);
    if (!v) return NULL;
    double threshold = PyFloat_AsDouble(args[2]);
    if (threshold == -1.0 && PyErr_Occurred()) return NULL;
    double u[256];
    if (take_u(args[1], 6 + v->c.n_var, u) < 0) return NULL;
    return pk_one_velocity_array(args[0], u, threshold, NULL, NULL, 0, singular, NULL);
}

/* chain_one_jacobian's answer at u (6 + n_var) for pack; given (6 L rows, given_n columns,
 * given_position[var] the column of each variable, the platform's at 0..5): the closure's
 * Jacobian at u evaluated by the caller (chain_one.c's inverse, its last evaluation), or NULL.
 * q non-NULL: the record layout instead, a read-only (R, n) array of rows J (6), J_homogeneous
 * (6), the singular values and the condition (1 or 2 rows, zero after), the passive rates,
 * q (n). A new reference (the array, None or False), NULL with an error set. */
PyObject *pk_one_velocity_array(PyObject *pack, const double *u, double threshold,
                                const double *given, const int64_t *given_position,
                                ptrdiff_t given_n, int singular, const double *q) {
    chain_velocity *v = pack_state(pack);
    if (!v) return NULL;
    if (given && 6 + v->c.n_var != given_n) given = NULL; /* not the same machine's */
    /* the array first, then the kernel straight into it: no Python code runs between the
     * capsule's scratch and the answer (a thread switch there could reuse the scratch) */
    const ptrdiff_t n = v->n_act, k = n < 6 ? n : 6, rows = 13 + (k < n ? 1 : 2) + v->n_u - 6;
    static PyObject *seal; /* "setflags" (interned, kept): the record's read-only */
    if (q && !seal && !(seal = PyUnicode_InternFromString("setflags"))) return NULL;
    PyObject *empty = pk_numpy_empty(), *size = q ? Py_BuildValue("(nn)", rows, n)
                                                  : PyLong_FromSsize_t(v->size);
    PyObject *array = empty && size ? PyObject_CallOneArg(empty, size) : NULL;
    Py_XDECREF(size);
    Py_buffer view;
    if (!array || PyObject_GetBuffer(array, &view, PyBUF_C_CONTIGUOUS | PyBUF_WRITABLE) < 0) {
        Py_XDECREF(array);
        return NULL;
    }
    ptrdiff_t rates_at = q ? (rows - 1 - v->n_u + 6) * n : 12 * n + k + 1;
    double *out = view.buf, bound = velocity(v, u, out, singular, given, given_position, given_n,
                                             rates_at);
    if (q) memcpy(out + (rows - 1) * n, q, (size_t)n * sizeof(double));
    PyBuffer_Release(&view);
    if (bound < 0.0 || !(bound >= threshold) || !(bound > 0.0)) {
        Py_DECREF(array);
        return Py_NewRef(bound < 0.0 ? Py_False : Py_None);
    }
    PyObject *sealed = q ? PyObject_CallMethodOneArg(array, seal, Py_False) : Py_NewRef(Py_None);
    if (!sealed) Py_CLEAR(array);
    Py_XDECREF(sealed);
    return array;
}
