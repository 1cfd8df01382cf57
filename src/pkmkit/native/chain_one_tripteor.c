/* The Tripteor X7's near-closed-form start of the one-pose inverse (machines/tripteor_forms.py
 * start_unknowns and inverse_unknowns, statement for statement; chain_starts.closed_starts;
 * issue 22 §1, session 34). The platform's two angles (psi, sigma) solve the fixed point
 * (psi, sigma) = Phi(W - c1 x'(psi, sigma)), Phi the explicit angles of an MPS origin P, by
 * Newton's iterations with the Jacobian by differences (chord steps once a step is small), from
 * the platform of c1 = 0; then every joint variable. k: tripteor_forms.constants (24,): c1,
 * spindle, L, D, R_m by rows (9), p_m (3), b2 (3), b3 (3), the assembly's signs. */
#include "chain_one.h"

#include <math.h>

enum { STEPS = 10 };  /* tripteor_forms.INVERSE_STEPS */
static const double TOL = 1e-15, STALL = 1e-13, SINGULAR = 1e-3, H = 1e-7, REFRESH = 1e-6;

/* tripteor_forms._explicit: psi, sigma of the platform whose MPS origin is p (NaN without
 * assembly). */
static void explicit_angles(const double *k, double px, double py, double pz, double *psi,
                            double *sigma) {
    double ax2 = -k[3], ay2 = -0.5 * k[2];
    double r = sqrt(px * px + pz * pz);
    double a = atan2(pz, px) + k[22] * acos(k[15] / r);
    double cp = cos(a), sp = sin(a);
    double ea = -sp * (px - ax2) + cp * pz, eb = -(py - ay2);
    double rho = sqrt(ea * ea + eb * eb);
    *psi = a;
    *sigma = atan2(eb, ea) + k[23] * acos(-(k[16] - k[13]) / rho);
}

/* tripteor_forms._head: R51's columns (x, y, z: 9), z_P, a.z_P, |g| and x' = -b g/|g|. */
typedef struct {
    double x[3], y[3], z[3], zp[3], az, gn, xq[3];
} head_t;

static void head(const double *k, double psi, double sigma, const double *a, double b,
                 head_t *o) {
    double cp = cos(psi), sp = sin(psi), cs = cos(sigma), ss = sin(sigma);
    o->x[0] = -sp * cs, o->x[1] = -ss, o->x[2] = cp * cs;
    o->y[0] = sp * ss, o->y[1] = -cs, o->y[2] = -cp * ss;
    o->z[0] = cp, o->z[1] = 0.0 * cp, o->z[2] = sp;
    for (int i = 0; i < 3; i++) o->zp[i] = o->x[i] * k[6] + o->y[i] * k[9] + o->z[i] * k[12];
    o->az = a[0] * o->zp[0] + a[1] * o->zp[1] + a[2] * o->zp[2];
    double g[3];
    for (int i = 0; i < 3; i++) g[i] = a[i] - o->az * o->zp[i];
    o->gn = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    double f = -b / o->gn;
    for (int i = 0; i < 3; i++) o->xq[i] = f * g[i];
}

/* tripteor_forms._step: Phi(psi, sigma). */
static void step(const double *k, double psi, double sigma, const double *w, const double *a,
                 double b, double *f_psi, double *f_sigma) {
    head_t o;
    head(k, psi, sigma, a, b, &o);
    double c1 = k[0];
    explicit_angles(k, w[0] - c1 * o.xq[0], w[1] - c1 * o.xq[1], w[2] - c1 * o.xq[2], f_psi,
                    f_sigma);
}

/* Hamilton product (w, x, y, z). */
static void qmul(const double *p, const double *q, double *out) {
    out[0] = p[0] * q[0] - p[1] * q[1] - p[2] * q[2] - p[3] * q[3];
    out[1] = p[0] * q[1] + p[1] * q[0] + p[2] * q[3] - p[3] * q[2];
    out[2] = p[0] * q[2] - p[1] * q[3] + p[2] * q[0] + p[3] * q[1];
    out[3] = p[0] * q[3] + p[1] * q[2] - p[2] * q[1] + p[3] * q[0];
}

