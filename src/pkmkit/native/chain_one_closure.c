/* The one-pose solve's closure (issue 22 §1, session 33): chain.c's evaluate and tool_rows for
 * one configuration, written straight into the blocks' column panels that chain_one_solve.c's
 * normal equations read, instead of a dense (m, n) Jacobian zeroed at every evaluation and
 * gathered by blocks afterwards.
 *
 * A block's panel (pk_blocks.panel doubles) is its 6 rows of the Jacobian by columns: the core
 * columns (the platform's 6, then the joints several blocks share) at 6 t, its own columns at
 * 6 (n_core + p). A leg writes -1 at (i, i) of the platform's first 3 columns and the rotation
 * rows' 3 x 3 at rows 3..5 of columns 3..5 (chain.c's evaluate), the tool block its platform
 * entries (tool_rows), each block its unknown joints' twist columns; every other entry is a
 * structural zero, written once per solve (pk_one_panels_init). The same operations as
 * chain.c on every entry written (the bits of its dense matrix, signed zeros aside), with:
 * - the frames by kind (pk_blocks.kind): a frame without translation adds no position
 *   products, one without rotation no rotation products (a zero product added to a sum leaves
 *   it unchanged), a leg's first frame copied (the walk starts at the identity);
 * - the platform's rotation (Rodrigues) evaluated once for the legs and the tool rows;
 * - each turn's cosine and sine kept with its angle (cache: 3 doubles per element, angle,
 *   cosine, sine) and reused while the angle is bit for bit the same: the known joints of the
 *   direct model (the actuators) at every evaluation of a solve, any joint whose step left it
 *   unchanged. */
#include "chain_one.h"

#include <math.h>

/* (rot, pos) <- (rot, pos) f by the frame's kind (chain.c's apply_frame, its products of zero
 * translation or identity rotation left out). */
static inline void frame(double *rot, double *pos, const double *f, unsigned char kind) {
    if (kind == PK_FRAME_IDENTITY) return;
    double r[9];
    memcpy(r, rot, sizeof r);
    if (kind != PK_FRAME_ROTATION)
        for (int i = 0; i < 3; i++)
            pos[i] += r[3 * i] * f[3] + r[3 * i + 1] * f[7] + r[3 * i + 2] * f[11];
    if (kind != PK_FRAME_SHIFT)
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                rot[3 * i + j] = r[3 * i] * f[j] + r[3 * i + 1] * f[4 + j]
                                 + r[3 * i + 2] * f[8 + j];
}

/* pk_chain_joint_move with the turn's cosine and sine from the cache when its angle is the
 * same bits as the last one's. */
static inline void joint(double *rot, double *pos, int64_t type, double q, double *cache) {
    if (type != 1) {
        pk_chain_joint_move(rot, pos, type, q);
        return;
    }
    uint64_t now, last;
    memcpy(&now, &q, sizeof now);
    memcpy(&last, cache, sizeof last);
    double cq, sq;
    if (now == last) {
        cq = cache[1];
        sq = cache[2];
    } else {
        cq = cos(q);
        sq = sin(q);
        cache[0] = q;
        cache[1] = cq;
        cache[2] = sq;
    }
    for (int i = 0; i < 3; i++) {
        double x = rot[3 * i], y = rot[3 * i + 1];
        rot[3 * i] = cq * x + sq * y;
        rot[3 * i + 1] = cq * y - sq * x;
    }
}

/* A walk over elements list (length), its twists' raw entries written into the panel at
 * their columns (dest: offsets, -1 for none): (pos x z, z) of a turn, (z, 0) of a slide —
 * chain.c's walk_element. from_identity: the walk starts at the identity (a leg). */
static inline void walk(const pk_chain *c, const pk_blocks *bk, const int64_t *list,
                        const int64_t *dest, ptrdiff_t length, const double *values,
                        double *rot, double *pos, double *panel, double *cache,
                        int from_identity) {
    for (ptrdiff_t i = 0; i < length; i++) {
        int64_t e = list[i];
        const double *f = c->frames + 16 * e;
        if (i == 0 && from_identity) {
            for (int a = 0; a < 3; a++) {
                pos[a] = f[4 * a + 3];
                for (int b = 0; b < 3; b++) rot[3 * a + b] = f[4 * a + b];
            }
        } else {
            frame(rot, pos, f, bk->kind[e]);
        }
        int64_t t = c->types[e];
        if (t == 0) continue;
        if (dest[i] >= 0) {
            pk_chain_joint_twist(rot, pos, t, panel + dest[i]);
        }
        joint(rot, pos, t, values[c->evar[e]], cache + 3 * e);
    }
}

