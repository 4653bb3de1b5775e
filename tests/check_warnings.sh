#!/usr/bin/env bash
# No warning with -Wall -Wextra -Wpedantic from Clang, the compiler the rest of make test
# does not build with (GCC's warnings: the tests build with -Werror at -O2, and
# check_cmake.sh's full CMake build, -O3, must give none). About 20 s in all:
#   1. lpfdm.cpp compiled by clang++ -O3 -fopenmp: the optimiser's own warnings come only
#      from a real compile at -O3 (such as a loop under `omp simd` it could not vectorise);
#   2. the unit tests, as one translation unit (LPFDM_INTERNALS), lpfdm.cpp with
#      LPFDM_HEADER_ONLY, tools/embed_example.cpp (LPFDM_NO_IO) and lpfdm.cpp without the
#      AVX2 version (LPFDM_NO_WIDE, and -mfma)
#      checked by clang++ -fsyntax-only: Clang's other warnings and what it refuses where
#      GCC accepts (a structured binding captured by a lambda, as INFO does, is not C++17).
#
# usage: tests/check_warnings.sh EXE   (EXE only chooses whether to run: once, for the plain
# build of the program, not for a sanitizer build, whose name contains "san")
# Needs clang and libomp-dev (make test installs them). Last line "warnings: N passed, M failed".
set -u
. "$(dirname "$0")/lib.sh"
cd "$(dirname "$0")/.." || exit 2
plain_build_only warnings "${1:-}"
passed=0 failed=0
fail() { echo "FAIL warnings $1"; failed=$((failed + 1)); }
cxx=
for c in clang++ clang++-19 clang++-18 clang++-17 clang++-16 clang++-15 clang++-14; do
    command -v "$c" >/dev/null 2>&1 && { cxx=$c; break; }
done
if [ -z "$cxx" ]; then
    fail "clang is not installed (Debian: apt-get install clang)"
    echo "warnings: $passed passed, $failed failed"
    exit 1
fi
tmp=$(mktemp -d) || exit 2
trap 'rm -rf "$tmp"' EXIT
warn=(-std=c++17 -Wall -Wextra -Wpedantic)
# With OpenMP, as the program is built: without it the parallel regions and the `omp simd`
# loop would be left out, and their warnings with them.
if ! echo '#include <omp.h>' | "$cxx" -fopenmp -x c++ -fsyntax-only - >/dev/null 2>&1; then
    fail "$cxx has no OpenMP runtime (Debian: apt-get install libomp-dev)"
    echo "warnings: $passed passed, $failed failed"
    exit 1
fi
omp=(-fopenmp)

# compile LABEL ARGS...: no error, no warning.
compile() {
    local label=$1 start=$SECONDS
    shift
    if ! "$cxx" "${warn[@]}" "$@" >"$tmp/log" 2>&1; then
        fail "$label does not compile with $cxx: $(grep -m 3 -E 'error|warning' "$tmp/log")"
    elif grep -q 'warning:' "$tmp/log"; then
        fail "$label: $(grep -c 'warning:' "$tmp/log") warnings from $cxx: $(grep -m 3 'warning:' "$tmp/log")"
    else
        passed=$((passed + 1))
        echo "warnings: $label: none ($((SECONDS - start)) s)"
    fi
}
compile "lpfdm.cpp at -O3" -O3 "${omp[@]}" -c lpfdm.cpp -o "$tmp/lpfdm.o"
printf '#include "%s"\n' "$PWD"/tests/test_*.cpp >"$tmp/unit.cpp"
compile "the unit tests (LPFDM_INTERNALS, as make test builds them; -fsyntax-only)" -O3 "${omp[@]}" -DLPFDM_INTERNALS -I. -I/usr/include/eigen3 -fsyntax-only "$tmp/unit.cpp"
compile "lpfdm.cpp with LPFDM_HEADER_ONLY (-fsyntax-only)" -O3 "${omp[@]}" -DLPFDM_HEADER_ONLY -fsyntax-only lpfdm.cpp
compile "tools/embed_example.cpp with LPFDM_NO_IO (-fsyntax-only)" -O3 -DLPFDM_NO_IO -I. -fsyntax-only tools/embed_example.cpp
# The builds without the AVX2 version: LPFDM_NO_WIDE, and any build with fused multiply-add
# (-mfma, -march=native), which leaves it out too (lpfdm.hpp, LPFDM_WIDE).
compile "lpfdm.cpp without the AVX2 version (LPFDM_NO_WIDE, -fsyntax-only)" -O2 "${omp[@]}" -DLPFDM_NO_WIDE -fsyntax-only lpfdm.cpp
compile "lpfdm.cpp with -mfma (-fsyntax-only)" -O2 "${omp[@]}" -mfma -fsyntax-only lpfdm.cpp
echo "warnings: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
