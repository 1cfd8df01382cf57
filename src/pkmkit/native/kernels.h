/* pkmkit.native.kernels: ahead-of-time twins of the Numba kernels of the full-pose rod
 * machines (see __init__.py). Plain C99, no NumPy headers: arrays come through the buffer
 * protocol, already checked for shape and type by module.c. */
#ifndef PKMKIT_NATIVE_KERNELS_H
#define PKMKIT_NATIVE_KERNELS_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#define PK_PI 3.141592653589793

/* Python's float a % b (the sign of b; Objects/floatobject.c, as Numba compiles it). */
static inline double pk_pymod(double a, double b) {
    double mod = fmod(a, b);
    if (mod) {
        if ((b < 0) != (mod < 0)) mod += b;
    } else {
        mod = copysign(0.0, b);
    }
    return mod;
}

/* Python's max(a, b) and min(a, b): b only when b compares greater (less). */
static inline double pk_max(double a, double b) { return b > a ? b : a; }
static inline double pk_min(double a, double b) { return b < a ? b : a; }

/* full_pose_kernels.rotation_entries: Rodrigues, the series below 1e-8 rad; r row-major. */
static inline void pk_rotation(double wx, double wy, double wz, double r[9]) {
    double theta = sqrt(wx * wx + wy * wy + wz * wz);
    double a, b;
    if (theta < 1e-8) {
        a = 1.0 - theta * theta / 6.0;
        b = 0.5 - theta * theta / 24.0;
    } else {
        a = sin(theta) / theta;
        b = (1.0 - cos(theta)) / (theta * theta);
    }
    r[0] = 1.0 - b * (wy * wy + wz * wz);
    r[4] = 1.0 - b * (wx * wx + wz * wz);
    r[8] = 1.0 - b * (wx * wx + wy * wy);
    r[1] = b * wx * wy - a * wz;
    r[3] = b * wx * wy + a * wz;
    r[2] = b * wx * wz + a * wy;
    r[6] = b * wx * wz - a * wy;
    r[5] = b * wy * wz - a * wx;
    r[7] = b * wy * wz + a * wx;
}

/* The rods of a full-pose machine, as full_pose_kernels.inverse_poses takes them. */
typedef struct {
    ptrdiff_t m;               /* rods */
    const int64_t *kind;       /* (m,) 0 slide, 1 strut, 2 crank */
    const double *base;        /* (m, 3) */
    const double *platform;    /* (m, 3) */
    const double *axis;        /* (m, 3) */
    const double *pivot;       /* (m, 3) */
    const double *e1;          /* (m, 3) */
    const double *e2;          /* (m, 3) */
    const double *length_sq;   /* (m,) */
    const double *length;      /* (m,) */
    const double *crank_radius;/* (m,) */
    const double *crank_offset;/* (m,) */
    const double *sigma;       /* (m,) */
    double boundary_tol;
} pk_rods;

/* The actuators: rods grouped per actuator. */
typedef struct {
    ptrdiff_t n;               /* actuators */
    ptrdiff_t width;           /* columns of groups */
    const int64_t *groups;     /* (n, width) */
    const int64_t *counts;     /* (n,) */
    const unsigned char *angular; /* (n,) bool */
    double consistency_tol;
} pk_actuators;

/* full_pose_kernels.inverse_poses over rows x (rows, 6) -> q (rows, n), status (rows,);
 * rod_q: scratch of m doubles. */
void pk_inverse_poses(const double *x, ptrdiff_t rows, const pk_rods *rods,
                      const pk_actuators *act, double *q, int64_t *status, double *rod_q);

/* The same, one pose at a time (inverse.c); pk_inverse_poses (inverse_simd.c) runs its
 * vectorised twin (AVX-512 or AVX2, 8 or 4 poses per block; the same operations but a
 * vectorised sincos: q within a few ulps) where the CPU and the rods allow, and this for the
 * rest. */
void pk_inverse_poses_scalar(const double *x, ptrdiff_t rows, const pk_rods *rods,
                             const pk_actuators *act, double *q, int64_t *status,
                             double *rod_q);

/* Poses per block of the vectorised inverse kernel in use (0: none, scalar only);
 * pk_simd_set(0) switches it off (tests), 4 or 8 asks for that width, 1 the widest the CPU
 * has; it returns the lanes in use before. pk_simd_sincos: the vectorised kernel's sin and
 * cos of t (count,) into s and c by the width in use; returns it (0: nothing written). */
