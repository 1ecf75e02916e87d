/* The C program's entry, called by c_api_test_main.cpp with the server's gRPC address. */
#ifndef HAPTIC_TESTS_C_API_TEST_H
#define HAPTIC_TESTS_C_API_TEST_H

#ifdef __cplusplus
extern "C" {
#endif

/** Returns the number of failed checks (0: passed); they are printed on stderr. */
int c_api_test_run(const char* address);

/** Records a session to `dir`/session.csv and `dir`/session.h5 from C while the state callback
 * writes what it saw to `dir`/seen.csv (the recorder's column names); returns the failed checks. */
int c_api_record_run(const char* address, const char* dir);

#ifdef __cplusplus
}
#endif

#endif