/* The panels' constant entries: zeros, -1 at a leg's (i, i) for i < 3, 1 at the tool block's. */
void pk_one_panels_init(const pk_chain *c, const pk_blocks *bk, double *panels) {
    memset(panels, 0, sizeof(double) * (size_t)(bk->count * bk->panel));
    for (ptrdiff_t b = 0; b < bk->count; b++)
        for (int i = 0; i < 3; i++) panels[b * bk->panel + 7 * i] = b < c->n_legs ? -1.0 : 1.0;
}

/* The residual r (chain.c's rows) and the panels' variable entries at u (values filled). */
void pk_one_closure(const pk_chain *c, const pk_blocks *bk, double *values, const double *u,
                    double *r, double *panels, const double *target, double tool,
                    double *cache) {
    const double length = c->length;
    double rx[9], rot[9], tmp[9], mm[9], rows[9], pos[3];
    for (ptrdiff_t v = 0; v < c->n_var; v++)
        if (c->position[v] >= 0) values[v] = u[c->position[v]];
    pk_chain_rotvec_matrix(u[3], u[4], u[5], rx);
    for (ptrdiff_t leg = 0; leg < c->n_legs; leg++) {
        double *panel = panels + leg * bk->panel, *rb = r + 6 * leg;
        int64_t first = c->offsets[leg], count = c->offsets[leg + 1] - first;
        for (int i = 0; i < 3; i++) {  /* the identity (the first frame copied over it) */
            pos[i] = 0.0;
            for (int j = 0; j < 3; j++) rot[3 * i + j] = i == j ? 1.0 : 0.0;
        }
        walk(c, bk, c->elements + first, bk->dest + first, count, values, rot, pos, panel,
             cache, 1);
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                mm[3 * i + j] = rot[3 * i] * rx[3 * j] + rot[3 * i + 1] * rx[3 * j + 1]
                                + rot[3 * i + 2] * rx[3 * j + 2];
        double cc = 0.25 * (1.0 + mm[0] + mm[4] + mm[8]);
        for (int i = 0; i < 3; i++) rb[i] = pos[i] - u[i];
        rb[3] = length * (0.5 * (mm[7] - mm[5])) / cc;
        rb[4] = length * (0.5 * (mm[2] - mm[6])) / cc;
        rb[5] = length * (0.5 * (mm[3] - mm[1])) / cc;
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) tmp[3 * i + j] = mm[3 * j + i];
        pk_chain_rotation_rows(tmp, length, -1.0, rows);
        for (int i = 0; i < 3; i++)  /* row 3 + i, column 3 + j */
            for (int j = 0; j < 3; j++) panel[6 * (3 + j) + 3 + i] = rows[3 * i + j];
        pk_chain_rotation_rows(mm, length, 1.0, rows);
        const int64_t *dest = bk->dest + first;
        for (int64_t i = 0; i < count; i++) {
            if (dest[i] < 0) continue;
            double *tw = panel + dest[i];
            double w0 = tw[3], w1 = tw[4], w2 = tw[5];
            tw[0] = tw[0] + w1 * pos[2] - w2 * pos[1];
            tw[1] = tw[1] + w2 * pos[0] - w0 * pos[2];
            tw[2] = tw[2] + w0 * pos[1] - w1 * pos[0];
            for (int a = 0; a < 3; a++)
                tw[3 + a] = rows[3 * a] * w0 + rows[3 * a + 1] * w1 + rows[3 * a + 2] * w2;
        }
    }
    if (!c->inverse) return;
    /* the tool rows (chain.c's tool_rows; its rotvec_matrix of u is rx) */
    double *panel = panels + c->n_legs * bk->panel, *rb = r + 6 * c->n_legs;
    const int64_t *dest = bk->dest + c->offsets[c->n_legs];
    memcpy(rot, rx, sizeof rot);
    for (int i = 0; i < 3; i++) pos[i] = u[i];
    walk(c, bk, c->head, dest, c->n_head, values, rot, pos, panel, cache, 0);
    double a0 = rot[2], a1 = rot[5], a2 = rot[8];
    double p0 = pos[0] + tool * a0, p1 = pos[1] + tool * a1, p2 = pos[2] + tool * a2;
    rb[0] = p0 - target[0];
    rb[1] = p1 - target[1];
    rb[2] = p2 - target[2];
    rb[3] = length * (a0 - target[3]);
    rb[4] = length * (a1 - target[4]);
    rb[5] = length * (a2 - target[5]);
    double d0 = p0 - u[0], d1 = p1 - u[1], d2 = p2 - u[2];
    panel[6 * 4 + 0] = d2;  /* (row, column) at 6 column + row */
    panel[6 * 5 + 0] = -d1;
    panel[6 * 3 + 1] = -d2;
    panel[6 * 5 + 1] = d0;
    panel[6 * 3 + 2] = d1;
    panel[6 * 4 + 2] = -d0;
    panel[6 * 4 + 3] = length * a2;
    panel[6 * 5 + 3] = -length * a1;
    panel[6 * 3 + 4] = -length * a2;
    panel[6 * 5 + 4] = length * a0;
    panel[6 * 3 + 5] = length * a1;
    panel[6 * 4 + 5] = -length * a0;
    for (ptrdiff_t i = 0; i < c->n_head; i++) {
        if (dest[i] < 0) continue;
        double *tw = panel + dest[i];
        double w0 = tw[3], w1 = tw[4], w2 = tw[5];
        tw[0] = tw[0] + w1 * p2 - w2 * p1;
        tw[1] = tw[1] + w2 * p0 - w0 * p2;
        tw[2] = tw[2] + w0 * p1 - w1 * p0;
        tw[3] = length * (w1 * a2 - w2 * a1);
        tw[4] = length * (w2 * a0 - w0 * a2);
        tw[5] = length * (w0 * a1 - w1 * a0);
    }
}

