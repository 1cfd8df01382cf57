"""The fixed C text of a rod-leg LinuxCNC module (:mod:`pkmkit.export.linuxcnc` writes the
numbers before it): the rotations of X Y Z A B C, the rods' vectors, the parallel Jacobian rows
and det A, the closed-form inverse model rod by rod, the bounded Newton direct model, and
LinuxCNC's four kinematics functions. Lengths in the module's unit, crank joints in degrees.
"""

from __future__ import annotations

#: Everything after the tables, up to the realtime module's glue.
#: ``turn``: R <- exp([w]x) R (Rodrigues), the rotation update both modules' Newton steps use.
TURN_C = r"""/* R <- exp([w]x) R (Rodrigues) */
static void turn(double R[3][3], const double w[3])
{
    double angle = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    double E[3][3], T[3][3], k[3], c, s, v;
    int i, r;
    if (angle == 0.0) return;
    k[0] = w[0] / angle; k[1] = w[1] / angle; k[2] = w[2] / angle;
    c = cos(angle); s = sin(angle); v = 1.0 - c;
    E[0][0] = c + k[0] * k[0] * v;        E[0][1] = k[0] * k[1] * v - k[2] * s;
    E[0][2] = k[0] * k[2] * v + k[1] * s; E[1][0] = k[1] * k[0] * v + k[2] * s;
    E[1][1] = c + k[1] * k[1] * v;        E[1][2] = k[1] * k[2] * v - k[0] * s;
    E[2][0] = k[2] * k[0] * v - k[1] * s; E[2][1] = k[2] * k[1] * v + k[0] * s;
    E[2][2] = c + k[2] * k[2] * v;
    for (r = 0; r < 3; r++)
        for (i = 0; i < 3; i++)
            T[r][i] = E[r][0] * R[0][i] + E[r][1] * R[1][i] + E[r][2] * R[2][i];
    for (r = 0; r < 3; r++)
        for (i = 0; i < 3; i++) R[r][i] = T[r][i];
}
"""

