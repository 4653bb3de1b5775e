#!/usr/bin/env bash
# The fuzzing smoke test of `make test`: 30 seconds of tools/fuzz.sh (libFuzzer on the
# deck reader, under ASan and UBSan). Any crash fails it; each crash found must become a
# tests/decks/fuzz_*.deck.
#
# usage: tests/check_fuzz.sh EXE
#
# tests/run.sh runs every check script once per build of the program; the fuzzer builds
# its own harness, so the smoke runs once, for the plain build (./lpfdm, or ctest's), and
# the run for the sanitizer build (a name containing "san") counts nothing.
# Without clang and its libFuzzer runtime (Debian: clang libclang-rt-14-dev) it fails.
# Last line "fuzz: N passed, M failed". FUZZ_SMOKE_SECONDS changes the 30 seconds (`make fuzz` runs the long campaign).
set -u
cd "$(dirname "$0")/.." || exit 2

if [ $# -ne 1 ]; then
    echo "usage: $0 EXE" >&2
    exit 2
fi
case $(basename "$1") in
    *san*)
        echo "fuzz: the smoke runs once, for the plain build of the program; nothing to do for $1"
        echo "fuzz: 0 passed, 0 failed"
        exit 0
        ;;
esac

seconds=${FUZZ_SMOKE_SECONDS:-30}
have=0
for c in clang++ clang++-19 clang++-18 clang++-17 clang++-16 clang++-15 clang++-14; do
    command -v "$c" >/dev/null 2>&1 || continue
    t=$(mktemp -d) || exit 2
    printf '#include <cstdint>\n#include <cstddef>\nextern "C" int LLVMFuzzerTestOneInput(const uint8_t*, size_t) { return 0; }\n' >"$t/f.cpp"
    "$c" -fsanitize=fuzzer -o "$t/f" "$t/f.cpp" >/dev/null 2>&1 && have=1
    rm -rf "$t"
    [ $have = 1 ] && break
done
if [ $have = 0 ]; then
    echo "FAIL fuzz smoke: clang with libFuzzer is not installed (Debian: apt-get install clang libclang-rt-14-dev)"
    echo "fuzz: 0 passed, 1 failed"
    exit 1
fi

out=$(timeout -k 30 $((seconds + 600)) bash tools/fuzz.sh "$seconds" 2>&1)
rc=$?
echo "$out" | tail -n 12
if [ $rc -eq 0 ]; then
    echo "fuzz: 1 passed, 0 failed"
    exit 0
fi
echo "FAIL fuzz smoke: tools/fuzz.sh $seconds exited with status $rc"
echo "fuzz: 0 passed, 1 failed"
exit 1
