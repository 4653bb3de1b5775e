// The unit tests' one implementation unit: the kernel's out-of-line definitions, compiled
// once for all the test files, which include lpfdm.hpp with LPFDM_INTERNALS (its inline
// equations and helpers in view, the rest declared) and link against this unit.
#define LPFDM_IMPLEMENTATION
#include "../lpfdm.hpp"
