/* native/chain_one.c, chain_one_solve.c, chain_one_pack.c: a joint-chain machine's one-pose
 * constants (the capsule's state) and the solve by block elimination (see chain_one.c). */
#ifndef PKMKIT_CHAIN_ONE_H
#define PKMKIT_CHAIN_ONE_H

#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdlib.h>
#include <string.h>

#include "kernels.h"

#define PK_ONE_CAPSULE "pkmkit.chain_one"

/* Columns of each block of rows (legs, then the tool rows of the inverse model). */
typedef struct {
    ptrdiff_t count;     /* blocks */
    int64_t *start;      /* (count + 1,) into cols */
    int64_t *cols;       /* the blocks' columns, each >= 6 */
    ptrdiff_t widest;    /* largest block */
    ptrdiff_t n_core;    /* the platform's 6 columns and the joints shared by blocks */
    int64_t *core;
    /* chain_one_closure.c's plan: each walk entry's twist offset in its block's panel (-1:
     * none; the legs' elements, then the head's), each element's frame kind (PK_FRAME_*),
     * doubles per panel (6 (n_core + widest)), elements */
    int64_t *dest;
    unsigned char *kind;
    ptrdiff_t panel, n_elements;
} pk_blocks;

enum { PK_FRAME_GENERAL = 0, PK_FRAME_ROTATION = 1, PK_FRAME_SHIFT = 2, PK_FRAME_IDENTITY = 3 };

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
    int closed;          /* the kind's closed-form start: PK_CLOSED_* (chain_one.c closed_start) */
    double cl[32];       /* its constants (the TriMule's c1, c2, spindle, L, l, H, h) */
    void *owned[48];
    int n_owned;
} pk_one;

/* The families with a closed-form start in C (the first entry of chain_one_pack's closed). */
enum { PK_CLOSED_TRIMULE = 1, PK_CLOSED_TRIPTEOR = 2 };

/* chain_one_tripteor.c: the Tripteor's start u (21,) of target (6,) on branch (+-1, 0: nearest
 * home) from tripteor_forms.constants k (24,); 1, or 0 where it declines. */
int pk_one_tripteor_start(const double *k, double tool, const double *target, double branch,
                          double *u);
/* chain_one_tripteor.c: the Tripteor's direct start u (21,) from q (5,); 1, or 0 (declined). */
int pk_one_tripteor_direct(const double *k, const double *q, double *u);
/* The TriMule's (chain_one_trimule.c): cl the constants after the family's code. */
int pk_one_trimule_start(const double *cl, double tool, const double *target, double branch,
                         double *u);
int pk_one_trimule_direct(const double *cl, const double *q, double *u);

/* chain_one_solve.c: pk_chain_rows's loop on one row u (n,) from known (n_var,), its normal
 * equations by block elimination (scratch: pk_one_block_scratch doubles); the blocks of a
 * model (-2 when out of memory; their arrays appended to s->owned). */
void pk_one_solve_blocks(const pk_chain *c, const pk_blocks *bk, const double *known,
                         double *u, const pk_chain_options *o, const double *target,
                         double tool, pk_chain_work *w, double *scratch, int64_t *status,
                         double *residual, int64_t *iterations);
ptrdiff_t pk_one_block_scratch(const pk_blocks *bk, ptrdiff_t n);
int pk_one_find_blocks(pk_one *s, const pk_chain *c, pk_blocks *bk);

/* chain_one_closure.c: the closure written into the blocks' column panels (bk->count panels
 * of bk->panel doubles), its constant entries, its plan (-2 when out of memory). cache: 3
 * doubles per element (angle, cosine, sine), all NaN before a solve's first evaluation. */
void pk_one_closure(const pk_chain *c, const pk_blocks *bk, double *values, const double *u,
                    double *r, double *panels, const double *target, double tool,
                    double *cache);
void pk_one_panels_init(const pk_chain *c, const pk_blocks *bk, double *panels);
int pk_one_closure_plan(pk_one *s, const pk_chain *c, pk_blocks *bk);

/* chain_one_solve.c: the panels in a solve's scratch (after pk_one_solve_blocks, the Jacobian
 * at the returned u, that u in *last); the closure at u alone into them; J'J's lower part from
 * them. */
double *pk_one_panels(const pk_blocks *bk, ptrdiff_t n, double *scratch, const double **last);
double *pk_one_evaluate(const pk_chain *c, const pk_blocks *bk, double *values,
                        const double *u, double *r, const double *target, double tool,
                        double *scratch);
void pk_one_gram(const pk_blocks *bk, const double *panels, ptrdiff_t n, double *h);

/* chain_one_velocity.c: chain_one_jacobian's answer at u (a new reference: the array, None or
 * False; NULL with an error), the legs' rows of the closure's Jacobian at u given (6 L rows,
 * given_n columns, given_position[var] each variable's; the platform's at 0..5) or NULL; the
 * singular stage run too where singular is nonzero; q (n) non-NULL: the record layout, a
 * read-only (R, n) array with q its last row. */
PyObject *pk_one_velocity_array(PyObject *pack, const double *u, double threshold,
                                const double *given, const int64_t *given_position,
                                ptrdiff_t given_n, int singular, const double *q);

#endif
