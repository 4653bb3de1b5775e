#!/usr/bin/env bash
# Builds and runs every test of `make test`: the unit tests at -O2 and under ASan+UBSan,
# and the deck-level checks with both builds of the program. Ends with "N passed, N failed".
#
# The four builds (./lpfdm, build/lpfdm-san, build/tests, build/tests-san) and the runs are
# jobs on one queue, taken by as many workers as cores (at least two), each worker the
# next job when its last is done: the builds first, the longest soonest, then the runs,
# the longest first (check_cmake.sh with its own CMake build, then the two unit runs). A
# run waits for the build it needs, and the checks that need only ./lpfdm start while the
# test builds compile: built by one make before the runs, the builds left a core idle for
# a minute or two while the last of them compiled. The checks differ in length a
# hundredfold and some run for one build only: one fixed lane per build, as before, left a
# core idle for minutes. The logs are printed afterwards, in a fixed order.
set -u
cd "$(dirname "$0")/.."
passed=0 failed=0
dir=$(mktemp -d); trap 'rm -rf "$dir"' EXIT

# built TARGET: waits for the build job of TARGET to end; true when it built. A build
# writes $dir/built.NAME (its exit status) when it ends.
built() {
    local t=${1#./}
    local mark=$dir/built.${t//\//_} since
    since=$(date +%s)
    while [ ! -e "$mark" ]; do sleep 1; done
    waited=$((waited + $(date +%s) - since))  # (the job's core idle meanwhile, all its waits: run.sh's last lines)
    [ "$(cat "$mark")" = 0 ] || { echo "the build of $1 failed (its log is printed below)"; return 1; }
}
# job N KIND ARG: KIND build (ARG a make target), unit-o2, unit-san, or check (ARG "SCRIPT
# EXE"); writes $dir/N.log and $dir/N.rc.
job() {
    local n=$1 kind=$2 arg=${3:-} start=$SECONDS rc t waited=0
    t=$(date +%s)
    case $kind in
        # each target by one make, so that no two write the same file
        # (the test builds wait for the packages' job, so that two apt-get never run at once)
        # (the sanitizer kernel, build/san/kernel.o, is build/lpfdm-san's: its job makes it,
        # and the sanitizer tests' job makes their own units first, then waits for it)
        build) case $arg in build/tests*) built test-deps ;; esac &&
               case $arg in
                   build/tests-san) make --no-print-directory san-test-units &&
                                    built build/lpfdm-san && make --no-print-directory build/tests-san ;;
                   *) make --no-print-directory "$arg" ;;
               esac; rc=$?
               echo $rc >"$dir/built.${arg//\//_}"; [ $rc = 0 ] ;;
        # the cases tagged [verify] are make verify's: a case without it checks the same at a coarser size
        unit-o2) built build/tests && OMP_NUM_THREADS=1 build/tests --no-version=1 --test-case-exclude='*[verify]*' ;;
        # the sanitizer build leaves out the [slow] cases and runs the whole-scene comparisons
        # smaller (LPFDM_TEST_SMALL: tests/common.hpp); the kernel's own threads stay at one
        unit-san) built build/tests-san && LPFDM_TEST_SMALL=1 OMP_NUM_THREADS=1 ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
                      build/tests-san --no-version=1 --test-case-exclude='*[slow]*,*[verify]*' ;;
        check) built test-deps && built "${arg#* }" && bash ${arg% *} "${arg#* }" ;;
    esac >"$dir/$n.log" 2>&1
    echo $? >"$dir/$n.rc"
    echo "$((SECONDS - start)) $kind${arg:+ $arg}" >"$dir/$n.time"
    echo "$((t + waited - t0)) $(($(date +%s) - t0)) $kind${arg:+ $arg}" >"$dir/$n.span"
}
export -f job built
export dir t0=$(date +%s)
# Two jobs run at once on a two-core machine, so a run's second OpenMP thread shares a core
# with another job: threads that wait at a barrier sleep instead of spinning through the
# time slice the thread they wait for needs (check_threads.sh under the sanitizers beside
# a busy core: 35 s instead of 43). It changes when a thread runs, never a number.
export OMP_WAIT_POLICY=passive

# The Debian packages. The program's (fmt) first, alone. The tests' (Eigen, doctest, Clang,
# CMake, gnuplot, Python's readers) are the queue's first job, `make test-deps`, when this
# runs as root: on a fresh machine their installation takes a minute or two, which the
# other core spends building the two programs, which need fmt only; the test builds and
# every check wait for it. Not root: make test-deps stops here with the apt-get command.
make --no-print-directory deps || exit 1
[ "$(id -u)" = 0 ] || make --no-print-directory test-deps || exit 1

