/* The TriMule 600's closed-form starts (trimule_forms.py start_unknowns, inverse_unknowns and
 * direct_unknowns, statement for statement; chain_starts.closed_starts, closed_direct_starts;
 * issue 22 §1, sessions 33 and 35 — moved here from chain_one.c for the batch entry of
 * chain_closed_rows.c). cl: trimule_forms.native_constants without the family's code: c1, c2,
 * spindle, L, l, H, h. */
#include "chain_one.h"

#include <math.h>

/* The kind's closed-form start (chain_starts.closed_starts; the Tripteor's: chain_one_tripteor.c;
 * the TriMule's: trimule_forms.py inverse_unknowns, start_unknowns): u (27,) on the head's branch
 * (+1: Q5 >= 0, -1: Q5 <= 0, 0: Q4 within a quarter turn of home's); 1, or 0 where it declines. */
enum { CLOSED_SWEEPS = 40 };
static const double CLOSED_TOL = 1e-15, CLOSED_SINGULAR = 1e-3;

/* The platform u[:6] (P = length d, the rotation vector) and the parallel part's joints
 * u[6:25] from the measured leg (length, psi1, theta4; d its unit direction): the tail of
 * trimule_forms.inverse_unknowns and direct_unknowns (_platform_rotvec, _parallel_joints). */
static void closed_joints(const double *cl, double length, double psi, double theta, double dx,
                          double dy, double dz, double *u) {
    const double big = cl[3], small = cl[4], hb = cl[5], hs = cl[6];
    double ct = cos(theta), st = sin(theta), cp = cos(psi), sp = sin(psi);
    u[0] = length * dx, u[1] = length * dy, u[2] = length * dz;
    /* the platform's rotation vector: Rx(-psi1) Ry(-theta4) Rz(pi) by its quaternion, w >= 0 */
    double ch = cos(-0.5 * psi), sh = sin(-0.5 * psi), cq = cos(-0.5 * theta),
           sq = sin(-0.5 * theta);
    double w = -sh * sq, qx = ch * sq, qy = -sh * cq, qz = ch * cq;
    double flip = w < 0 ? -1.0 : 1.0;
    w *= flip, qx *= flip, qy *= flip, qz *= flip;
    double norm = sqrt(qx * qx + qy * qy + qz * qz), scale = 2.0 * atan2(norm, w) / norm;
    u[3] = scale * qx, u[4] = scale * qy, u[5] = scale * qz;
    /* the parallel part's joints (trimule_forms._parallel_joints) */
    double e1x = big - small * ct + 2 * length * st, e1y = small * st + 2 * length * ct;
    double e3x = -big + small * ct + 2 * length * st, e3y = -small * st + 2 * length * ct;
    double lx = -length * st, ly = length * ct * sp - hs * cp + hb, lz = length * ct * cp + hs * sp;
    double q2 = sqrt(lx * lx + ly * ly + lz * lz), theta2 = asin(-lx / q2),
           psi2 = atan2(ly, lz);
    double ca = cos(theta2), sa = sin(theta2), cb = cos(psi2 - psi), sb = sin(psi2 - psi);
    double cc = ct, sc = -st;
    double g00 = ca * cc - sa * cb * sc, g10 = sb * sc, g20 = -sa * cc - ca * cb * sc;
    double g21 = ca * sb, g22 = -sa * sc + ca * cb * cc;
    double theta1 = atan2(e1x, e1y), theta3 = atan2(e3x, e3y);
    double *v = u + 6;
    v[0] = psi, v[1] = theta1, v[2] = 0.5 * hypot(e1x, e1y), v[3] = 0.0, v[4] = 0.0;
    v[5] = theta - theta1, v[6] = psi2, v[7] = theta2, v[8] = q2, v[9] = atan2(g10, g00);
    v[10] = asin(g20 < -1.0 ? -1.0 : (g20 > 1.0 ? 1.0 : g20)), v[11] = atan2(g21, g22);
    v[12] = theta3, v[13] = 0.5 * hypot(e3x, e3y), v[14] = 0.0, v[15] = 0.0;
    v[16] = theta3 - theta, v[17] = theta, v[18] = length;
}