/* The frames' kinds and the walks' twist offsets of model c's blocks bk (found): -2 when out of
 * memory (the arrays appended to s->owned). A column a walk reaches twice keeps its last twist
 * (chain.c overwrites the dense entry). */
int pk_one_closure_plan(pk_one *s, const pk_chain *c, pk_blocks *bk) {
    ptrdiff_t walked = c->offsets[c->n_legs] + c->n_head, elements = 0;
    for (ptrdiff_t i = 0; i < c->offsets[c->n_legs]; i++)
        if (c->elements[i] + 1 > elements) elements = c->elements[i] + 1;
    for (ptrdiff_t i = 0; i < c->n_head; i++)
        if (c->head[i] + 1 > elements) elements = c->head[i] + 1;
    int64_t *dest = malloc(sizeof(int64_t) * (size_t)(walked + 1));
    unsigned char *kind = malloc((size_t)elements + 1);
    int64_t *slot = malloc(sizeof(int64_t) * (size_t)(c->n + 1));
    if (!dest || !kind || !slot) {
        free(dest), free(kind), free(slot);
        return -2;
    }
    s->owned[s->n_owned++] = dest;
    s->owned[s->n_owned++] = kind;
    bk->dest = dest;
    bk->kind = kind;
    for (ptrdiff_t e = 0; e < elements; e++) {
        const double *f = c->frames + 16 * e;
        int moved = f[3] != 0.0 || f[7] != 0.0 || f[11] != 0.0, turned = 0;
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) turned = turned || f[4 * i + j] != (i == j ? 1.0 : 0.0);
        kind[e] = turned ? (moved ? PK_FRAME_GENERAL : PK_FRAME_ROTATION)
                         : (moved ? PK_FRAME_SHIFT : PK_FRAME_IDENTITY);
    }
    bk->panel = 6 * (bk->n_core + bk->widest);
    bk->n_elements = elements;
    for (ptrdiff_t b = 0; b < c->n_legs + (c->inverse ? 1 : 0); b++) {
        for (ptrdiff_t a = 0; a < c->n; a++) slot[a] = -1;
        for (ptrdiff_t t = 6; t < bk->n_core; t++) slot[bk->core[t]] = 6 * t;
        if (b < bk->count)
            for (int64_t p = bk->start[b]; p < bk->start[b + 1]; p++)
                slot[bk->cols[p]] = 6 * (bk->n_core + p - bk->start[b]);
        int leg = b < c->n_legs;
        const int64_t *list = leg ? c->elements + c->offsets[b] : c->head;
        ptrdiff_t length = leg ? c->offsets[b + 1] - c->offsets[b] : c->n_head;
        int64_t *out = dest + (leg ? c->offsets[b] : c->offsets[c->n_legs]);
        for (ptrdiff_t i = 0; i < length; i++) {
            int64_t e = list[i];
            int64_t col = c->types[e] == 0 ? -1 : c->position[c->evar[e]];
            out[i] = col < 0 ? -1 : slot[col];
            for (ptrdiff_t j = 0; j < i && out[i] >= 0; j++)
                if (out[j] == out[i]) out[j] = -1;
        }
    }
    if (!c->inverse)
        for (ptrdiff_t i = 0; i < c->n_head; i++) dest[c->offsets[c->n_legs] + i] = -1;
    free(slot);
    return 0;
}

