/* The full-pose inverse model in one pass per pose: the C twin of
 * pkmkit.machines.full_pose_kernels.inverse_poses (and _pose_rods), statement for statement,
 * in the same order of operations, so that both give the same bits. pk_inverse_poses
 * (inverse_simd.c) runs it, or its vectorised twin eight or four poses at a time (the same
 * operations but sin and cos: q within a few ulps). */
#include "kernels.h"

/* Every rod's actuator coordinate of pose xk (6,) into out (m,) (_pose_rods). */
static void pose_rods(const double *xk, const pk_rods *g, double *out) {
    const double two_pi = 2.0 * PK_PI;
    double px = xk[0], py = xk[1], pz = xk[2];
    double r[9];
    pk_rotation(xk[3], xk[4], xk[5], r);
    for (ptrdiff_t j = 0; j < g->m; j++) {
        const double *b = g->platform + 3 * j;
        double bx = b[0], by = b[1], bz = b[2];
        double qx = px + r[0] * bx + r[1] * by + r[2] * bz;
        double qy = py + r[3] * bx + r[4] * by + r[5] * bz;
        double qz = pz + r[6] * bx + r[7] * by + r[8] * bz;
        if (g->kind[j] == 2) { /* crank */
            const double *pv = g->pivot + 3 * j, *ax = g->axis + 3 * j;
            const double *e1 = g->e1 + 3 * j, *e2 = g->e2 + 3 * j;
            double vx = qx - pv[0], vy = qy - pv[1], vz = qz - pv[2];
            double vw = vx * ax[0] + vy * ax[1] + vz * ax[2] - g->crank_offset[j];
            double v1 = vx * e1[0] + vy * e1[1] + vz * e1[2];
            double v2 = vx * e2[0] + vy * e2[1] + vz * e2[2];
            double perp = sqrt(v1 * v1 + v2 * v2);
            double rr = g->crank_radius[j];
            double gg = vw * vw + perp * perp + rr * rr - g->length_sq[j];
            double amplitude = 2.0 * rr * perp;
            double cosine = amplitude > 0.0 ? gg / amplitude : NAN;
            if (fabs(gg) - amplitude <= g->boundary_tol * g->length_sq[j])
                cosine = pk_min(1.0, pk_max(-1.0, cosine));
            if (cosine > 1.0 || cosine < -1.0 || cosine != cosine) {
                out[j] = NAN;
            } else {
                double angle = atan2(v2, v1) + g->sigma[j] * acos(cosine);
                out[j] = pk_pymod(angle + PK_PI, two_pi) - PK_PI;
            }
            continue;
        }
        const double *a0 = g->base + 3 * j;
        double wxr = qx - a0[0], wyr = qy - a0[1], wzr = qz - a0[2];
        double dist_sq = wxr * wxr + wyr * wyr + wzr * wzr;
        if (g->kind[j] == 1) { /* strut */
            out[j] = sqrt(dist_sq) - g->length[j];
            continue;
        }
        const double *ax = g->axis + 3 * j;
        double s = wxr * ax[0] + wyr * ax[1] + wzr * ax[2];
        double radicand = g->length_sq[j] - dist_sq + s * s;
        if (radicand < 0.0) {
            if (radicand > -g->boundary_tol * g->length_sq[j]) {
                radicand = 0.0;
            } else {
                out[j] = NAN;
                continue;
            }
        }
        out[j] = s + g->sigma[j] * sqrt(radicand);
    }
}

void pk_inverse_poses_scalar(const double *x, ptrdiff_t rows, const pk_rods *rods,
                             const pk_actuators *act, double *q, int64_t *status, double *rod_q) {
    const ptrdiff_t m = rods->m, n = act->n;
    for (ptrdiff_t k = 0; k < rows; k++) {
        const double *xk = x + 6 * k;
        double *qk = q + n * k;
        int valid = 1;
        for (int i = 0; i < 6; i++)
            if (!(fabs(xk[i]) <= 1e9)) valid = 0;
        if (!valid) {
            status[k] = 4;
            for (ptrdiff_t a = 0; a < n; a++) qk[a] = NAN;
            continue;
        }
        pose_rods(xk, rods, rod_q);
        int ok = 1;
        for (ptrdiff_t j = 0; j < m; j++)
            if (!(rod_q[j] == rod_q[j])) ok = 0;
        double spread = 0.0;
        if (ok) {
            for (ptrdiff_t a = 0; a < n; a++) {
                const int64_t *grp = act->groups + act->width * a;
                int64_t count = act->counts[a];
                double first = rod_q[grp[0]];
                double total = 0.0;
                for (int64_t c = 1; c < count; c++) {
                    double d = rod_q[grp[c]] - first;
                    if (act->angular[a]) d = pk_pymod(d + PK_PI, 2.0 * PK_PI) - PK_PI;
                    total += d;
                }
                double mean = total / (double)count;
                spread = pk_max(spread, fabs(mean));
                for (int64_t c = 1; c < count; c++) {
                    double d = rod_q[grp[c]] - first;
                    if (act->angular[a]) d = pk_pymod(d + PK_PI, 2.0 * PK_PI) - PK_PI;
                    spread = pk_max(spread, fabs(d - mean));
                }
                qk[a] = first + mean;
            }
            ok = spread <= act->consistency_tol;
        }
        if (ok) {
            status[k] = 0;
        } else {
            status[k] = 1;
            for (ptrdiff_t a = 0; a < n; a++) qk[a] = NAN;
        }
    }
}
