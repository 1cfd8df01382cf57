/* ThreadSanitizer run of pk_inverse_shared: 3 threads on one plan, many small slices, every
 * row compared with the single-thread kernel's bits. */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include "kernels.h"

#define ROWS 3001
static double x[6 * ROWS], q1[6 * ROWS], q2[6 * ROWS];
static int64_t s1[ROWS], s2[ROWS];
static pk_rods rods;
static pk_actuators act;
static unsigned char *plan;

typedef struct { int wait; } arg_t;

static void *run(void *p) {
    arg_t *a = p;
    double sq[6 * 7], rq[6];
    int64_t ss[7];
    pk_inverse_shared(x, ROWS, &rods, &act, q2, s2, plan, a->wait, sq, ss, rq);
    return NULL;
}

int main(void) {
    static int64_t kind[6] = {1, 1, 1, 1, 1, 1}, groups[6] = {0, 1, 2, 3, 4, 5},
                   counts[6] = {1, 1, 1, 1, 1, 1};
    static unsigned char angular[6];
    static double base[18], platform[18], axis[18], zero[18], lsq[6], len[6], zr[6], sigma[6];
    for (int j = 0; j < 6; j++) {
        double t = j * 1.047;
        base[3 * j] = cos(t), base[3 * j + 1] = sin(t), base[3 * j + 2] = 0;
        platform[3 * j] = 0.5 * cos(t + 0.3), platform[3 * j + 1] = 0.5 * sin(t + 0.3);
        platform[3 * j + 2] = 0, axis[3 * j + 2] = 1, len[j] = 1.0, lsq[j] = 1.0, sigma[j] = 1;
    }
    rods = (pk_rods){.m = 6, .kind = kind, .base = base, .platform = platform, .axis = axis,
                     .pivot = zero, .e1 = zero, .e2 = zero, .length_sq = lsq, .length = len,
                     .crank_radius = zr, .crank_offset = zr, .sigma = sigma, .boundary_tol = 1e-12};
    act = (pk_actuators){.n = 6, .width = 1, .groups = groups, .counts = counts,
                         .angular = angular, .consistency_tol = 1e-9};
    srand(35);
    for (int i = 0; i < 6 * ROWS; i++) x[i] = (i % 6 == 2 ? 1.0 : 0.0) + 0.1 * rand() / RAND_MAX;
    double rq[6];
    pk_inverse_poses(x, ROWS, &rods, &act, q1, s1, rq);
    int bad = 0;
    for (int rep = 0; rep < 300; rep++) {
        ptrdiff_t slice = 1 + rep % 7, block = 1 + rep % 5;
        ptrdiff_t bytes = pk_inverse_plan_bytes(ROWS, slice, block);
        plan = calloc((size_t)bytes, 1);
        pk_inverse_plan_init(plan, ROWS, slice, block);
        memset(q2, 0xff, sizeof q2);
        pthread_t t[2];
        arg_t helper = {0}, caller = {1};
        pthread_create(&t[0], NULL, run, &helper);
        pthread_create(&t[1], NULL, run, &helper);
        run(&caller);
        if (memcmp(q1, q2, sizeof q1) || memcmp(s1, s2, sizeof s1)) bad++;
        pthread_join(t[0], NULL);
        pthread_join(t[1], NULL);
        free(plan);
    }
    printf("runs 300, rows differing in %d\n", bad);
    return bad != 0;
}
