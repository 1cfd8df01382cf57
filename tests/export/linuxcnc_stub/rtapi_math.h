/* Test stand-in for LinuxCNC's rtapi_math.h. */
#include <math.h>
