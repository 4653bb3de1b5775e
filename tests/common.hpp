// Constants the unit tests share. The tests build in groups, several files to one
// translation unit (Makefile), so a name a file defines for itself must not be defined
// by another file too: shared ones live here.
#ifndef LPFDM_TESTS_COMMON_HPP
#define LPFDM_TESTS_COMMON_HPP

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180;  // radians per degree
}  // namespace

#endif
