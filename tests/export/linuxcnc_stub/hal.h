/* Test stand-in for LinuxCNC's hal.h: the three calls a kinematics module makes. */
#ifndef PKM_TEST_HAL_H
#define PKM_TEST_HAL_H
static inline int hal_init(const char *name) { (void)name; return 1; }
static inline int hal_ready(int comp_id) { (void)comp_id; return 0; }
static inline int hal_exit(int comp_id) { (void)comp_id; return 0; }
#endif
