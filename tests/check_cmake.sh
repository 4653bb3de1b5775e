#!/usr/bin/env bash
# The CMake build and package. First the recipes of README.md's "Use it in your project",
# run as written: its ```cmake and ```sh blocks, taken from the README, in a temporary
# directory that holds `lpfdm` (a link to this tree) and the projects beside it, with a
# temporary prefix in place of /opt/lpfdm and tools/embed_example.cpp as mine.cpp:
#   1. the CMakeLists.txt with add_subdirectory(../lpfdm lpfdm) builds mine.cpp (with fmt)
#      and nothing of lpfdm's own (no program, no tests);
#   2. the header-only install (the prefix given at install time) puts the header and the
#      package files there; the same CMakeLists.txt with find_package(lpfdm CONFIG
#      REQUIRED) in place of add_subdirectory builds mine.cpp from them;
#   3. pkg-config --cflags lpfdm, from that prefix, names its include directory (lpfdm.pc
#      finds the prefix from its own place), and the README's g++ line builds mine.cpp;
#      (each example must run and print no failed check)
# Then the build of README's "With CMake:", cmake -S . -B DIR (Release, -O3, GCC or the
# default compiler), in two steps:
#   4. the program (cmake --build DIR --target lpfdm): no warning; cmake --install puts it
#      in bin/; it runs two threads when asked (OpenMP found) and writes the same bytes as
#      EXE (make's -O2 build) on two Mohr-Coulomb runs; `ctest -N` lists the unit tests
#      (unit_quick, unit_slow) and one test for every tests/check_*.sh; the quick checks
#      (labels quick and check: cli and vtu) pass with that program;
#   5. the unit tests (the rest of cmake --build DIR: the kernel's unit tests/kernel.cpp
#      and the test files' unity unit), built of the one file it runs (LPFDM_TEST_FILES:
#      test_mohr.cpp, the models' cases, which call the kernel's inline equations through
#      LPFDM_INTERNALS): no warning, and its cases pass. make test builds and runs every
#      file's cases with its own build (the same sources, at -O2 and -O1).
#   make test runs the other checks and the [slow] unit tests with its own builds. Run by
#   ctest as the test `cmake` (LPFDM_CMAKE_INSIDE_CTEST set), the check leaves 4 and 5 out:
#   that ctest run is the full build.
#
# usage: tests/check_cmake.sh EXE   (EXE chooses whether to run, and is compared in way 4: tests/run.sh runs every
# check once per build of the program, and this one runs for the plain build, not for a
# sanitizer build, whose name contains "san", like the fuzzing smoke)
# Needs cmake and pkg-config (make test installs them). Prints how long each way took; last
# line "cmake: N passed, M failed".
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
took() { echo "cmake: way $1 took $((SECONDS - $2)) s"; }
first_error() { grep -m 1 -A 2 -i error "$tmp/log" | tr -s '\n ' ' '; }

