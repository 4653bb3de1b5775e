// Constants the unit tests share. The tests build in groups, several files to one
// translation unit (Makefile), so a name a file defines for itself must not be defined
// by another file too: shared ones live here.
#ifndef LPFDM_TESTS_COMMON_HPP
#define LPFDM_TESTS_COMMON_HPP

#include <doctest/doctest.h>

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180;  // radians per degree

// x == approx(v).epsilon(e): |x - v| < e max(|x|, |v|), a relative tolerance. doctest's
// own Approx adds its scale, 1 unless set, to those magnitudes: for values below one its
// epsilon is an absolute tolerance (a strain of 1e-3 "within 1 %" passed anything within
// 0.01), and for values near one the tolerance is twice the one written. Every Approx
// comparison of the tests is this one. The comparison is strict, so approx(0) passes
// nothing, not even 0: where a value may be zero, .scale(s) gives the floor s.
inline doctest::Approx approx(double v) { return doctest::Approx(v).scale(0); }
}  // namespace

#endif