/* ---------------------------------------------------------------- the module face (tests) */

const char pk_chain_one_closure_doc[] =
    "chain_one_closure(packed, u, values, inverse, target)\n\n"
    "The one-pose solve's closure (native/chain_one_closure.c) of the machine packed by\n"
    "chain_one_pack at u (n numbers of the model) and the known variables' values (n_var\n"
    "numbers; the unknown ones taken from u), its panels reassembled into the dense Jacobian:\n"
    "(r (m,), J (m, n)). inverse: the inverse model (the tool rows at target (6\n"
    "numbers) and the packed tool length), else the direct model (target read, unused). For\n"
    "tests: chain.c's evaluate (its Numba twin) is the oracle.";

PyObject *pk_py_chain_one_closure(PyObject *self, PyObject *const *args, Py_ssize_t nargs) {
    (void)self;
    if (nargs != 5) {
        PyErr_SetString(PyExc_TypeError, "chain_one_closure(packed, u, values, inverse, target)");
        return NULL;
    }
    pk_one *s = PyCapsule_GetPointer(args[0], PK_ONE_CAPSULE);
    if (!s) return NULL;
    int inverse = PyObject_IsTrue(args[3]);
    if (inverse < 0) return NULL;
    const pk_chain *c = inverse ? &s->inv : &s->dir;
    const pk_blocks *bk = inverse ? &s->inv_b : &s->dir_b;
    ptrdiff_t n = c->n, m = 6 * c->n_legs + (c->inverse ? 6 : 0);
    ptrdiff_t cells = pk_one_block_scratch(bk, n);
    double *memory = malloc(sizeof(double) * (size_t)(cells + c->n_var + m + m * n + n + 6));
    if (!memory) return PyErr_NoMemory();
    double *scratch = memory, *values = scratch + cells, *r = values + c->n_var;
    double *jac = r + m, *u = jac + m * n, *target = u + n;
    const char *wrong = NULL;
    int got = pk_plain_numbers(args[1], n, INFINITY, u);
    if (got == PK_PLAIN_TAKEN) {
        got = pk_plain_numbers(args[2], c->n_var, INFINITY, values);
        if (got == PK_PLAIN_TAKEN) {
            got = pk_plain_numbers(args[4], 6, INFINITY, target);
            if (got != PK_PLAIN_TAKEN) wrong = "target: 6 finite numbers expected";
        } else {
            wrong = "values: n_var finite numbers expected";
        }
    } else {
        wrong = "u: n finite numbers expected (the model's unknowns)";
    }
    PyObject *out = NULL;
    if (got < 0) goto done;
    if (wrong) {
        PyErr_SetString(PyExc_ValueError, wrong);
        goto done;
    }
    double *panels = pk_one_evaluate(c, bk, values, u, r, target, s->tool, scratch);
    memset(jac, 0, sizeof(double) * (size_t)(m * n));
    for (ptrdiff_t b = 0; b < bk->count; b++) {
        ptrdiff_t k = bk->start[b + 1] - bk->start[b];
        for (ptrdiff_t p = 0; p < bk->n_core + k; p++) {
            int64_t col = p < bk->n_core ? bk->core[p] : bk->cols[bk->start[b] + p - bk->n_core];
            for (int i = 0; i < 6; i++)
                jac[(6 * b + i) * n + col] = panels[b * bk->panel + 6 * p + i];
        }
    }
    PyObject *ra = pk_new_array(r, m, 0), *ja = ra ? pk_new_array(jac, m, n) : NULL;
    out = ja ? PyTuple_Pack(2, ra, ja) : NULL;
    Py_XDECREF(ra);
    Py_XDECREF(ja);
done:
    free(memory);
    return out;
}
