#!/usr/bin/env bash
# The CMake build and package, the four ways the README gives:
#   1. add_subdirectory(lpfdm) and target lpfdm::lpfdm (the program and tests are not built);
#   2. cmake --install of the header-only configuration, then find_package(lpfdm CONFIG);
#   3. the installed pkg-config file: g++ $(pkg-config --cflags lpfdm);
#      (1-3 each build and run tools/embed_example.cpp, a scene built in code, LPFDM_NO_IO:
#      no fmt, no Eigen);
#   4. the full build, cmake -S . -B DIR && cmake --build DIR && ctest --test-dir DIR, in a
#      temporary directory: it builds with no warning (GCC or the default compiler, -O3),
#      the program runs two threads when asked (OpenMP found) and writes the same bytes as
#      EXE (make's -O2 build) on two Mohr-Coulomb runs, `ctest -N` lists the unit
#      tests (unit_quick, unit_slow) and one test for every tests/check_*.sh, and the tests
#      labelled quick pass: the unit tests not tagged [slow] and the two quickest checks,
#      cli and vtu (make test runs the rest with its own builds). Run by ctest as the test
#      `cmake` (LPFDM_CMAKE_INSIDE_CTEST set), the check leaves way 4 out: that ctest run
#      is way 4.
#
# usage: tests/check_cmake.sh EXE   (EXE chooses whether to run, and is compared in way 4: tests/run.sh runs every
# check once per build of the program, and this one runs for the plain build, not for a
# sanitizer build, whose name contains "san", like the fuzzing smoke)
# Needs cmake and pkg-config (make test installs them). Last line "cmake: N passed, M failed".
set -u
. "$(dirname "$0")/lib.sh"
cd "$(dirname "$0")/.." || exit 2
plain_build_only cmake "${1:-}"
prog=$1
case $prog in /*) ;; *) prog=$OLDPWD/$prog ;; esac  # (given from where the script was started)
passed=0 failed=0
fail() { echo "FAIL cmake $1"; failed=$((failed + 1)); }
for tool in cmake pkg-config; do
    if ! command -v $tool >/dev/null; then
        fail "$tool is not installed (Debian: apt-get install cmake pkg-config)"
        echo "cmake: $passed passed, $failed failed"
        exit 1
    fi
done
src=$PWD
tmp=$(mktemp -d) || exit 2
trap 'rm -rf "$tmp"' EXIT
# run NAME EXE: the example must exit 0 and print no failed check.
run() {
    local out
    if ! out=$("$2" 2>&1); then
        fail "$1: the example exited with an error: $(echo "$out" | tail -n 2)"
    elif echo "$out" | grep -qi "fail"; then
        fail "$1: $(echo "$out" | grep -i -m 1 fail)"
    else
        passed=$((passed + 1))
    fi
}
consumer() {  # DIR, the lines that bring in lpfdm
    mkdir -p "$1"
    cp tools/embed_example.cpp "$1/"
    cat >"$1/CMakeLists.txt" <<EOF
cmake_minimum_required(VERSION 3.16)
project(consumer CXX)
$2
add_executable(example embed_example.cpp)
target_compile_definitions(example PRIVATE LPFDM_NO_IO)
target_link_libraries(example PRIVATE lpfdm::lpfdm)
EOF
}

# 1. add_subdirectory
consumer "$tmp/sub" "add_subdirectory(\"$src\" lpfdm)"
if cmake -S "$tmp/sub" -B "$tmp/sub/build" >"$tmp/log" 2>&1 && cmake --build "$tmp/sub/build" >>"$tmp/log" 2>&1; then
    if [ -e "$tmp/sub/build/lpfdm/lpfdm" ] || [ -e "$tmp/sub/build/lpfdm/lpfdm_tests" ]; then
        fail "add_subdirectory built the program or the tests of lpfdm as well"
    else
        run "add_subdirectory" "$tmp/sub/build/example"
    fi
else
    fail "add_subdirectory: $(grep -m 1 -i error "$tmp/log")"
fi

# 2. install, then find_package
if cmake -S "$src" -B "$tmp/lp" -DLPFDM_BUILD_PROGRAM=OFF -DLPFDM_BUILD_TESTS=OFF -DCMAKE_INSTALL_PREFIX="$tmp/prefix" >"$tmp/log" 2>&1 &&
   cmake --install "$tmp/lp" >>"$tmp/log" 2>&1 && [ -f "$tmp/prefix/include/lpfdm.hpp" ]; then
    passed=$((passed + 1))
    consumer "$tmp/pkg" "find_package(lpfdm 0.1 CONFIG REQUIRED)"
    if cmake -S "$tmp/pkg" -B "$tmp/pkg/build" -DCMAKE_PREFIX_PATH="$tmp/prefix" >"$tmp/log" 2>&1 && cmake --build "$tmp/pkg/build" >>"$tmp/log" 2>&1; then
        run "find_package" "$tmp/pkg/build/example"
    else
        fail "find_package: $(grep -m 1 -i error "$tmp/log")"
    fi
    # 3. pkg-config
    flags=$(PKG_CONFIG_PATH="$tmp/prefix/share/pkgconfig" pkg-config --cflags lpfdm 2>"$tmp/log")
    if [ -z "$flags" ]; then
        fail "pkg-config --cflags lpfdm: $(head -n 1 "$tmp/log")"
    elif mkdir -p "$tmp/pc" && ${CXX:-g++} $flags -DLPFDM_NO_IO -O1 -o "$tmp/pc/example" tools/embed_example.cpp -I/nonexistent 2>"$tmp/log" &&
         [ -n "$(echo "$flags" | grep -F "$tmp/prefix/include")" ]; then
        run "pkg-config" "$tmp/pc/example"
    else
        fail "pkg-config: the example does not build with '$flags': $(head -n 2 "$tmp/log")"
    fi
else
    fail "cmake --install: $(grep -m 1 -i error "$tmp/log")"
fi

# 4. the full build and ctest
if [ -n "${LPFDM_CMAKE_INSIDE_CTEST:-}" ]; then
    echo "cmake: run by ctest; the full build (way 4) is the one running it, not built again"
elif build_start=$SECONDS && ! { cmake -S "$src" -B "$tmp/full" >"$tmp/full.log" 2>&1 &&
         cmake --build "$tmp/full" --parallel "$(nproc)" >>"$tmp/full.log" 2>&1; }; then
    fail "cmake -S . -B DIR && cmake --build DIR: $(grep -m 3 -iE 'error|warning' "$tmp/full.log")"
else
    start=$SECONDS
    echo "cmake: the full build took $((start - build_start)) s ($(grep -c 'Building CXX' "$tmp/full.log") compiles)"
    if grep -q 'warning:' "$tmp/full.log"; then
        fail "the full build gives $(grep -c 'warning:' "$tmp/full.log") warnings: $(grep -m 3 'warning:' "$tmp/full.log")"
    else
        passed=$((passed + 1))
    fi
    # OpenMP: with OpenMP the provenance line names the threads asked for, without it 1.
    if "$tmp/full/lpfdm" -q --threads 2 --steps 10 -o "$tmp/omp" decks/column.deck >"$tmp/omp.log" 2>&1 &&
       grep -q '^# run: threads 2 ' "$tmp/omp/column_history.txt"; then
        passed=$((passed + 1))
    else
        fail "the program of the full build does not run two threads with --threads 2 (OpenMP not found?): $(grep -m 1 '^# run: threads' "$tmp/omp/column_history.txt" 2>/dev/null || head -n 2 "$tmp/omp.log")"
    fi
    # The same bytes as the program under test (make's build, -O2; CMake's Release, -O3,
    # and perhaps another compiler): a Mohr-Coulomb cut failing under its own weight (a
    # thousand steps: softening, points crossing cells) and the first steps of the flowing
    # collapse (the AVX2 loop of four points, the consult's edge lanes), one thread each.
    differ=""
    for args in "--steps 1000 decks/cut_high.deck" "--steps 300 decks/bench_flow.deck"; do
        name=$(basename "${args##* }" .deck)
        # shellcheck disable=SC2086  # (the options, word by word)
        OMP_NUM_THREADS=1 "$prog" -q -o "$tmp/same-make/$name" $args >/dev/null 2>&1 &&
            OMP_NUM_THREADS=1 "$tmp/full/lpfdm" -q -o "$tmp/same-cmake/$name" $args >/dev/null 2>&1 ||
            { differ="$differ $name (a run failed)"; continue; }
        for f in "$tmp/same-make/$name"/*; do
            cmp -s "$f" "$tmp/same-cmake/$name/$(basename "$f")" || differ="$differ $(basename "$f")"
        done
    done
    if [ -z "$differ" ]; then
        passed=$((passed + 1))
    else
        fail "the program of the full build writes other bytes than $prog:$differ"
    fi
    # ctest -N: "  Test  #3: decks" lines; every check script and the two unit parts.
    registered=$(ctest --test-dir "$tmp/full" -N 2>&1 | sed -nE 's/^ *Test +#[0-9]+: ([^ ]+).*/\1/p' | sort)
    expected=$( (printf 'unit_quick\nunit_slow\n'; for f in tests/check_*.sh; do f=${f#tests/check_}; echo "${f%.sh}"; done) | sort)
    if [ "$registered" = "$expected" ]; then
        passed=$((passed + 1))
    else
        fail "ctest -N does not list every tests/check_*.sh and the unit tests: missing $(comm -13 <(echo "$registered") <(echo "$expected") | tr '\n' ' '), extra $(comm -23 <(echo "$registered") <(echo "$expected") | tr '\n' ' ')"
    fi
    if ctest --test-dir "$tmp/full" -L quick --output-on-failure >"$tmp/ctest.log" 2>&1; then
        passed=$((passed + 1))
        echo "cmake: ctest -L quick: $(grep -E 'tests passed' "$tmp/ctest.log")"
    else
        fail "ctest -L quick: $(grep -E 'tests passed|\(Failed\)|\*\*\*' "$tmp/ctest.log" | head -n 5)"
        tail -n 30 "$tmp/ctest.log"
    fi
    echo "cmake: the full build's checks took $((SECONDS - start)) s"
fi
echo "cmake: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