/* tripteor_forms._legs: the platform (B1, R51's rotation vector) and every joint of the legs
 * into u[:19] from psi, sigma, R51's columns (o->x, y, z) and B1. */
static void legs(const double *k, double psi, double sigma, const head_t *o, const double *b1,
                 double *u) {
    double b2[3], b3[3];
    for (int i = 0; i < 3; i++) {
        b2[i] = o->x[i] * k[16] + o->y[i] * k[17] + o->z[i] * k[18];
        b3[i] = o->x[i] * k[19] + o->y[i] * k[20] + o->z[i] * k[21];
    }
    for (int i = 0; i < 3; i++) u[i] = b1[i];
    /* R51's rotation vector: (r, r, 0, 0) (cos psi/2, 0, 0, sin psi/2) F (cos sigma/2, 0, 0,
     * sin sigma/2), w >= 0 */
    double r = sqrt(0.5), ch = cos(0.5 * psi), sh = sin(0.5 * psi), cs = cos(0.5 * sigma),
           ss = sin(0.5 * sigma);
    double qa[4] = {r * ch, r * ch, -r * sh, r * sh}, qf[4] = {0.5, 0.5, 0.5, 0.5}, qb[4],
           qs[4] = {cs, 0.0 * cs, 0.0 * cs, ss}, q[4];
    qmul(qa, qf, qb);
    qmul(qb, qs, q);
    double flip = q[0] < 0 ? -1.0 : 1.0;
    for (int i = 0; i < 4; i++) q[i] *= flip;
    double norm = sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    double scale = 2.0 * atan2(norm, q[0]) / norm;
    u[3] = scale * q[1], u[4] = scale * q[2], u[5] = scale * q[3];
    double cp = cos(psi), sp = sin(psi), big = k[2], dd = k[3];
    double e1b1 = -sp * b1[0] + cp * b1[2], theta1 = atan2(-b1[1], e1b1);
    double d3[3] = {b1[0] + b3[0], b1[1] + b3[1] + big, b1[2] + b3[2]};
    double e1b3 = -sp * d3[0] + cp * d3[2], theta3 = atan2(-d3[1], e1b3);
    double d2[3] = {b1[0] + b2[0] + dd, b1[1] + b2[1] + 0.5 * big, b1[2] + b2[2]};
    double q2 = sqrt(d2[0] * d2[0] + d2[1] * d2[1] + d2[2] * d2[2]);
    double psi2 = atan2(-d2[1], d2[2]);
    double theta2 = atan2(d2[0], sqrt(d2[1] * d2[1] + d2[2] * d2[2]));
    double c2 = cos(psi2), s2 = sin(psi2), ct2 = cos(theta2), st2 = sin(theta2);
    double mx = ct2 * o->x[0] + s2 * st2 * o->x[1] - c2 * st2 * o->x[2];
    double my = c2 * o->x[1] + s2 * o->x[2];
    double eta2 = atan2(-mx, my);
    double phi2 = atan2(d2[0] * o->z[0] + d2[1] * o->z[1] + d2[2] * o->z[2],
                        d2[0] * o->y[0] + d2[1] * o->y[1] + d2[2] * o->y[2]);
    double half = 0.5 * PK_PI, *v = u + 6;
    v[0] = psi, v[1] = theta1, v[2] = hypot(e1b1, b1[1]), v[3] = sigma - theta1 + half;
    v[4] = psi2, v[5] = theta2, v[6] = eta2, v[7] = q2, v[8] = phi2, v[9] = psi;
    v[10] = theta3, v[11] = hypot(e1b3, d3[1]), v[12] = sigma - theta3 + half;
}