int pk_simd_lanes(void);
int pk_simd_set(int choice);
int pk_simd_sincos(const double *t, ptrdiff_t count, double *s, double *c);

/* Working arrays of one direct solve for m rods (full_pose_direct_kernel.scratch). */
typedef struct {
    double *base;   /* (m, 3) */
    double *length; /* (m,) */
    double *r;      /* (m,) */
    double *r_new;  /* (m,) */
    double *jac;    /* (m, 6) */
    double *jac_new;/* (m, 6) */
} pk_work;

/* full_pose_direct_kernel.solve_row: one pose q (n,) from u0 (6,) when has_guess;
 * geom (m, 16), home (6 + n + 6n,), opts (7,); out (9,). */
void pk_solve_row(const double *q, ptrdiff_t n, const double *u0, int has_guess,
                  const double *geom, ptrdiff_t m, const double *home, const double *opts,
                  double *out, pk_work *work);

/* direct.c's helpers, shared with position.c: compose (out[0:3] = rotation vector of
 * exp(d) exp(p)), rods (base joints and rod lengths at q), the damped Cholesky step, the
 * stationarity test, a unit quaternion's rotation vector (full_pose_direct_kernel.compose,
 * _rods, _step, _stationary, quaternion_rotvec). */
void pk_quaternion_rotvec(double x, double y, double z, double w, double *out);
void pk_compose(double dx, double dy, double dz, double px, double py, double pz, double *out);
void pk_rod_joints(const double *q, const double *geom, ptrdiff_t m, double *base,
                   double *length);
void pk_lm_step(const double *jac, const double *r, ptrdiff_t m, double lam, double *step,
                double *h);
int pk_stationary(const double *jac, const double *r, ptrdiff_t m, double cost, double gtol);

/* full_pose_position_kernel.solve_rows over rows positions p (rows, 3): u0 (rows, 6) read
 * when has_guess, else the first-order start from home (6 + 3 + 18,) and jt_inv (3, 3), rows
 * of skip (bool) left INVALID_INPUT; geom (m, 16), opts (n_opts = 9 or 10,), out (rows,
 * n_out = 9 or 10; column 9: 1 where the paired Newton solve answered). */
/* n itself when the start table opts[10:] of the paired position solve (n values: a header
 * and the coefficients its header asks for; position.c) is well formed, else -1. */
ptrdiff_t pk_start_table_size(const double *table, ptrdiff_t n);
void pk_position_rows(const double *p, ptrdiff_t rows, const double *u0, int has_guess,
                      const unsigned char *skip, const double *geom, ptrdiff_t m,
                      const double *home, const double *jt_inv, const double *opts,
                      ptrdiff_t n_opts, double *out, ptrdiff_t n_out, pk_work *work);

/* A joint-chain machine as chain_kernel._solve_rows takes it (chain_kernel.model_arrays). */
typedef struct {
    const double *frames;    /* (E, 4, 4) every element's invariant frame */
    const int64_t *types;    /* (E,) 0 fixed, 1 revolute, 2 prismatic */
    const int64_t *evar;     /* (E,) the element's variable */
    const int64_t *elements; /* the legs' elements, flattened */
    const int64_t *offsets;  /* (L + 1,) each leg's first element in `elements` */
    const int64_t *position; /* (n_var,) column of each variable in u, -1 when known */
    const int64_t *head;     /* (H,) the head's elements (inverse model) */
    ptrdiff_t n_legs, n_var, n, n_head;
    double length;           /* characteristic length (m) */
    int inverse;             /* the tool rows too */
} pk_chain;

typedef struct {
    int64_t max_iter;
    double xtol, atol, gtol, stall, residual_tol, damping;
} pk_chain_options;

/* Working arrays of pk_chain_rows: m residual rows (6L, + 6 for the inverse), n unknowns,
 * twists of up to `elements + head` joints. */
typedef struct {
    ptrdiff_t m;
    double *values, *r, *jac, *r_new, *j_new, *u_new, *step, *grad, *h, *low, *tw;
    int64_t *nz, *tw_col;
} pk_chain_work;

/* chain_kernel._solve_rows over u (rows, n) in place: known (known_rows, n_var) (one row for
 * all, or one per row), targets (., 6) and tools (.,) (row k for the inverse, row 0 else). */
