#!/usr/bin/env bash
# Program-level checks of the run guards (decks/README.md: exit status, output files):
#   - SIGINT: exit status 130, the last frame and a history row written, the tables
#     renamed from NAME.part and ending with a "# run interrupted" comment;
#   - a run killed without warning leaves only NAME.part files, never a table that
#     looks complete (write, then rename);
#   - a run that goes wrong numerically: exit status 3, the step, the point and its
#     cell named, the tables closed with a "# run stopped" comment, the last good
#     frame written;
#   - a normal run: exit status 0, no .part file, no such comment;
#   - a run whose cycle creates energy (energy_error below -0.1): it completes (exit
#     status 0) with a warning on stderr (the tables are left as they are); not when
#     the same scene is resolved finely.
#
# usage: tests/check_guards.sh EXE
#
# Every check counts; GUARDS_STRICT=0 reports a missing behaviour as "GAP ..." without
# counting it (for work in progress). Last line "guards: N passed, M failed".
set -u

. "$(dirname "$0")/lib.sh"
need_program guards "$@"

tmp=$(mktemp -d) || exit 2
trap 'rm -rf "$tmp"' EXIT
passed=0 failed=0 gaps=0
strict=${GUARDS_STRICT:-1}
pass() { passed=$((passed + 1)); }
fail() { echo "FAIL $1: $2"; failed=$((failed + 1)); }
# gap NAME MESSAGE: a known missing behaviour (a failure when GUARDS_STRICT=1)
gap() {
    if [ "$strict" = 1 ]; then fail "$1" "$2"; else echo "GAP $1: $2"; gaps=$((gaps + 1)); fi
}
# expect NAME CONDITION-STATUS MESSAGE [gap]: counts a check
check() {
    local name=$1 ok=$2 msg=$3 kind=${4:-}
    if [ "$ok" -eq 0 ]; then pass
    elif [ "$kind" = gap ]; then gap "$name" "$msg"
    else fail "$name" "$msg"; fi
}

# --- decks, written here ---
# 128 elastic points settling on a fixed floor: about 10^5 steps per second, run for 10^8.
cat >"$tmp/long.deck" <<'EOF'
TITLE run to be stopped
GRID 8 8 0.5
MATERIAL 1 ELASTIC E=2E7 NU=0.25 RHO=2000
CLUSTER 1 0 0 4 2
FIX XY 0 0 4 0
GRAVITY 0 -9.81
DAMPING 0.8
STEP 1E-4 100000000
OUTPUT POINTS p.txt EVERY 10000000
OUTPUT HISTORY h.txt EVERY 1000000
OUTPUT HISTORY every.txt
END
EOF
# The same scene, 200 steps to the end.
sed -e 's/^STEP .*/STEP 1E-4 200/' -e 's/EVERY 10000000/EVERY 50/' -e 's/EVERY 1000000/EVERY 20/' "$tmp/long.deck" >"$tmp/short.deck"
# Gravity 10^4 m/s^2 crushes the block: the nodal increments grow by g dt^2 = 0.01 m per
# step and pass half a cell (0.25 m) after a few tens of steps. Frames every 1000 steps.
cat >"$tmp/crush.deck" <<'EOF'
TITLE crushed by a huge gravity
GRID 8 8 0.5
MATERIAL 1 ELASTIC E=2E7 NU=0.25 RHO=2000
CLUSTER 1 0 0 4 2
FIX XY 0 0 4 0
GRAVITY 0 -1E4
STEP 1E-3 100000
OUTPUT POINTS p.txt EVERY 1000
OUTPUT HISTORY h.txt EVERY 1000
END
EOF
# Gravity 10^308: the first nodal force overflows to infinity.
sed -e 's/^GRAVITY .*/GRAVITY 0 -1E308/' -e 's/^TITLE .*/TITLE infinite force/' "$tmp/crush.deck" >"$tmp/inf.deck"