/* tripteor_forms._fill: every unknown into u (21,) from the platform angles; returns |g|. */
static double fill(const double *k, double psi, double sigma, const double *w, const double *a,
                   double b, double *u) {
    head_t o;
    head(k, psi, sigma, a, b, &o);
    double c1 = k[0], b1[3], xp[3], yp[3];
    for (int i = 0; i < 3; i++)
        b1[i] = w[i] - c1 * o.xq[i] - (o.x[i] * k[13] + o.y[i] * k[14] + o.z[i] * k[15]);
    legs(k, psi, sigma, &o, b1, u);
    for (int i = 0; i < 3; i++) {
        xp[i] = o.x[i] * k[4] + o.y[i] * k[7] + o.z[i] * k[10];
        yp[i] = o.x[i] * k[5] + o.y[i] * k[8] + o.z[i] * k[11];
    }
    u[19] = atan2(o.xq[0] * yp[0] + o.xq[1] * yp[1] + o.xq[2] * yp[2],
                  o.xq[0] * xp[0] + o.xq[1] * xp[1] + o.xq[2] * xp[2]);
    u[20] = b * atan2(o.gn, -o.az);
    return o.gn;
}

/* newton2's equations: the inverse's fixed point of Phi (data: w, a, b), the direct model's
 * leg 2 (data: q). */
enum { INVERSE = 0, DIRECT = 1 };
static int newton2(int which, const double *k, double *z0, double *z1, int steps,
                   const double *data);

int pk_one_tripteor_start(const double *k, double tool, const double *target, double branch,
                          double *u) {
    const double *a = target + 3;
    double reach = k[1] + tool, w[3], psi, sigma;
    for (int i = 0; i < 3; i++) w[i] = target[i] - reach * a[i];
    explicit_angles(k, w[0], w[1], w[2], &psi, &sigma);  /* c1 = 0 */
    if (branch == 0.0) {  /* the branch whose Q4 is within a quarter turn of home's */
        head_t o;
        head(k, psi, sigma, a, 1.0, &o);
        double along = 0.0;
        for (int i = 0; i < 3; i++)
            along += a[i] * (o.x[i] * k[4] + o.y[i] * k[7] + o.z[i] * k[10]);
        branch = -along >= 0 ? 1.0 : -1.0;
    }
    double b = branch, data[7] = {w[0], w[1], w[2], a[0], a[1], a[2], branch};
    int done = newton2(INVERSE, k, &psi, &sigma, STEPS, data);
    double gn = fill(k, psi, sigma, w, a, b, u);
    if (!(done && gn >= SINGULAR)) return 0;
    for (int i = 0; i < 21; i++)
        if (!isfinite(u[i])) return 0;
    return 1;
}

/* ---------------------------------------------------------------- the direct model's start */

/* tripteor_forms.FOUR_BAR, DIRECT_START, DIRECT_STEPS. */
static const double FOUR_BAR = 1.0;
enum { DIRECT_STEPS = 12 };

/* tripteor_forms._platform_of: sigma, B1 and R51's columns (o->x, y, z) at theta1, psi. */
static void platform_of(const double *k, double theta, double psi, double q1, double q3,
                        double *sigma, double *b1, head_t *o) {
    double big = k[2], small = k[24];
    double s1 = q1 * cos(theta), t1 = q1 * sin(theta);
    double ds = s1, dt = t1 - big;
    double rho = sqrt(ds * ds + dt * dt);
    double ca = (q3 * q3 + rho * rho - small * small) / (2 * q3 * rho);
    double alpha = atan2(dt, ds) + FOUR_BAR * acos(ca);
    double s3 = q3 * cos(alpha), t3 = big + q3 * sin(alpha);
    *sigma = atan2(t1 - t3, s1 - s3);
    double cp = cos(psi), sp = sin(psi), cs = cos(*sigma), ss = sin(*sigma);
    o->x[0] = -sp * cs, o->x[1] = -ss, o->x[2] = cp * cs;
    o->y[0] = sp * ss, o->y[1] = -cs, o->y[2] = -cp * ss;
    o->z[0] = cp, o->z[1] = 0.0 * cp, o->z[2] = sp;
    b1[0] = -sp * s1, b1[1] = -t1, b1[2] = cp * s1;
}