int pk_one_trimule_start(const double *cl, double tool, const double *target, double branch,
                         double *u) {
    const double c1 = cl[0], c2 = cl[1], reach = cl[2] + tool;
    double ax = target[3], ay = target[4], az = target[5];
    double wx = target[0] - reach * ax, wy = target[1] - reach * ay, wz = target[2] - reach * az;
    double vx = wx, vy = wy, vz = wz, r, dx, dy, dz, ad, gx, gy, gz;
    if (branch == 0.0) {
        r = sqrt(wx * wx + wy * wy + wz * wz);
        dx = wx / r, dy = wy / r, dz = wz / r;
        double ct = sqrt(dy * dy + dz * dz);
        double along = -ct * ax + dx * (dy * ay + dz * az) / ct;
        branch = along >= 0 ? 1.0 : -1.0;
    }
    int done = 0;
    for (int sweep = 0; sweep < CLOSED_SWEEPS && !done; sweep++) {
        r = sqrt(vx * vx + vy * vy + vz * vz);
        dx = vx / r, dy = vy / r, dz = vz / r;
        ad = ax * dx + ay * dy + az * dz;
        gx = ax - ad * dx, gy = ay - ad * dy, gz = az - ad * dz;
        double k = c2 * branch / sqrt(gx * gx + gy * gy + gz * gz);
        double nx = wx - k * gx, ny = wy - k * gy, nz = wz - k * gz;
        double change = fabs(nx - vx) + fabs(ny - vy) + fabs(nz - vz);
        vx = nx, vy = ny, vz = nz;
        done = change <= CLOSED_TOL;
    }
    r = sqrt(vx * vx + vy * vy + vz * vz);
    dx = vx / r, dy = vy / r, dz = vz / r;
    ad = ax * dx + ay * dy + az * dz;
    gx = ax - ad * dx, gy = ay - ad * dy, gz = az - ad * dz;
    double gn = sqrt(gx * gx + gy * gy + gz * gz);
    if (!(done && gn >= CLOSED_SINGULAR)) return 0;
    double length = r - c1, theta = asin(-dx), psi = atan2(dy, dz);
    double ct = cos(theta), st = sin(theta), cp = cos(psi), sp = sin(psi);
    closed_joints(cl, length, psi, theta, dx, dy, dz, u);
    /* x_P = (-cos th4, -sin th4 sin psi1, -sin th4 cos psi1), y_P = (0, -cos psi1, sin psi1) */
    u[25] = atan2(branch * (-cp * ay + sp * az), branch * (-ct * ax - st * sp * ay - st * cp * az));
    u[26] = branch * atan2(gn, ad);
    for (int i = 0; i < 27; i++)
        if (!isfinite(u[i])) return 0;
    return 1;
}

/* The TriMule's closed-form direct start (trimule_forms.direct_unknowns and measured_leg,
 * statement for statement; chain_starts.closed_direct_starts): u (27,) from q (5,) = Q1..Q5
 * (the measured leg by DIRECT_BISECTIONS bisections and two Newton steps, then closed_joints);
 * 1, or 0 where it declines (no assembly in the working mode, not finite). */
enum { DIRECT_BISECTIONS = 30 };

static double leg_h(double a, double b, double k, double t) {
    double v = a + b * cos(t);
    return sqrt(v > 0.0 ? v : 0.0) * sin(t) - k;
}

int pk_one_trimule_direct(const double *cl, const double *q, double *u) {
    const double big = cl[3], small = cl[4], hb = cl[5], hs = cl[6];
    double q1 = q[0], q2 = q[1], q3 = q[2];
    if (!(q1 > 0.0 && q2 > 0.0 && q3 > 0.0 && isfinite(q1) && isfinite(q2) && isfinite(q3)))
        return 0;
    double k = (q1 * q1 - q3 * q3) / big;
    double a = 2 * (q1 * q1 + q3 * q3) - big * big - small * small, b = 2 * big * small;
    double c_star = (-a + sqrt(a * a + 3 * b * b)) / (3 * b);
    double limit = acos(c_star < -1.0 ? -1.0 : (c_star > 1.0 ? 1.0 : c_star));
    double lo = -limit, hi = limit;
    if (!(a - b > 0 && leg_h(a, b, k, lo) <= 0 && leg_h(a, b, k, hi) >= 0)) return 0;
    for (int i = 0; i < DIRECT_BISECTIONS; i++) {
        double mid = 0.5 * (lo + hi);
        if (leg_h(a, b, k, mid) > 0) hi = mid; else lo = mid;
    }
    double theta = 0.5 * (lo + hi);
    for (int i = 0; i < 2; i++) {  /* Newton: h' = (3B c^2 + 2A c - B) / (2u) */
        double w = sqrt(a + b * cos(theta)), c = cos(theta);
        theta = theta - leg_h(a, b, k, theta) * 2 * w / (3 * b * c * c + 2 * a * c - b);
    }
    double length = 0.5 * sqrt(a + b * cos(theta));
    double ca = 2 * hb * length * cos(theta), cb = -2 * hb * hs;
    double d = q2 * q2 - length * length - hs * hs - hb * hb, radius = hypot(ca, cb);
    if (!(fabs(d) <= radius)) return 0;
    double ratio = d / radius;
    double psi = atan2(ca, cb) - acos(ratio < -1.0 ? -1.0 : (ratio > 1.0 ? 1.0 : ratio));
    psi = pk_pymod(psi + PK_PI, 2 * PK_PI) - PK_PI;
    double ct = cos(theta), st = sin(theta), cp = cos(psi), sp = sin(psi);
    closed_joints(cl, length, psi, theta, -st, ct * sp, ct * cp, u);
    u[0] = -length * st, u[1] = length * ct * sp, u[2] = length * ct * cp;
    u[25] = q[3], u[26] = q[4];
    for (int i = 0; i < 27; i++)
        if (!isfinite(u[i])) return 0;
    return 1;
}

