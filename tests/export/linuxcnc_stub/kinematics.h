/* Test stand-in for LinuxCNC's kinematics.h and emcpos.h: the types and declarations a
   kinematics module uses (same names and layouts as LinuxCNC's), no LinuxCNC needed. */
#ifndef PKM_TEST_KINEMATICS_H
#define PKM_TEST_KINEMATICS_H

typedef struct { double x, y, z; } PmCartesian;
typedef struct EmcPose { PmCartesian tran; double a, b, c; double u, v, w; } EmcPose;

typedef enum {
    KINEMATICS_IDENTITY = 1,
    KINEMATICS_FORWARD_ONLY,
    KINEMATICS_INVERSE_ONLY,
    KINEMATICS_BOTH
} KINEMATICS_TYPE;

typedef unsigned long int KINEMATICS_FORWARD_FLAGS;
typedef unsigned long int KINEMATICS_INVERSE_FLAGS;

extern int kinematicsForward(const double *joint, struct EmcPose *world,
                             const KINEMATICS_FORWARD_FLAGS *fflags,
                             KINEMATICS_INVERSE_FLAGS *iflags);
extern int kinematicsInverse(const struct EmcPose *world, double *joint,
                             const KINEMATICS_INVERSE_FLAGS *iflags,
                             KINEMATICS_FORWARD_FLAGS *fflags);
extern int kinematicsHome(struct EmcPose *world, double *joint,
                          KINEMATICS_FORWARD_FLAGS *fflags, KINEMATICS_INVERSE_FLAGS *iflags);
extern KINEMATICS_TYPE kinematicsType(void);
extern int kinematicsSwitchable(void);
extern int kinematicsSwitch(int switchkins_type);

#define KINS_NOT_SWITCHABLE \
int kinematicsSwitchable(void) { return 0; } \
int kinematicsSwitch(int switchkins_type) { (void)switchkins_type; return 0; }

#endif