/* tripteor_forms._leg2: (B2 - A2).x51 and |B2 - A2| - Q2. */
static void leg2(const double *k, double theta, double psi, const double *q, double *f0,
                 double *f1) {
    double sigma, b1[3], d[3];
    head_t o;
    platform_of(k, theta, psi, q[0], q[2], &sigma, b1, &o);
    for (int i = 0; i < 3; i++) d[i] = b1[i] + o.x[i] * k[16] + o.y[i] * k[17] + o.z[i] * k[18];
    d[0] = d[0] + k[3];
    d[1] = d[1] + 0.5 * k[2];
    *f0 = d[0] * o.x[0] + d[1] * o.x[1] + d[2] * o.x[2];
    *f1 = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) - q[1];
}

/* tripteor_forms._newton2 on one row: Newton's steps on F(z) - shift z = 0 (shift 1: the
 * inverse's fixed point of Phi; 0: the direct model's leg-2 equations) from (z0, z1), the
 * Jacobian by differences, chord steps once a step is below REFRESH; 1 where converged. */
static void equations(int which, const double *k, double z0, double z1, const double *data,
                      double *f0, double *f1) {
    if (which == INVERSE) step(k, z0, z1, data, data + 3, data[6], f0, f1);
    else leg2(k, z0, z1, data, f0, f1);
}

static int newton2(int which, const double *k, double *z0, double *z1, int steps,
                   const double *data) {
    double shift = which == INVERSE ? 1.0 : 0.0, x0 = *z0, x1 = *z1, f0, f1;
    double i00 = 0, i01 = 0, i10 = 0, i11 = 0;
    int done = 0, fresh = 1;
    double last = INFINITY;
    equations(which, k, x0, x1, data, &f0, &f1);
    for (int it = 0; it < steps; it++) {
        double r0 = f0 - shift * x0, r1 = f1 - shift * x1;
        if (fresh) {  /* the Jacobian by differences */
            double a0, a1, c0, c1;
            equations(which, k, x0 + H, x1, data, &a0, &a1);
            equations(which, k, x0, x1 + H, data, &c0, &c1);
            double j00 = (a0 - f0) / H - shift, j10 = (a1 - f1) / H;
            double j01 = (c0 - f0) / H, j11 = (c1 - f1) / H - shift;
            double det = j00 * j11 - j01 * j10;
            i00 = j11 / det, i01 = -j01 / det, i10 = -j10 / det, i11 = j00 / det;
        }
        double d0 = i00 * r0 + i01 * r1, d1 = i10 * r0 + i11 * r1;
        x0 = x0 - d0, x1 = x1 - d1;
        double change = fabs(d0) + fabs(d1);
        if (change <= TOL || (change <= STALL && change >= last)) {  /* or rounding */
            done = 1;
            break;
        }
        last = change;
        fresh = change > REFRESH;
        equations(which, k, x0, x1, data, &f0, &f1);
    }
    *z0 = x0, *z1 = x1;
    return done;
}

int pk_one_tripteor_direct(const double *k, const double *q, double *u) {
    double theta = 17.7023 * (PK_PI / 180.0), psi = 0.2813 * (PK_PI / 180.0);
    int done = newton2(DIRECT, k, &theta, &psi, DIRECT_STEPS, q);
    double sigma, b1[3];
    head_t o;
    platform_of(k, theta, psi, q[0], q[2], &sigma, b1, &o);
    legs(k, psi, sigma, &o, b1, u);
    u[19] = q[3], u[20] = q[4];
    if (!done) return 0;
    for (int i = 0; i < 21; i++)
        if (!isfinite(u[i])) return 0;
    return 1;
}
