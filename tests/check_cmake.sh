#!/usr/bin/env bash
# The CMake package: another project takes the kernel three ways, and each builds and runs
# tools/embed_example.cpp (a scene built in code, LPFDM_NO_IO: no fmt, no Eigen):
#   1. add_subdirectory(lpfdm) and target lpfdm::lpfdm (the program and tests are not built);
#   2. cmake --install of the header-only configuration, then find_package(lpfdm CONFIG);
#   3. the installed pkg-config file: g++ $(pkg-config --cflags lpfdm).
# The full build with tests (cmake -S . -B build && cmake --build build && ctest) is the
# README's CMake way; it is not repeated here (make test builds and runs the same tests).
#
# usage: tests/check_cmake.sh EXE   (runs once, for ./lpfdm, like the fuzzing smoke)
# Needs cmake and pkg-config (make test installs them). Last line "cmake: N passed, M failed".
set -u
cd "$(dirname "$0")/.." || exit 2
case ${1:-} in
    ./lpfdm | lpfdm | "$PWD/lpfdm") ;;
    *)
        echo "cmake: the check runs once, with ./lpfdm; nothing to do for ${1:-}"
        echo "cmake: 0 passed, 0 failed"
        exit 0
        ;;
esac
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
echo "cmake: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
