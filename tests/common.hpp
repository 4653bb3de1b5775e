// Constants and helpers the unit tests share. The tests build in groups, several files to one
// translation unit (Makefile), so a name a file defines for itself must not be defined
// by another file too: shared ones live here.
#ifndef LPFDM_TESTS_COMMON_HPP
#define LPFDM_TESTS_COMMON_HPP

#include <doctest/doctest.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>

#include <unistd.h>

#include "../lpfdm.hpp"

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

// The whole-scene comparisons at a smaller size: true when LPFDM_TEST_SMALL=1, as make
// test's sanitizer run sets it. The fast kernels against the reference cycle, AVX2 against
// one point at a time and threads against one thread then run a quarter of their steps (a
// tenth of test_reference.cpp's budget): ASan and UBSan look for faults along the code's
// paths, which the shorter runs take as well (tests/README says how that was checked), at
// a seventh of their time there; the -O2 run checks every bound at full size.
inline bool small_runs() {
    static const bool small = [] {
        const char* e = std::getenv("LPFDM_TEST_SMALL");
        return e != nullptr && std::string(e) == "1";
    }();
    return small;
}

// A directory name of this test process's own, "build/NAME.PID": make test runs the -O2
// and the sanitizer builds of the unit tests at once, and two runs writing the same files
// would read each other's.
// OwnDir made is that directory, created; gone with the object.
inline std::string own_dir(const std::string& name) { return "build/" + name + "." + std::to_string(::getpid()); }
// The three cycles a large-deformation case runs in: the paper's mapping with eq. 12 (the
// default), MAPPING SMOOTH with eq. 12, and MAPPING SMOOTH with ADVECT FLIP.
struct Cycle {
    lpfdm::Mapping mapping;
    lpfdm::Advect advect;
    const char* name;
    bool paper() const { return mapping == lpfdm::Mapping::Paper; }
    bool flip() const { return advect == lpfdm::Advect::Flip; }
    void apply(lpfdm::Scene& s) const { s.mapping = mapping; s.advect = advect; }
};
constexpr Cycle kCycles[] = {{lpfdm::Mapping::Paper, lpfdm::Advect::Eq12, "MAPPING PAPER"},
                             {lpfdm::Mapping::Smooth, lpfdm::Advect::Eq12, "MAPPING SMOOTH"},
                             {lpfdm::Mapping::Smooth, lpfdm::Advect::Flip, "MAPPING SMOOTH, ADVECT FLIP"}};

struct OwnDir {
    std::string path;
    explicit OwnDir(const std::string& name) : path(own_dir(name)) { std::filesystem::create_directories(path); }
    ~OwnDir() { std::error_code e; std::filesystem::remove_all(path, e); }
    OwnDir(const OwnDir&) = delete;
    OwnDir& operator=(const OwnDir&) = delete;
};
}  // namespace

#endif