# The README's recipes: block N prints the Nth fenced block of "Use it in your project",
# without the list's indentation; as_prefix puts the temporary prefix for /opt/lpfdm.
section() { awk '/^### Use it in your project$/ { on = 1; next } on && /^#/ { exit } on' README.md; }
block() {
    section | awk -v want="$1" '
        inb && /^ *```/ { inb = 0; next }
        inb { if (k == want) { sub("^" ind, ""); print } next }
        /^ *```[a-z]+ *$/ { k++; inb = 1; ind = $0; sub(/```.*/, "", ind) }'
}
prefix=$tmp/prefix
as_prefix() { sed "s|/opt/lpfdm|$prefix|g"; }
# recipe N DIR: runs block N (a shell block) in DIR, as bash -e would, logged to $tmp/log.
recipe() { block "$1" | as_prefix >"$tmp/recipe$1.sh" && (cd "$2" && bash -e -o pipefail "$tmp/recipe$1.sh") >"$tmp/log" 2>&1; }
work=$tmp/work
mkdir -p "$work/mine" "$work/mine-installed" "$work/mine-pc"
ln -s "$src" "$work/lpfdm"
for d in mine mine-installed mine-pc; do cp tools/embed_example.cpp "$work/$d/mine.cpp"; done
langs=$(section | sed -nE 's/^ *```([a-z]+) *$/\1/p' | paste -sd ' ')
start=$SECONDS
if [ "$langs" != "cmake sh sh sh" ]; then
    fail "README.md's \"Use it in your project\" shows the blocks '$langs', not the four this check runs (cmake: the CMakeLists.txt; sh: the install, the build with find_package, pkg-config)"
else
    # 1. add_subdirectory
    block 1 >"$work/mine/CMakeLists.txt"
    if (cd "$work/mine" && cmake -S . -B build && cmake --build build) >"$tmp/log" 2>&1; then
        if [ -e "$work/mine/build/lpfdm/lpfdm" ] || [ -e "$work/mine/build/lpfdm/lpfdm_tests" ]; then
            fail "add_subdirectory built the program or the tests of lpfdm as well"
        else
            run "add_subdirectory" "$work/mine/build/mine"
        fi
    else
        fail "add_subdirectory: $(first_error)"
    fi

    # 2. the header-only install, then find_package
    if ! recipe 2 "$work"; then
        fail "the install: $(first_error)"
    elif [ ! -f "$prefix/include/lpfdm.hpp" ] || [ ! -f "$prefix/share/lpfdm/cmake/lpfdmConfig.cmake" ] ||
         [ ! -f "$prefix/share/pkgconfig/lpfdm.pc" ]; then
        fail "the install did not put the header, lpfdmConfig.cmake and lpfdm.pc in the prefix: $(cd "$prefix" 2>/dev/null && find . -type f | tr '\n' ' ')"
    else
        passed=$((passed + 1))
        block 1 | sed 's/^add_subdirectory(.*/find_package(lpfdm CONFIG REQUIRED)/' >"$work/mine-installed/CMakeLists.txt"
        if ! grep -q '^find_package(lpfdm CONFIG REQUIRED)$' "$work/mine-installed/CMakeLists.txt"; then
            fail "the README's CMakeLists.txt has no add_subdirectory line for find_package to take the place of"
        elif ! recipe 3 "$work/mine-installed"; then
            fail "find_package: $(first_error)"
        elif ! grep -rqF --include=flags.make --include=build.ninja -- "$prefix/include" "$work/mine-installed/build"; then
            fail "find_package: mine.cpp was not built with the installed header ($prefix/include)"
        else
            run "find_package" "$work/mine-installed/build/mine"
        fi

        # 3. pkg-config
        flags=$(PKG_CONFIG_PATH=$prefix/share/pkgconfig pkg-config --cflags lpfdm 2>"$tmp/log")
        inc=$(echo "$flags" | sed -nE 's/^-I([^ ]+).*/\1/p')
        if [ -z "$inc" ] || [ "$(cd "$inc" 2>/dev/null && pwd -P)" != "$(cd "$prefix/include" && pwd -P)" ]; then
            fail "pkg-config --cflags lpfdm gives '$flags', not the include directory of the prefix given at install time ($prefix/include) $(head -n 1 "$tmp/log")"
        else
            passed=$((passed + 1))
        fi
        if recipe 4 "$work/mine-pc"; then
            run "pkg-config" "$work/mine-pc/mine"
        else
            fail "pkg-config: $(head -n 2 "$tmp/log")"
        fi
    fi
fi
took 1-3 $start

# 4. the program of the full build
if [ -n "${LPFDM_CMAKE_INSIDE_CTEST:-}" ]; then
    echo "cmake: run by ctest; the full build (ways 4 and 5) is the one running it, not built again"
    echo "cmake: $passed passed, $failed failed"
    [ "$failed" -eq 0 ]
    exit
fi
start=$SECONDS
full=$tmp/full
if ! { cmake -S "$src" -B "$full" >"$tmp/full.log" 2>&1 &&
       cmake --build "$full" --target lpfdm --parallel "$(nproc)" >>"$tmp/full.log" 2>&1; }; then
    fail "cmake -S . -B DIR && cmake --build DIR --target lpfdm: $(grep -m 3 -iE 'error|warning' "$tmp/full.log")"
    echo "cmake: $passed passed, $failed failed"
    exit 1
fi
echo "cmake: the program's build took $((SECONDS - start)) s"
if grep -q 'warning:' "$tmp/full.log"; then
    fail "the program's build gives $(grep -c 'warning:' "$tmp/full.log") warnings: $(grep -m 3 'warning:' "$tmp/full.log")"
else
    passed=$((passed + 1))
fi
exe=$tmp/installed/bin/lpfdm
if cmake --install "$full" --prefix "$tmp/installed" >"$tmp/log" 2>&1 && [ -x "$exe" ] && [ -f "$tmp/installed/include/lpfdm.hpp" ]; then
    passed=$((passed + 1))
else
    fail "cmake --install of the full build does not install bin/lpfdm and the header: $(first_error)"
    exe=$full/lpfdm
fi
# OpenMP: with OpenMP the provenance line names the threads asked for, without it 1.
if "$exe" -q --threads 2 --steps 10 -o "$tmp/omp" decks/column.deck >"$tmp/omp.log" 2>&1 &&
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
        OMP_NUM_THREADS=1 "$exe" -q -o "$tmp/same-cmake/$name" $args >/dev/null 2>&1 ||
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
registered=$(ctest --test-dir "$full" -N 2>&1 | sed -nE 's/^ *Test +#[0-9]+: ([^ ]+).*/\1/p' | sort)
expected=$( (printf 'unit_quick\nunit_slow\n'; for f in tests/check_*.sh; do f=${f#tests/check_}; echo "${f%.sh}"; done) | sort)
if [ "$registered" = "$expected" ]; then
    passed=$((passed + 1))
else
    fail "ctest -N does not list every tests/check_*.sh and the unit tests: missing $(comm -13 <(echo "$registered") <(echo "$expected") | tr '\n' ' '), extra $(comm -23 <(echo "$registered") <(echo "$expected") | tr '\n' ' ')"
fi
# ctest_quick LABEL NAME: the tests labelled quick and LABEL must pass (and be some).
ctest_quick() {
    if ctest --test-dir "$full" -L quick -L "$1" --no-tests=error --output-on-failure >"$tmp/ctest.log" 2>&1; then
        passed=$((passed + 1))
        echo "cmake: ctest -L quick -L $1 ($2): $(grep -E 'tests passed' "$tmp/ctest.log")"
    else
        fail "ctest -L quick -L $1 ($2): $(grep -E 'tests passed|\(Failed\)|\*\*\*|No tests' "$tmp/ctest.log" | head -n 5)"
        tail -n 30 "$tmp/ctest.log"
    fi
}
ctest_quick check "the quick checks"
took 4 $start

# 5. the unit tests of the full build
start=$SECONDS
if ! { cmake -S "$src" -B "$full" '-DLPFDM_TEST_FILES=tests/test_mohr.cpp' >"$tmp/unit.log" 2>&1 &&
       cmake --build "$full" --parallel "$(nproc)" >>"$tmp/unit.log" 2>&1; }; then
    fail "cmake --build DIR (the unit tests): $(grep -m 3 -iE 'error|warning' "$tmp/unit.log")"
else
    echo "cmake: the unit tests' build took $((SECONDS - start)) s"
    if grep -q 'warning:' "$tmp/unit.log"; then
        fail "the unit tests' build gives $(grep -c 'warning:' "$tmp/unit.log") warnings: $(grep -m 3 'warning:' "$tmp/unit.log")"
    else
        passed=$((passed + 1))
    fi
    # make test's own build runs every case; this build's binary holds one file's cases
    # (a few seconds): every case it holds must run and pass
    if (OMP_NUM_THREADS=1 "$full/lpfdm_tests" --no-version=1) >"$tmp/unit-run.log" 2>&1 &&
       grep -qE '^\[doctest\] test cases: +[1-9][0-9]* \|' "$tmp/unit-run.log" &&
       ! grep -qE '^\[doctest\] test cases:.* [1-9][0-9]* skipped' "$tmp/unit-run.log"; then
        passed=$((passed + 1))
        echo "cmake: the unit tests of test_mohr.cpp: $(grep -E '^\[doctest\] test cases:' "$tmp/unit-run.log")"
    else
        fail "the unit tests of the full build (test_mohr.cpp): $(grep -E 'ERROR|test cases:' "$tmp/unit-run.log" | head -n 5)"
    fi
fi
took 5 $start
echo "cmake: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