void pk_chain_rows(const pk_chain *c, const double *known, ptrdiff_t known_rows, double *u,
                   ptrdiff_t rows, const pk_chain_options *o, int64_t *status,
                   double *residual, int64_t *iterations, const double *targets,
                   const double *tools, pk_chain_work *w);

/* chain.c's evaluate: residual r (w->m,) and Jacobian jac (w->m, c->n) of the closure at u
 * (values (n_var,) filled from u; w->tw, w->tw_col used). */
void pk_chain_evaluate(const pk_chain *c, double *values, const double *u, double *r,
                       double *jac, pk_chain_work *w);

/* chain.c's evaluate_any (the closure, and the tool rows of the inverse model) and retract
 * (u + step, the rotation composed on the left), for chain_one.c. */
void pk_chain_evaluate_any(const pk_chain *c, double *values, const double *u, double *r,
                           double *jac, const double *target, double tool, pk_chain_work *w);
void pk_chain_retract(const double *u, const double *step, double *out, ptrdiff_t n);

/* The spatial twist tw (6,) of a joint whose axis is z = rot[:, 2] at pos: [pos x z, z] for a
 * revolute joint (type 1), [z, 0] for a prismatic one (chain.c, chain_one_closure.c and
 * chain_one_velocity.c: the same operations, so the same bits). */
static inline void pk_chain_joint_twist(const double *rot, const double *pos, int64_t type,
                                        double *tw) {
    double z0 = rot[2], z1 = rot[5], z2 = rot[8];
    if (type == 1) {
        tw[0] = pos[1] * z2 - pos[2] * z1;
        tw[1] = pos[2] * z0 - pos[0] * z2;
        tw[2] = pos[0] * z1 - pos[1] * z0;
        tw[3] = z0;
        tw[4] = z1;
        tw[5] = z2;
    } else {
        tw[0] = z0;
        tw[1] = z1;
        tw[2] = z2;
        tw[3] = tw[4] = tw[5] = 0.0;
    }
}

/* A joint's motion along its element's local z axis (chain_kernel's walk): type 1 turns the
 * frame rot (3 x 3 row-major) by q about its z axis, type 2 slides pos by q along it; the
 * operations of the Numba kernels in their order. Shared by chain.c, chain_linearise.c,
 * chain_one.c and chain_one_velocity.c. */
