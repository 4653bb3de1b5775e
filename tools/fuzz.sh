#!/usr/bin/env bash
# Coverage-guided fuzzing of the deck reader with clang's libFuzzer (Debian packages
# clang and libclang-rt-14-dev), under AddressSanitizer and UndefinedBehaviorSanitizer.
#
# usage: tools/fuzz.sh [SECONDS]        (make fuzz: FUZZ_SECONDS, default 1800)
#
# Builds build/fuzz_deck from tests/fuzz_deck.cpp, seeds build/fuzz/corpus from decks/
# and tests/decks/ (the corpus is kept between runs and grows), runs for SECONDS and
# writes every crash, leak, timeout or out-of-memory input to build/fuzz/crashes/.
# Exit status 0 when nothing was found; otherwise 1, with the inputs listed: turn each
# into a tests/decks/fuzz_*.deck (first line "* expect: ...", see tests/check_decks.sh).
# FUZZ_KEEP_GOING=1 runs libFuzzer's fork mode, which goes on after a crash (to look for
# more bugs while a known one is not fixed yet). Last line: "fuzz: N executions in S s, K crashes".
set -u
cd "$(dirname "$0")/.." || exit 2

seconds=${1:-1800}
if ! [[ $seconds =~ ^[0-9]+$ ]] || [ "$seconds" -lt 1 ]; then
    echo "usage: $0 [SECONDS]" >&2
    exit 2
fi

# --- the compiler and the libFuzzer runtime ---
find_clang() {
    for c in clang++ clang++-19 clang++-18 clang++-17 clang++-16 clang++-15 clang++-14; do
        command -v "$c" >/dev/null 2>&1 && { echo "$c"; return 0; }
    done
    return 1
}
has_libfuzzer() {  # $1: compiler; true when -fsanitize=fuzzer links
    local t
    t=$(mktemp -d) || return 1
    printf '#include <cstdint>\n#include <cstddef>\nextern "C" int LLVMFuzzerTestOneInput(const uint8_t*, size_t) { return 0; }\n' >"$t/f.cpp"
    "$1" -fsanitize=fuzzer -o "$t/f" "$t/f.cpp" >/dev/null 2>&1
    local rc=$?
    rm -rf "$t"
    return $rc
}
cxx=$(find_clang)
if [ -z "$cxx" ] || ! has_libfuzzer "$cxx" || [ ! -f /usr/include/fmt/format.h ]; then
    packages="clang libclang-rt-14-dev libfmt-dev"
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
        echo "fuzz: installing $packages"
        apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $packages >/dev/null || exit 1
        cxx=$(find_clang)
    else
        echo "fuzz: clang with libFuzzer is missing; run: sudo apt-get install $packages"
        exit 1
    fi
    if [ -z "$cxx" ] || ! has_libfuzzer "$cxx"; then
        echo "fuzz: $cxx cannot link -fsanitize=fuzzer (libclang-rt for this clang missing?)"
        exit 1
    fi
fi

# --- the harness ---
mkdir -p build/fuzz/corpus build/fuzz/crashes build/fuzz/seeds
exe=build/fuzz_deck
if [ ! -x "$exe" ] || [ tests/fuzz_deck.cpp -nt "$exe" ] || [ lpfdm.hpp -nt "$exe" ]; then
    echo "fuzz: building $exe with $cxx"
    "$cxx" -std=c++17 -g1 -O1 -fno-omit-frame-pointer \
        -fsanitize=fuzzer,address,undefined,float-cast-overflow -fno-sanitize-recover=all \
        -o "$exe" tests/fuzz_deck.cpp -lfmt || exit 1
fi

# --- seeds and a dictionary of the deck language ---
rm -f build/fuzz/seeds/*
for d in decks/*.deck tests/decks/*.deck; do
    [ -f "$d" ] && cp "$d" "build/fuzz/seeds/${d//\//_}"
done
dict=build/fuzz/deck.dict
{
    for w in TITLE GRID MATERIAL ELASTIC MOHR CLUSTER FIX WALL GRAVITY DAMPING SEED STEP OUTPUT POINTS HISTORY EVERY END \
             E= NU= RHO= PHI= C= PSI= TENSION= SOFTEN= SCATTER= PPC= FILL= CELLS POLYGON X XY Y \
             SHAKE ABSORB FILE= SCALE= START= DAMPING= COMPLIANT BASELINE BOTTOM TOP LEFT RIGHT SHIFT RATE= ABOVE= \
             decks/quake_pulse.txt decks/quake_burst.txt tests/decks/good_quake.txt; do
        printf '"%s"\n' "$w"
    done
    for w in ' ' ',' '=' '!' '&' '\x0a' '\x0d\x0a' '\x0a*' '\x0a&\x0a' '5E7' '5.0D+07' '.5' '3.' '-0' '1E308' '1E-308' '4.9E-324' \
             '2147483648' '1000000' '1E9' '0.4999999' 'NaN' 'inf' '\xef\xbb\xbf' '\x09'; do
        printf '"%s"\n' "$w"
    done
} >"$dict"

# --- run ---
log=build/fuzz/last.log
before=$(find build/fuzz/crashes -type f | wc -l)
echo "fuzz: $seconds s on $exe, corpus build/fuzz/corpus ($(find build/fuzz/corpus -type f | wc -l) inputs) + $(find build/fuzz/seeds -type f | wc -l) seeds"
keep_going=()
[ "${FUZZ_KEEP_GOING:-0}" = 1 ] && keep_going=(-fork=1 -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1)
start=$(date +%s)
ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=1 UBSAN_OPTIONS=print_stacktrace=1 \
"$exe" "${keep_going[@]}" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=8192 -print_final_stats=1 \
    -dict="$dict" -artifact_prefix=build/fuzz/crashes/ build/fuzz/corpus build/fuzz/seeds >"$log" 2>&1
rc=$?
took=$(($(date +%s) - start))
runs=$(grep -E '^Done [0-9]+ runs' "$log" | tail -1 | sed -E 's/^Done ([0-9]+) runs.*/\1/')
[ -n "$runs" ] || runs=$(grep -E '^#[0-9]+: cov:' "$log" | tail -1 | sed -E 's/^#([0-9]+):.*/\1/')  # fork mode
[ -n "$runs" ] || runs=$(grep -E '^stat::number_of_executed_units:' "$log" | tail -1 | awk '{print $2}')
after=$(find build/fuzz/crashes -type f | wc -l)
new=$((after - before))
grep -E '^#[0-9]+.*(DONE|pulse|cov:)' "$log" | tail -n 2
if [ $rc -ne 0 ] || [ "$new" -gt 0 ]; then
    grep -m 1 -E 'ERROR|runtime error|deadly signal|Timeout|out-of-memory' "$log"
    echo "fuzz: found a problem (exit status $rc); inputs in build/fuzz/crashes/, log in $log:"
    find build/fuzz/crashes -type f -newer "$dict" | sed 's/^/  /'
    echo "fuzz: ${runs:-?} executions in ${took:-?} s, $((new > 0 ? new : 1)) crashes"
    exit 1
fi
echo "fuzz: ${runs:-?} executions in $took s, 0 crashes"
