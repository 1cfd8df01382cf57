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

typedef struct {
    int n;             /* 2 or 3 */
    unsigned ok;       /* PK_F_* of the fields answered */
    double a[9], b[3], j[9], j_inv[9], sv[3];
    double det_a, det_b, condition, parallel, serial;
    long flags, mode;
} pk_rod_state;

/* One pose x (n,) at q (n,), thresholds tol (singularities) and near (J's singular values
 * from J^-1 below it); needs the GIL (NumPy's arccos is looked up on first use). */
void pk_rod_velocity(const double *legs, int n, const double *x, const double *q, double tol,
                     double near, pk_rod_state *s);

#endif