# Jobs 1 and 2 are the unit runs, then every tests/check_*.sh with each build of the program
# (./lpfdm, then build/lpfdm-san), then the packages and the four builds. The queue takes
# those first: the packages, the two programs beside them, the sanitizer tests (the longest
# build), the -O2 tests, check_cmake.sh with ./lpfdm (its own CMake build, the longest
# run), then the unit runs and the others in the order above.
n=0 list=()
add() { n=$((n + 1)); list+=("$n $1${2:+ $2}"); }
add unit-o2
add unit-san
# (the longest checks first: the fuzzing smoke and the documents' commands)
scripts=$(ls tests/check_*.sh | awk '/check_(fuzz|docs)\.sh$/ { print; next } { rest = rest $0 "\n" } END { printf "%s", rest }')
for exe in ./lpfdm build/lpfdm-san; do
    for script in $scripts; do add check "$script $exe"; done
done
builds=$n
for target in test-deps lpfdm build/lpfdm-san build/tests-san build/tests; do add build "$target"; done
cmake_job=$(printf '%s\n' "${list[@]}" | grep -m 1 ' check tests/check_cmake.sh ./lpfdm$')
workers=$(nproc 2>/dev/null || echo 2)
[ "$workers" -ge 2 ] || workers=2
{
    printf '%s\n' "${list[@]:builds}"
    [ -n "$cmake_job" ] && echo "$cmake_job"
    printf '%s\n' "${list[@]:0:builds}" | grep -vxF "${cmake_job:-none}"
} | xargs -P "$workers" -L 1 bash -c 'job "$1" "$2" "${*:3}"' _

# A build that failed: its compiler's messages first.
for ((k = builds + 1; k <= n; k++)); do
    [ "$(cat "$dir/$k.rc" 2>/dev/null)" = 0 ] || { echo "== the build of ${list[k - 1]#* build }:"; tail -n 40 "$dir/$k.log"; failed=$((failed + 1)); }
done

count() {  # $1: label, $2: log; adds doctest's "test cases" totals
    local line p f
    line=$(grep -E '^\[doctest\] test cases:' "$2" | tail -1)
    p=$(sed -E 's/.*\| *([0-9]+) passed.*/\1/' <<<"$line"); f=$(sed -E 's/.*\| *([0-9]+) failed.*/\1/' <<<"$line")
    [[ $p =~ ^[0-9]+$ ]] || p=0; [[ $f =~ ^[0-9]+$ ]] || f=1
    echo "$1: $p passed, $f failed"
    passed=$((passed + p)); failed=$((failed + f))
}
rc_of() { local rc; rc=$(cat "$dir/$1.rc" 2>/dev/null); [[ $rc =~ ^[0-9]+$ ]] && echo "$rc" || echo 1; }
cat "$dir/1.log"; count "unit (-O2)" "$dir/1.log"; [ "$(rc_of 1)" -eq 0 ] || failed=$((failed + (failed == 0)))
tail -n 30 "$dir/2.log"; count "unit (ASan+UBSan)" "$dir/2.log"; [ "$(rc_of 2)" -eq 0 ] || failed=$((failed + (failed == 0)))
# Program-level checks: each, given the program, ends with "NAME: N passed, M failed"; in the
# order of the queue (the plain build's, then the sanitizer build's).
for ((k = 3; k <= builds; k++)); do
    tail -n 40 "$dir/$k.log"
    line=$(grep -E '^[A-Za-z_-]+: [0-9]+ passed, [0-9]+ failed$' "$dir/$k.log" | tail -1)
    p=$(sed -E 's/^[A-Za-z_-]+: ([0-9]+) passed.*/\1/' <<<"$line"); f=$(sed -E 's/.* ([0-9]+) failed$/\1/' <<<"$line")
    [[ $p =~ ^[0-9]+$ ]] || p=0; [[ $f =~ ^[0-9]+$ ]] || f=1
    [ "$(rc_of $k)" -eq 0 ] || [ "$f" -gt 0 ] || f=1
    passed=$((passed + p)); failed=$((failed + f))
done
# How long each job took (seconds, longest first): where make test's time goes.
echo "longest jobs, seconds each ($workers at a time): $(cat "$dir"/*.time 2>/dev/null | sort -rn | head -n 8 | sed 's/ tests\/check_/ /; s/\.sh / /' | paste -sd ';' | sed 's/;/; /g')"
# Where the cores waited: the queue's wall time against the jobs' own, and when each job ran.
sort -n "$dir"/*.span 2>/dev/null | awk -v w="$workers" '{ busy += $2 - $1; if ($2 > end) end = $2 }
    END { if (end > 0) printf "the queue: %d s wall, %d of %d core-seconds in jobs (%.0f %% busy)\n", end, busy, w * end, 100 * busy / (w * end) }'
echo "the last to end (start-end s): $(sort -k2 -n "$dir"/*.span 2>/dev/null | tail -n 4 | awk '{ printf "%s%s-%s %s %s%s", (NR > 1 ? "; " : ""), $1, $2, $3, $4, (NF > 4 ? " " $5 : "") }' | sed 's/tests\/check_//g; s/\.sh//g')"
echo "core-seconds by kind: $(cat "$dir"/*.span 2>/dev/null | awk '{ k = $3 == "check" ? ($5 ~ /san/ ? "checks (sanitizer program)" : "checks (plain program)") : $3 == "build" ? "builds" : "unit runs"; t[k] += $2 - $1 }
    END { for (k in t) printf "%s%s %d", (n++ ? "; " : ""), k, t[k] }')"
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