# run NAME DECK SIGNAL SECONDS: runs EXE on DECK into $tmp/NAME; SIGNAL "" for none.
# Sets $rc, $out and $err (stderr file).
run() {
    out="$tmp/$1" err="$tmp/$1.stderr"
    rm -rf "$out" && mkdir -p "$out"
    if [ -n "$3" ]; then
        { timeout -k 30 -s "$3" --preserve-status "$4" "$exe" -q -o "$out" "$2" >/dev/null 2>"$err" </dev/null; rc=$?; } 2>/dev/null
    else
        { timeout -k 5 "$4" "$exe" -q -o "$out" "$2" >/dev/null 2>"$err" </dev/null; rc=$?; } 2>/dev/null
    fi
    local report
    report=$(grep -m 1 -E 'runtime error:|AddressSanitizer|LeakSanitizer|terminate called|Assertion .* failed' "$err")
    if [ -n "$report" ]; then fail "$1" "sanitizer report or abort: $report"; return 1; fi
    return 0
}
no_part() {  # NAME: no NAME.part left in $out
    local parts
    parts=$(cd "$out" && ls ./*.part 2>/dev/null | tr '\n' ' ')
    check "$1: no .part file" $([ -z "$parts" ]; echo $?) "left behind: $parts"
}
last_line() { tail -n 1 "$1" 2>/dev/null; }
last_frame_step() { grep -E '^# step [0-9]+' "$1" | tail -n 1 | awk '{print $3}'; }
# rows of the last frame of a point table (data lines after the last "# step")
last_frame_rows() { awk '/^# step /{n=0; next} /^[^#]/ && NF {n++} END {print n+0}' "$1"; }
first_frame_rows() { awk '/^# step /{f++; next} f==1 && /^[^#]/ && NF {n++} END {print n+0}' "$1"; }
all_finite() { ! grep -v '^#' "$1" | grep -q -i -E 'nan|inf'; }
last_row_step() { grep -v '^#' "$1" | grep . | tail -n 1 | awk '{print $1}'; }

# --- 1. SIGINT ---
if run sigint "$tmp/long.deck" INT 3; then
    check "SIGINT: exit status" $([ $rc -eq 130 ]; echo $?) "exit status $rc, expected 130 (stderr: $(head -n 1 "$err"))"
    n=$(sed -n -E 's/.*interrupted at step ([0-9]+).*/\1/p' "$err" | head -n 1)
    check "SIGINT: message names the step" $([ -n "$n" ]; echo $?) "stderr does not say 'interrupted at step N': $(head -n 1 "$err")"
    no_part "SIGINT"
    for f in p.txt h.txt every.txt; do
        if [ ! -f "$out/$f" ]; then fail "SIGINT: $f" "not written"; continue; fi
        check "SIGINT: $f ends with '# run interrupted'" $([[ $(last_line "$out/$f") == "# run interrupted"* ]]; echo $?) \
            "last line is '$(last_line "$out/$f")'"
    done
    if [ -n "$n" ] && [ -f "$out/p.txt" ]; then
        s=$(last_frame_step "$out/p.txt")
        check "SIGINT: last frame at the interrupted step" $([ "$s" = "$n" ]; echo $?) "last frame is step $s, interrupted at $n"
        r0=$(first_frame_rows "$out/p.txt") r1=$(last_frame_rows "$out/p.txt")
        check "SIGINT: last frame complete" $([ "$r0" -gt 0 ] && [ "$r0" = "$r1" ]; echo $?) "$r1 rows in the last frame, $r0 in the first"
        check "SIGINT: finite values" $(all_finite "$out/p.txt"; echo $?) "a nan or inf in the point table"
    fi
    if [ -n "$n" ] && [ -f "$out/h.txt" ]; then
        s=$(last_row_step "$out/h.txt")
        check "SIGINT: a history row at the interrupted step" $([ "$s" = "$n" ]; echo $?) "last history row is step '$s', interrupted at $n"
    fi
    if [ -f "$out/every.txt" ]; then  # history of every step: the interrupted step once
        d=$(grep -v '^#' "$out/every.txt" | grep . | awk '{print $1}' | uniq -d | head -n 3 | tr '\n' ' ')
        check "SIGINT: no duplicated history row" $([ -z "$d" ]; echo $?) \
            "history of every step repeats step(s) $d: the row due at that step and the interruption row are both written" gap
    fi
fi

# --- 2. killed without warning: only .part files, no table that looks complete ---
if run killed "$tmp/long.deck" KILL 2; then
    complete=$(cd "$out" && ls p.txt h.txt every.txt 2>/dev/null | tr '\n' ' ')
    parts=$(cd "$out" && ls ./*.part 2>/dev/null | wc -l)
    check "SIGKILL: no complete-looking table" $([ -z "$complete" ]; echo $?) "found $complete after a kill"
    check "SIGKILL: the tables are NAME.part" $([ "$parts" -eq 3 ]; echo $?) "$parts .part files, expected 3"
fi

# --- 3. a normal run ---
if run normal "$tmp/short.deck" "" 60; then
    check "normal run: exit status" $([ $rc -eq 0 ]; echo $?) "exit status $rc (stderr: $(head -n 1 "$err"))"
    no_part "normal run"
    for f in p.txt h.txt every.txt; do
        if [ ! -f "$out/$f" ]; then fail "normal run: $f" "not written"; continue; fi
        check "normal run: $f has no stop comment" $(! grep -q -E '^# run (interrupted|stopped)' "$out/$f"; echo $?) "a stop comment in a complete run"
    done
    s=$(last_frame_step "$out/p.txt")
    check "normal run: last frame at the last step" $([ "$s" = 200 ]; echo $?) "last frame is step $s"
    s=$(last_row_step "$out/every.txt") c=$(grep -v -e '^#' -e '^step ' "$out/every.txt" | grep -c .)
    check "normal run: one history row per step" $([ "$s" = 200 ] && [ "$c" = 200 ]; echo $?) "$c rows, the last at step $s"
fi

# --- 4. numerical trouble ---
# trouble NAME DECK PHRASE
trouble() {
    run "$1" "$2" "" 60 || return
    check "$1: exit status" $([ $rc -eq 3 ]; echo $?) "exit status $rc, expected 3 (stderr: $(head -n 1 "$err"))"
    local first n s
    first=$(grep -m 1 'error:' "$err")
    n=$(sed -n -E 's/.*numerical trouble at step ([0-9]+).*/\1/p' "$err" | head -n 1)
    check "$1: message names the step" $([ -n "$n" ]; echo $?) "stderr: $first"
    check "$1: message says what happened" $([[ $first == *"$3"* ]]; echo $?) "'$first' does not say '$3'"
    check "$1: message names the point and its cell" $([[ $first =~ point.*cell\ \([0-9]+,\ [0-9]+\) ]]; echo $?) \
        "'$first' names no point or cell (the trouble is in the nodal increments; the points are still finite, so first_nonfinite_point() finds none)" gap
    no_part "$1"
    [ -n "$n" ] || return
    for f in p.txt h.txt; do
        if [ ! -f "$out/$f" ]; then fail "$1: $f" "not written"; continue; fi
        check "$1: $f ends with '# run stopped'" $([[ $(last_line "$out/$f") == "# run stopped at step $n"* ]]; echo $?) \
            "last line is '$(last_line "$out/$f")'"
    done
    s=$(last_frame_step "$out/p.txt")
    check "$1: the last good frame is written" $([ -n "$s" ] && [ "$s" -ge $((n - 1)) ]; echo $?) \
        "the last frame is step $s, the run stopped at step $n (frames are only written every EVERY steps)" gap
    check "$1: finite values in the tables" $(all_finite "$out/p.txt" && all_finite "$out/h.txt"; echo $?) "a nan or inf was written"
}
trouble "unstable run" "$tmp/crush.deck" "more than half a cell"
trouble "non-finite force" "$tmp/inf.deck" "non-finite"

# --- 5. energy created: warned of, the run completes ---
# An undamped elastic block 4 cells across dropped 0.5 m onto a fixed floor, its increments
# carried by the points (ADVECT POINTS): its bounces create 21 % of the energy in play
# (energy_error -0.207 at t = 0.95 s; read every 100 steps, -0.195 at step 2400), above the
# 10 % the program warns at. 16 cells across the same drop creates 0.26 %: no warning.
cat >"$tmp/coarse_drop.deck" <<'EOF'
TITLE elastic block dropped, 4 cells across
GRID 40 24 0.25
MATERIAL 1 ELASTIC E=1E7 NU=0.3 RHO=2000
CLUSTER 1 4.5 0.5 5.5 1.5 PPC=2
FIX Y 0 0 10 0
GRAVITY 0 -9.81
DAMPING 0
ADVECT POINTS
MOTION CENTRE
STEP 4E-4 3000
OUTPUT HISTORY h.txt EVERY 25
END
EOF
sed -e 's/^GRID .*/GRID 160 96 0.0625/' -e 's/^STEP .*/STEP 1E-4 12000/' -e 's/EVERY 25/EVERY 100/' -e 's/4 cells across/16 cells across/' \
    "$tmp/coarse_drop.deck" >"$tmp/fine_drop.deck"
if run "coarse drop" "$tmp/coarse_drop.deck" "" 120; then
    check "energy created: exit status 0" $([ $rc -eq 0 ]; echo $?) "exit status $rc (stderr: $(head -n 1 "$err"))"
    w=$(grep -m 1 'warning: the cycle created energy' "$err")
    check "energy created: warned on stderr" $([ -n "$w" ]; echo $?) "no warning on stderr: $(head -n 1 "$err")"
    check "energy created: the warning names the step and the fraction" $([[ $w =~ energy_error\ reached\ -0\.[0-9]+\ at\ step\ [0-9]+ ]]; echo $?) "'$w'"
    check "energy created: the history is the run's alone (no warning in it)" $(! grep -q 'created energy' "$out/h.txt"; echo $?) \
        "a warning line in the history"
    no_part "coarse drop"
fi
if run "fine drop" "$tmp/fine_drop.deck" "" 300; then
    check "energy kept: exit status 0" $([ $rc -eq 0 ]; echo $?) "exit status $rc"
    check "energy kept: no warning" $(! grep -q 'created energy' "$err" "$out/h.txt"; echo $?) "$(grep -h -m 1 'created energy' "$err" "$out/h.txt")"
fi

[ "$gaps" -eq 0 ] || echo "($gaps known gaps, not counted; GUARDS_STRICT=1 counts them)"
echo "guards: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