ROD_MODEL_C = r"""/* R = Rz(c) Ry(b) Rx(a), angles in degrees */
static void rotation_from_abc(double a, double b, double c, double R[3][3])
{
    double ca = cos(a * DEG), sa = sin(a * DEG), cb = cos(b * DEG), sb = sin(b * DEG);
    double cc = cos(c * DEG), sc = sin(c * DEG);
    R[0][0] = cc * cb; R[0][1] = cc * sb * sa - sc * ca; R[0][2] = cc * sb * ca + sc * sa;
    R[1][0] = sc * cb; R[1][1] = sc * sb * sa + cc * ca; R[1][2] = sc * sb * ca - cc * sa;
    R[2][0] = -sb;     R[2][1] = cb * sa;                R[2][2] = cb * ca;
}

#if FULL_POSE && !POSITION_CONTROLLED
/* the angle + k 360 nearest to ref */
static double unwrap_near(double angle, double ref)
{
    while (angle - ref > 180.0) angle -= 360.0;
    while (angle - ref < -180.0) angle += 360.0;
    return angle;
}

/* A, B, C (degrees) of R, A and C taken nearest to the previous a0, c0 */
static void abc_from_rotation(double R[3][3], double a0, double c0,
                              double *a, double *b, double *c)
{
    double cb = sqrt(R[0][0] * R[0][0] + R[1][0] * R[1][0]);
    *b = atan2(-R[2][0], cb) / DEG;
    if (cb > 1e-9) {
        *a = atan2(R[2][1], R[2][2]) / DEG;
        *c = atan2(R[1][0], R[0][0]) / DEG;
    } else if (R[2][0] < 0.0) {        /* B = +90: only A - C is defined */
        *a = a0;
        *c = a0 - atan2(R[0][1], R[1][1]) / DEG;
    } else {                            /* B = -90: only A + C is defined */
        *a = a0;
        *c = atan2(-R[0][1], R[1][1]) / DEG - a0;
    }
    *a = unwrap_near(*a, a0);
    *c = unwrap_near(*c, c0);
}
#endif

/* platform joint centres P_j = p + R b_j, and R b_j */
static void platform_points(const double p[3], double R[3][3], double P[N_RODS][3],
                            double Rb[N_RODS][3])
{
    int j, k;
    for (j = 0; j < N_RODS; j++) {
        for (k = 0; k < 3; k++) {
            Rb[j][k] = R[k][0] * rod_platform[j][0] + R[k][1] * rod_platform[j][1]
                       + R[k][2] * rod_platform[j][2];
            P[j][k] = p[k] + Rb[j][k];
        }
    }
}

/* rod vectors d_j = P_j - a_j(q_j) and the rods' lengths rho_j(q_j) */
static void rod_vectors(double P[N_RODS][3], const double *q, double d[N_RODS][3],
                        double rho[N_RODS])
{
    int j, k;
    for (j = 0; j < N_RODS; j++) {
        double move = rod_kind[j] == PKM_SLIDE ? q[rod_joint[j]] : 0.0;
        for (k = 0; k < 3; k++)
            d[j][k] = P[j][k] - rod_base[j][k] - move * rod_axis[j][k];
#if HAS_CRANKS
        if (rod_kind[j] == PKM_CRANK) {
            double c = cos(q[rod_joint[j]] * DEG), s = sin(q[rod_joint[j]] * DEG);
            for (k = 0; k < 3; k++)
                d[j][k] = P[j][k] - crank_pivot[j][k] - crank_offset[j] * rod_axis[j][k]
                          - crank_radius[j] * (c * crank_e1[j][k] + s * crank_e2[j][k]);
        }
#endif
        rho[j] = rod_kind[j] == PKM_STRUT ? rod_length[j] + q[rod_joint[j]] : rod_length[j];
    }
}

#if FULL_POSE
#define N_POSE 6
#elif PLANAR
#define N_POSE 2
#else
#define N_POSE 3
#endif

/* rows of A: (d_j, (R b_j) x d_j) (translational: d_j) */
static void parallel_rows(double d[N_RODS][3], double Rb[N_RODS][3],
                          double A[N_RODS][N_POSE])
{
    int j;
    for (j = 0; j < N_RODS; j++) {
        A[j][0] = d[j][0]; A[j][1] = d[j][1];
#if !PLANAR
        A[j][2] = d[j][2];
#endif
#if FULL_POSE
        A[j][3] = Rb[j][1] * d[j][2] - Rb[j][2] * d[j][1];
        A[j][4] = Rb[j][2] * d[j][0] - Rb[j][0] * d[j][2];
        A[j][5] = Rb[j][0] * d[j][1] - Rb[j][1] * d[j][0];
#else
        (void)Rb;
#endif
    }
}

/* Gaussian elimination with partial pivoting: solves M x = rhs in place (rhs -> x) and returns
   det M (0 when a pivot vanishes: singular) */
static double solve_linear(double M[N_POSE][N_POSE], double rhs[N_POSE])
{
    int i, k, r, piv;
    double det = 1.0;
    for (k = 0; k < N_POSE; k++) {
        double best = fabs(M[k][k]);
        piv = k;
        for (r = k + 1; r < N_POSE; r++)
            if (fabs(M[r][k]) > best) { best = fabs(M[r][k]); piv = r; }
        if (!(best > 0.0)) return 0.0;
        if (piv != k) {
            for (i = 0; i < N_POSE; i++) {
                double t = M[k][i]; M[k][i] = M[piv][i]; M[piv][i] = t;
            }
            { double t = rhs[k]; rhs[k] = rhs[piv]; rhs[piv] = t; }
            det = -det;
        }
        det *= M[k][k];
        for (r = k + 1; r < N_POSE; r++) {
            double f = M[r][k] / M[k][k];
            for (i = k; i < N_POSE; i++) M[r][i] -= f * M[k][i];
            rhs[r] -= f * rhs[k];
        }
    }
    for (k = N_POSE - 1; k >= 0; k--) {
        for (i = k + 1; i < N_POSE; i++) rhs[k] -= M[k][i] * rhs[i];
        rhs[k] /= M[k][k];
    }
    return det;
}

/* sign of det A at a configuration (0: singular) */
static int mode_sign(double d[N_RODS][3], double Rb[N_RODS][3])
{
    double A[N_RODS][N_POSE], rhs[N_POSE] = {0};
    double det;
    parallel_rows(d, Rb, A);
    det = solve_linear(A, rhs);
    return det > 0.0 ? 1 : (det < 0.0 ? -1 : 0);
}

#if !POSITION_CONTROLLED
/* inverse model: joints q of the platform position p and rotation R */
static int inverse_model(const double p[3], double R[3][3], double *q)
{
    double P[N_RODS][3], Rb[N_RODS][3], d[N_RODS][3], rho[N_RODS];
    int j, sign;
    platform_points(p, R, P, Rb);
    for (j = 0; j < N_RODS; j++) {
        double w[3], ww, s, radicand, lsq = rod_length[j] * rod_length[j];
        w[0] = P[j][0] - rod_base[j][0];
        w[1] = P[j][1] - rod_base[j][1];
        w[2] = P[j][2] - rod_base[j][2];
        ww = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
        if (rod_kind[j] == PKM_STRUT) {
            q[j] = sqrt(ww) - rod_length[j];
            continue;
        }
#if HAS_CRANKS
        if (rod_kind[j] == PKM_CRANK) {
            double v[3], vw, v1, v2, perp, g, amplitude, cosine, angle;
            v[0] = P[j][0] - crank_pivot[j][0];
            v[1] = P[j][1] - crank_pivot[j][1];
            v[2] = P[j][2] - crank_pivot[j][2];
            vw = v[0] * rod_axis[j][0] + v[1] * rod_axis[j][1] + v[2] * rod_axis[j][2]
                 - crank_offset[j];
            v1 = v[0] * crank_e1[j][0] + v[1] * crank_e1[j][1] + v[2] * crank_e1[j][2];
            v2 = v[0] * crank_e2[j][0] + v[1] * crank_e2[j][1] + v[2] * crank_e2[j][2];
            perp = sqrt(v1 * v1 + v2 * v2);
            g = vw * vw + perp * perp + crank_radius[j] * crank_radius[j] - lsq;
            amplitude = 2.0 * crank_radius[j] * perp;
            cosine = g / amplitude;
            if (!(fabs(cosine) <= 1.0)) {
                if (fabs(g) - amplitude <= boundary_tol * lsq && amplitude > 0.0)
                    cosine = cosine > 0.0 ? 1.0 : -1.0;  /* rounding at the boundary */
                else return PKM_UNREACHABLE;
            }
            angle = atan2(v2, v1) + rod_branch[j] * acos(cosine);
            angle = fmod(angle + 3.14159265358979323846, 2.0 * 3.14159265358979323846);
            if (angle < 0.0) angle += 2.0 * 3.14159265358979323846;
            q[j] = (angle - 3.14159265358979323846) / DEG;  /* [-180, 180) degrees */
            continue;
        }
#endif
        s = w[0] * rod_axis[j][0] + w[1] * rod_axis[j][1] + w[2] * rod_axis[j][2];
        radicand = lsq - (ww - s * s);
        if (radicand < 0.0) {
            if (radicand > -boundary_tol * lsq) radicand = 0.0;  /* rounding at the boundary */
            else return PKM_UNREACHABLE;
        }
        q[j] = s + rod_branch[j] * sqrt(radicand);
    }
    rod_vectors(P, q, d, rho);
    sign = mode_sign(d, Rb);
    if (sign == 0) return PKM_SINGULAR;
    if (sign != working_mode) return PKM_OTHER_MODE;
    return 0;
}
#endif

#if FULL_POSE
""" + TURN_C + r"""#endif

#if POSITION_CONTROLLED
/* inverse model of a machine whose orientation follows its position (the Verne-type module:
   two rods per slide): Newton on the rod lengths |d_j| - rho_j = 0 for the rotation R and the
   joints q, the position p given, from (R, q), each step bounded; then the working branch of
   every rod (q = s + branch sqrt(...), pkmkit's check) and the working assembly mode */
static int position_inverse(const double p[3], double R[3][3], double *q)
{
    double P[N_RODS][3], Rb[N_RODS][3], d[N_RODS][3], rho[N_RODS];
    double A[N_POSE][N_POSE], e[N_POSE];
    int it, j, k;
    for (it = 0; it <= FK_MAX_ITER; it++) {
        double worst = 0.0, step = 0.0, angle, bound = 1.0;
        platform_points(p, R, P, Rb);
        rod_vectors(P, q, d, rho);
        for (j = 0; j < N_RODS; j++) {
            double len = sqrt(d[j][0] * d[j][0] + d[j][1] * d[j][1] + d[j][2] * d[j][2]);
            if (!(len > 0.0)) return PKM_SINGULAR;
            e[j] = len - rho[j];
            if (!(fabs(e[j]) <= worst)) worst = e[j] != e[j] ? 1e300 : fabs(e[j]);
            for (k = 0; k < 3; k++) d[j][k] /= len;
            /* d e_j = (R b_j x u_j) . w - (u_j . axis_j) dq */
            A[j][0] = Rb[j][1] * d[j][2] - Rb[j][2] * d[j][1];
            A[j][1] = Rb[j][2] * d[j][0] - Rb[j][0] * d[j][2];
            A[j][2] = Rb[j][0] * d[j][1] - Rb[j][1] * d[j][0];
            A[j][3] = A[j][4] = A[j][5] = 0.0;
            A[j][3 + rod_joint[j]] = -(d[j][0] * rod_axis[j][0] + d[j][1] * rod_axis[j][1]
                                       + d[j][2] * rod_axis[j][2]);
        }
        if (worst <= fk_tol) break;
        if (it == FK_MAX_ITER || !(worst < max_coordinate)) return PKM_NOT_CONVERGED;
        for (j = 0; j < N_POSE; j++) e[j] = -e[j];
        if (solve_linear(A, e) == 0.0) return PKM_SINGULAR;
        angle = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
        for (j = 0; j < N_JOINTS; j++) if (fabs(e[3 + j]) > step) step = fabs(e[3 + j]);
        if (!(angle == angle) || !(step == step)) return PKM_NOT_CONVERGED;
        if (step > max_step) bound = max_step / step;
        if (angle * bound > 0.25) bound = 0.25 / angle;
        for (j = 0; j < 3; j++) e[j] *= bound;
        turn(R, e);
        for (j = 0; j < N_JOINTS; j++) q[j] += bound * e[3 + j];
    }
    platform_points(p, R, P, Rb);
    for (j = 0; j < N_RODS; j++) {  /* the working branch: pkmkit's closed form gives q back */
        double w[3], ww, s, radicand, lsq = rod_length[j] * rod_length[j];
        for (k = 0; k < 3; k++) w[k] = P[j][k] - rod_base[j][k];
        ww = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
        s = w[0] * rod_axis[j][0] + w[1] * rod_axis[j][1] + w[2] * rod_axis[j][2];
        radicand = lsq - (ww - s * s);
        if (radicand < 0.0) radicand = 0.0;
        if (!(fabs(s + rod_branch[j] * sqrt(radicand) - q[rod_joint[j]]) <= branch_tol))
            return PKM_OTHER_MODE;
    }
    rod_vectors(P, q, d, rho);
    j = mode_sign(d, Rb);
    if (j == 0) return PKM_SINGULAR;
    return j == working_mode ? 0 : PKM_OTHER_MODE;
}

/* the last rotation and joints solved (the next inverse starts there; kinematicsHome resets) */
static double last_R[3][3];
static double last_q[N_JOINTS];
static int last_set = 0;

static void remember(double R[3][3], const double *q)
{
    int i, k;
    for (i = 0; i < 3; i++)
        for (k = 0; k < 3; k++) last_R[i][k] = R[i][k];
    for (i = 0; i < N_JOINTS; i++) last_q[i] = q[i];
    last_set = 1;
}

/* a start for position_inverse: each joint the mean of its rods' closed forms on their working
   branches with the rotation R held (q unchanged where a rod cannot close) */
static void branch_start(const double p[3], double R[3][3], double *q)
{
    double P[N_RODS][3], Rb[N_RODS][3], sum[N_JOINTS], count[N_JOINTS];
    int j, k;
    platform_points(p, R, P, Rb);
    for (j = 0; j < N_JOINTS; j++) sum[j] = count[j] = 0.0;
    for (j = 0; j < N_RODS; j++) {
        double w[3], ww, s, radicand, lsq = rod_length[j] * rod_length[j];
        for (k = 0; k < 3; k++) w[k] = P[j][k] - rod_base[j][k];
        ww = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
        s = w[0] * rod_axis[j][0] + w[1] * rod_axis[j][1] + w[2] * rod_axis[j][2];
        radicand = lsq - (ww - s * s);
        if (!(radicand >= 0.0)) return;
        sum[rod_joint[j]] += s + rod_branch[j] * sqrt(radicand);
        count[rod_joint[j]] += 1.0;
    }
    for (j = 0; j < N_JOINTS; j++) q[j] = sum[j] / count[j];
}

/* position_inverse from the last solution, then from home */
static int position_inverse_from_last(const double p[3], double *q)
{
    double R[3][3];
    int j, i, status = PKM_NOT_CONVERGED;
    if (last_set) {
        for (i = 0; i < 3; i++)
            for (j = 0; j < 3; j++) R[i][j] = last_R[i][j];
        for (j = 0; j < N_JOINTS; j++) q[j] = last_q[j];
        branch_start(p, R, q);
        status = position_inverse(p, R, q);
    }
    if (status != 0) {
        rotation_from_abc(home_world[3], home_world[4], home_world[5], R);
        for (j = 0; j < N_JOINTS; j++) q[j] = home_joints[j];
        branch_start(p, R, q);
        status = position_inverse(p, R, q);
    }
    if (status == 0) remember(R, q);
    return status;
}
#endif

/* direct model: Newton on the rod lengths |d_j| - rho_j = 0 from (p, R), each step bounded */
static int direct_model(const double *q, double p[3], double R[3][3])
{
    double P[N_RODS][3], Rb[N_RODS][3], d[N_RODS][3], rho[N_RODS];
    double A[N_RODS][N_POSE], e[N_POSE];
    int it, j, k;
    for (it = 0; it <= FK_MAX_ITER; it++) {
        double worst = 0.0, step, bound = 1.0, det;
        platform_points(p, R, P, Rb);
        rod_vectors(P, q, d, rho);
        for (j = 0; j < N_RODS; j++) {
            double len = sqrt(d[j][0] * d[j][0] + d[j][1] * d[j][1] + d[j][2] * d[j][2]);
            if (!(len > 0.0)) return PKM_SINGULAR;
            e[j] = len - rho[j];
            if (fabs(e[j]) > worst || e[j] != e[j]) worst = e[j] != e[j] ? 1e300 : fabs(e[j]);
            for (k = 0; k < 3; k++) d[j][k] /= len;  /* unit rods: rows of d|d|/d(p, w) */
        }
        if (worst <= fk_tol) {
            int sign = mode_sign(d, Rb);
            if (sign == 0) return PKM_SINGULAR;
            return sign == working_mode ? 0 : PKM_OTHER_MODE;
        }
        if (it == FK_MAX_ITER || !(worst < max_coordinate)) break;
        parallel_rows(d, Rb, A);
        for (j = 0; j < N_POSE; j++) e[j] = -e[j];
        det = solve_linear(A, e);
        if (det == 0.0 || det != det) return PKM_SINGULAR;
#if PLANAR
        step = sqrt(e[0] * e[0] + e[1] * e[1]);
#else
        step = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
#endif
        if (step > max_step) bound = max_step / step;
#if FULL_POSE
        {
            double angle = sqrt(e[3] * e[3] + e[4] * e[4] + e[5] * e[5]);
            if (angle * bound > 0.25) bound = 0.25 / angle;
            e[3] *= bound; e[4] *= bound; e[5] *= bound;
            turn(R, &e[3]);
        }
#endif
        p[0] += bound * e[0]; p[1] += bound * e[1];
#if !PLANAR
        p[2] += bound * e[2];
#endif
    }
    return PKM_NOT_CONVERGED;
}

static int finite_inputs(const double *v, int n)
{
    int i;
    for (i = 0; i < n; i++)
        if (!(fabs(v[i]) <= max_coordinate)) return 0;
    return 1;
}

int kinematicsInverse(const EmcPose *pos, double *joints, const KINEMATICS_INVERSE_FLAGS *iflags,
                      KINEMATICS_FORWARD_FLAGS *fflags)
{
    double p[3], R[3][3], q[N_RODS], abc[3] = {0.0, 0.0, 0.0};  /* q: N_JOINTS used */
    int j, status;
    (void)iflags;
    (void)fflags;
    p[0] = pos->tran.x; p[1] = pos->tran.y; p[2] = PLANAR ? 0.0 : pos->tran.z;
#if FULL_POSE && !POSITION_CONTROLLED
    abc[0] = pos->a; abc[1] = pos->b; abc[2] = pos->c;
#endif
    if (!finite_inputs(p, 3) || !finite_inputs(abc, 3)) return PKM_INVALID;
    rotation_from_abc(abc[0], abc[1], abc[2], R);
#if POSITION_CONTROLLED
    status = position_inverse_from_last(p, q);
#else
    status = inverse_model(p, R, q);
#endif
    if (status != 0) return status;
    for (j = 0; j < N_JOINTS; j++) joints[j] = q[j];
    return 0;
}

int kinematicsForward(const double *joints, EmcPose *pos, const KINEMATICS_FORWARD_FLAGS *fflags,
                      KINEMATICS_INVERSE_FLAGS *iflags)
{
    double p[3], R[3][3], start[3];
    int status, unset;
    (void)fflags;
    (void)iflags;
    if (!finite_inputs(joints, N_JOINTS)) return PKM_INVALID;
    /* start from the previous position (LinuxCNC passes it in *pos), then from home */
    status = PKM_NOT_CONVERGED;
    p[0] = pos->tran.x; p[1] = pos->tran.y; p[2] = PLANAR ? 0.0 : pos->tran.z;
    start[0] = pos->a; start[1] = pos->b; start[2] = pos->c;
    if (!FULL_POSE) start[0] = start[1] = start[2] = 0.0;
    unset = p[0] == 0.0 && p[1] == 0.0 && p[2] == 0.0 && start[0] == 0.0 && start[1] == 0.0
            && start[2] == 0.0;  /* LinuxCNC's initial, unset position: start from home */
    if (!unset && finite_inputs(p, 3) && finite_inputs(start, 3)) {
        rotation_from_abc(start[0], start[1], start[2], R);
        status = direct_model(joints, p, R);
    } else {
        start[0] = home_world[3]; start[2] = home_world[5];
    }
    if (status != 0) {
        p[0] = home_world[0]; p[1] = home_world[1]; p[2] = home_world[2];
        rotation_from_abc(home_world[3], home_world[4], home_world[5], R);
        status = direct_model(joints, p, R);
        if (status != 0) return status;
    }
    pos->tran.x = p[0]; pos->tran.y = p[1]; pos->tran.z = p[2];
#if POSITION_CONTROLLED
    remember(R, joints);
    pos->a = 0.0; pos->b = 0.0; pos->c = 0.0;  /* world X Y Z: the tilt follows */
#elif FULL_POSE
    abc_from_rotation(R, start[0], start[2], &pos->a, &pos->b, &pos->c);
#else
    pos->a = 0.0; pos->b = 0.0; pos->c = 0.0;
#endif
    pos->u = 0.0; pos->v = 0.0; pos->w = 0.0;
    return 0;
}

int kinematicsHome(EmcPose *world, double *joint, KINEMATICS_FORWARD_FLAGS *fflags,
                   KINEMATICS_INVERSE_FLAGS *iflags)
{
    int j;
    world->tran.x = home_world[0]; world->tran.y = home_world[1]; world->tran.z = home_world[2];
    world->a = home_world[3]; world->b = home_world[4]; world->c = home_world[5];
    world->u = 0.0; world->v = 0.0; world->w = 0.0;
    for (j = 0; j < N_JOINTS; j++) joint[j] = home_joints[j];
#if POSITION_CONTROLLED
    last_set = 0;  /* the next inverse starts from home */
#endif
    *fflags = 0;
    *iflags = 0;
    return 0;
}

KINEMATICS_TYPE kinematicsType(void)
{
    return KINEMATICS_BOTH;
}
"""