static inline void pk_chain_joint_move(double *rot, double *pos, int64_t type, double q) {
    if (type == 1) {
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

/* The end of one Levenberg-Marquardt iteration of chain_kernel._solve_rows, shared by chain.c
 * (the batch rows) and chain_one_solve.c (one pose): pk_lm_accept judges the trial cost
 * (accepted when finite and not above cost by more than 1e-13 relative) and moves the damping
 * (x 0.1, floor 1e-12, when accepted; x 10 else); after the caller has kept the trial or not,
 * pk_lm_done says whether the loop stops: an accepted step shorter than xtol (1 + |u|), the
 * damping beyond 1e12, or, every 10 iterations (count), a stall above residual_tol (checkpoint
 * updated). The operations of the Numba loop in its order (the same bits). */
static inline int pk_lm_accept(double cost, double cost_new, double *lam) {
    int accept = isfinite(cost_new) && cost_new <= cost * (1.0 + 1e-13);
    *lam = accept ? pk_max(*lam * 0.1, 1e-12) : *lam * 10.0;
    return accept;
}

static inline int pk_lm_done(const pk_chain_options *o, int accept, const double *step,
                             const double *u, ptrdiff_t n, double lam, double cost,
                             int64_t count, double *checkpoint) {
    double ss = 0.0, uu = 0.0;
    for (ptrdiff_t i = 0; i < n; i++) ss += step[i] * step[i];
    for (ptrdiff_t i = 0; i < n; i++) uu += u[i] * u[i];
    int done = (accept && sqrt(ss) <= o->xtol * (1.0 + sqrt(uu))) || lam > 1e12;
    if (count % 10 == 0) {
        if (cost > (1.0 - o->stall) * *checkpoint
            && cost > 0.5 * (o->residual_tol * o->residual_tol))
            done = 1;
        *checkpoint = cost;
    }
    return done;
}

/* chain.c's _rotvec_matrix, _apply_frame, _rotation_rows (3 x 3 row-major). */
void pk_chain_rotvec_matrix(double x, double y, double z, double *out);
void pk_chain_apply_frame(double *rot, double *pos, const double *f, double *tmp);
void pk_chain_rotation_rows(const double *mm, double length, double sign, double *out);

/* chain_velocity.c: chain_kernel._jacobian_rows and chain_linalg._closure_rates_rows. */
void pk_chain_jacobian_rows(const pk_chain *c, const double *values, const double *u,
                            ptrdiff_t rows, double *out, double *row, double *r,
                            pk_chain_work *w);
void pk_closure_rates_rows(const double *cu, const double *cq, ptrdiff_t n, ptrdiff_t r,
                           ptrdiff_t c, ptrdiff_t k, double rcond, double tol,
                           int64_t expected, double *du, int64_t *rank, double *ratio,
                           double *scratch);

/* The defects of a joint-chain model (chain_kernel.linearise): local twists (D, 6), their
 * order by element (D,) and each element's first entry in it (E + 1,). */
typedef struct {
    const double *local;
    const int64_t *order, *starts;
    ptrdiff_t n_defects;
} pk_defects;

/* chain_linearise.c: chain_kernel._linearise_rows and chain_linalg._absorb_rows. */
void pk_chain_linearise_rows(const pk_chain *c, const pk_defects *d, const double *values,
                             const double *u, ptrdiff_t rows, double *cu, double *cd,
                             double *tool_r, double *tool_p, double *tool_tw, double *row,
                             double *r, double *twists, int64_t *ids, pk_chain_work *w);
void pk_absorb_rows(const double *cu, const double *cd, ptrdiff_t n, ptrdiff_t r,
                    ptrdiff_t u, ptrdiff_t d, double *du, double *rest, unsigned char *ok,
                    double *h, double *low, double *g);

/* velocity.c: the velocity model of one pose of a translational rod-leg machine
 * (machines/velocity_one.py). Legs: PK_LEG doubles each (kind 0 slide, 1 strut, 2 crank, then
 * the terms of velocity_one._legs, zero-padded). Bits of `ok`: the fields answered. */
#define PK_LEG 14
#define PK_INV_LEG 20 /* closed_form.RodClosedForm._single_legs */
#define PK_POSE_ROD 24 /* full_pose_one.OnePoseInverse.rows */
#define PK_F_A (1u << 0)
#define PK_F_B (1u << 1)
#define PK_F_J (1u << 2)
#define PK_F_J_INV (1u << 3)
#define PK_F_SV (1u << 4)
#define PK_F_CONDITION (1u << 5)
#define PK_F_DET_A (1u << 6)
#define PK_F_DET_B (1u << 7)
#define PK_F_PARALLEL (1u << 8)
#define PK_F_SERIAL (1u << 9)
#define PK_F_SINGULARITY (1u << 10)
#define PK_F_MODE (1u << 11)
#define PK_F_Q (1u << 12) /* the inputs kept in the state (rod_one.c): q, then x */
#define PK_F_X (1u << 13)

typedef struct {
    int n;             /* 2 or 3 */
    unsigned ok;       /* PK_F_* of the fields answered */
    double a[9], b[3], j[9], j_inv[9], sv[3];
    double det_a, det_b, condition, parallel, serial;
    long flags, mode;
    /* rod_one.c's rod_jacobian_one: the inputs, the fields computed when one is first read */
    int pending;       /* 1: not computed yet (rod_field computes them) */
    double legs[3 * PK_LEG], x[3], q[3], tol, near;
    /* velocity.c's stages: J's singular values and the parallel measure when asked */
    int svd_pending, parallel_tried, zero_b;
    double lengths[3];
} pk_rod_state;

/* One pose x (n,) at q (n,), thresholds tol (singularities) and near (J's singular values
 * from J^-1 below it); needs the GIL (NumPy's arccos is looked up on first use). */
void pk_rod_velocity(const double *legs, int n, const double *x, const double *q, double tol,
                     double near, pk_rod_state *s);

/* svd.c: one-sided Jacobi sweeps (V optional, any layout) and the singular values of one
 * small matrix, shared by the SVD, chain-velocity and pose-velocity kernels. */
void pk_jacobi_sweeps(double *work, ptrdiff_t k, ptrdiff_t p, double *vmat, ptrdiff_t v_row,
                      ptrdiff_t v_col, ptrdiff_t v_len, double *norms, double tol);
void pk_singular_values_one(const double *mat, ptrdiff_t r, ptrdiff_t c, double *out,
                            double *work, double *norms);

/* plain_numbers.c: the one reader of plain numbers (a pose or configuration given as a list,
 * tuple or 1-D float64/int64 buffer) for the one-pose entries, and the one new-array helper;
 * the rule set is documented at the top of plain_numbers.c. -1 with an exception set. */
#ifdef Py_PYTHON_H /* only where Python.h came first */
enum { PK_PLAIN_TAKEN = 0, PK_PLAIN_REFUSED = 1, PK_PLAIN_OTHER = 2 };
int pk_plain_numbers(PyObject *x, Py_ssize_t count, double max_abs, double *out);
/* A new float64 NumPy array (rows,) (cols 0) or (rows, cols) holding values (row-major). */
PyObject *pk_new_array(const double *values, Py_ssize_t rows, Py_ssize_t cols);
/* A C-contiguous float64 ('d') or bool ('?') buffer argument of ndim dimensions, sizes shape
 * (-1: any; NULL: any shape); 0, or -1 with an exception set and nothing held. */
int pk_take(PyObject *obj, Py_buffer *view, const char *name, char type, int writable, int ndim,
            const Py_ssize_t *shape);
/* inverse_shared.c: one batch's inverse on several threads, held rows computed again by an
 * idle thread and written once (issue 22 §2). */
ptrdiff_t pk_inverse_plan_bytes(ptrdiff_t rows, ptrdiff_t slice_rows, ptrdiff_t block_slices);
void pk_inverse_plan_init(unsigned char *plan, ptrdiff_t rows, ptrdiff_t slice_rows,
                          ptrdiff_t block_slices);
int pk_inverse_plan_fits(unsigned char *plan, ptrdiff_t bytes, ptrdiff_t rows);
ptrdiff_t pk_inverse_plan_slice(unsigned char *plan); /* its slice_rows */
void pk_inverse_shared(const double *x, ptrdiff_t rows, const pk_rods *rods,
                       const pk_actuators *act, double *q, int64_t *status,
                       unsigned char *plan, int wait, double *scratch_q,
                       int64_t *scratch_status, double *rod_q);
extern const char pk_inverse_plan_doc[], pk_inverse_shared_doc[];
/* The plan argument (a writable buffer fitting rows; view held on success, else NULL with
 * an exception), and pk_inverse_shared with this thread's scratch, the GIL released (-1 and
 * MemoryError when the scratch cannot be had). */
unsigned char *pk_take_plan(PyObject *obj, Py_buffer *view, Py_ssize_t rows);
int pk_run_shared(const double *x, ptrdiff_t rows, const pk_rods *rods,
                  const pk_actuators *act, double *q, int64_t *status, unsigned char *plan,
                  int wait, double *rod_q);
PyObject *pk_py_inverse_plan(PyObject *self, PyObject *const *args, Py_ssize_t nargs);

/* recycled.c: large batch outputs' memory handed back to the next call (issue 22 §2). */
extern const char pk_recycled_block_doc[], pk_recycled_release_doc[];
PyObject *pk_py_recycled_block(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
PyObject *pk_py_recycled_release(PyObject *self, PyObject *const *args, Py_ssize_t nargs);

/* chain_closed_rows.c: the joint chains' closed-form starts over rows (session 35). */
extern const char pk_chain_closed_rows_doc[], pk_chain_closed_direct_rows_doc[];
PyObject *pk_py_chain_closed_rows(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
PyObject *pk_py_chain_closed_direct_rows(PyObject *self, PyObject *const *args,
                                         Py_ssize_t nargs);

/* angles.c: a table's angles -> rotation vectors, NumPy's bits (issue 22 §5) */
extern const char pk_euler_quat_doc[], pk_euler_rotvec_doc[];
PyObject *pk_py_euler_quat(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
PyObject *pk_py_euler_rotvec(PyObject *self, PyObject *const *args, Py_ssize_t nargs);

/* csv_text.c: a table's rows as CSV text, pyarrow's bytes (issue 22 §5, session 35) */
extern const char pk_csv_rows_doc[];
PyObject *pk_py_csv_rows(PyObject *self, PyObject *const *args, Py_ssize_t nargs);
#endif

#endif
