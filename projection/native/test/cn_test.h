// The check counter of the shim's self-tests.
#pragma once
#include <cstdio>

#include "cram_native.h"

static int failures = 0, checks = 0;
#define CHECK(c)                                                                     \
  do {                                                                               \
    ++checks;                                                                        \
    if (!(c)) {                                                                      \
      ++failures;                                                                    \
      fprintf(stderr, "FAIL %s:%d: %s (last error: %s)\n", __FILE__, __LINE__, #c,   \
              cn_last_error());                                                      \
    }                                                                                \
  } while (0)
