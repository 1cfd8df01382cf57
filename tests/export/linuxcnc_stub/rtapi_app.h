/* Test stand-in for LinuxCNC's rtapi_app.h: module macros expand to nothing. */
#ifndef PKM_TEST_RTAPI_APP_H
#define PKM_TEST_RTAPI_APP_H
#define EXPORT_SYMBOL(sym) extern int pkm_test_exported_dummy
#define MODULE_LICENSE(text) extern int pkm_test_license_dummy
#endif
