/* Test harness: batch wrappers around a generated kinematics module, called through ctypes.
   Compiled together with the module: gcc -shared -fPIC -O2 -I<stub dir> module.c harness.c */
#include "kinematics.h"

/* world rows (n, 6) = x y z a b c -> joints (n, n_joints), status (n,) */
void pkm_batch_inverse(long n, int n_joints, const double *world, double *joints, int *status)
{
    long i;
    for (i = 0; i < n; i++) {
        EmcPose pos = {{world[6 * i], world[6 * i + 1], world[6 * i + 2]},
                       world[6 * i + 3], world[6 * i + 4], world[6 * i + 5], 0.0, 0.0, 0.0};
        KINEMATICS_INVERSE_FLAGS iflags = 0;
        KINEMATICS_FORWARD_FLAGS fflags = 0;
        status[i] = kinematicsInverse(&pos, joints + (long)n_joints * i, &iflags, &fflags);
    }
}

/* joints (n, n_joints) and start worlds (n, 6) -> worlds (n, 6), status (n,) */
void pkm_batch_forward(long n, int n_joints, const double *joints, const double *start,
                       double *world, int *status)
{
    long i;
    for (i = 0; i < n; i++) {
        EmcPose pos = {{start[6 * i], start[6 * i + 1], start[6 * i + 2]},
                       start[6 * i + 3], start[6 * i + 4], start[6 * i + 5], 0.0, 0.0, 0.0};
        KINEMATICS_FORWARD_FLAGS fflags = 0;
        KINEMATICS_INVERSE_FLAGS iflags = 0;
        status[i] = kinematicsForward(joints + (long)n_joints * i, &pos, &fflags, &iflags);
        world[6 * i] = pos.tran.x; world[6 * i + 1] = pos.tran.y; world[6 * i + 2] = pos.tran.z;
        world[6 * i + 3] = pos.a; world[6 * i + 4] = pos.b; world[6 * i + 5] = pos.c;
    }
}

int pkm_home(double *world, double *joints)
{
    EmcPose pos;
    KINEMATICS_FORWARD_FLAGS fflags = 1;
    KINEMATICS_INVERSE_FLAGS iflags = 1;
    int status = kinematicsHome(&pos, joints, &fflags, &iflags);
    world[0] = pos.tran.x; world[1] = pos.tran.y; world[2] = pos.tran.z;
    world[3] = pos.a; world[4] = pos.b; world[5] = pos.c;
    return status;
}

int pkm_type(void) { return (int)kinematicsType(); }
extern int rtapi_app_main(void);
int pkm_app_main(void) { return rtapi_app_main(); }

/* as pkm_batch_inverse, each pose after kinematicsHome (the module starts from home) */
void pkm_batch_inverse_from_home(long n, int n_joints, const double *world, double *joints,
                                 int *status)
{
    long i;
    double home_world[6], home_joints[64];
    for (i = 0; i < n; i++) {
        pkm_home(home_world, home_joints);
        pkm_batch_inverse(1, n_joints, world + 6 * i, joints + (long)n_joints * i, status + i);
    }
}

/* as pkm_batch_forward, each actuator set after kinematicsHome */
void pkm_batch_forward_from_home(long n, int n_joints, const double *joints, const double *start,
                                 double *world, int *status)
{
    long i;
    double home_world[6], home_joints[64];
    for (i = 0; i < n; i++) {
        pkm_home(home_world, home_joints);
        pkm_batch_forward(1, n_joints, joints + (long)n_joints * i, start + 6 * i, world + 6 * i,
                          status + i);
    }
}
