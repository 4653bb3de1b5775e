#!/usr/bin/env bash
# Program-level checks of restart files (OUTPUT STATE, lpfdm --restart; decks/README.md):
#   - a run stopped at step k (--steps k) and continued with --restart writes the same
#     bytes as the run that was never stopped: the frames of its point table after k,
#     its history rows after k, its last VTU frame and its last state; with the fast
#     kernel and the reference kernel, one and two threads, and across kernels (a state
#     of one continued by the other); the state files of every kernel and thread count
#     are the same bytes (the sanitizer build: the two pairings across kernels only);
#   - SIGINT: exit status 130, the state of the interrupted step written, and --restart
#     from it gives the uninterrupted run's frames and rows;
#   - a state file that is truncated, corrupt, of another format version, of another
#     deck or other options, not a state file at all, a directory, or already at the
#     last step is refused: exit status 2, "FILE: error: ..." naming the problem, no
#     output file.
#
# usage: tests/check_restart.sh EXE
# Last line "restart: N passed, M failed".
set -u

. "$(dirname "$0")/lib.sh"
need_program restart "$@"
base="fast, 1 thread"  # the stopped run whose state the refusals below edit
sanitizer_build "$exe" && base="fast to reference"

tmp=$(mktemp -d) || exit 2
trap 'rm -rf "$tmp"' EXIT
passed=0 failed=0
pass() { passed=$((passed + 1)); }
fail() { echo "FAIL $1: $2"; failed=$((failed + 1)); }
check() { if [ "$2" -eq 0 ]; then pass; else fail "$1" "$3"; fi; }

# A Mohr-Coulomb block with strength scatter and softening, pressed by a wall under a
# strong gravity: points yield, soften and leave the lattice on the right (outflow);
# 5184 points, so that two threads take the threaded point pass (above 4096).
cat >"$tmp/r.deck" <<'EOF'
TITLE restart
GRID 64 32 0.125
MATERIAL 1 MOHR E=5E7 NU=0.3 RHO=2000 PHI=30 C=2000 SOFTEN=0.5 SCATTER=0.2
CLUSTER 1 5 0 8 3 PPC=3
FIX XY 0 0 8 0
WALL 1 5.5 3 6.5 3 0 -2
GRAVITY 0 -98.1
SEED 7
STEP 4E-4 120
OUTPUT POINTS p.txt EVERY 20
OUTPUT HISTORY h.txt EVERY 1
OUTPUT STATE s.state EVERY 50
OUTPUT VTU v EVERY 40
END
EOF

# frames FILE K: the frames of a point table after step K; rows FILE K: the history rows after step K.
frames() { awk -v k="$2" '/^# step [0-9]/ { keep = ($3 > k) } /^# run / { keep = 0 } keep' "$1"; }
rows() { awk -v k="$2" '!/^#/ && $1 ~ /^[0-9]+$/ && $1 > k' "$1"; }
report() { grep -m 1 -E 'runtime error:|AddressSanitizer|LeakSanitizer|terminate called|Assertion .* failed' "$1"; }

# run DIR ARGS...: EXE -q -o DIR ARGS, stderr in DIR.err; sets rc.
run() {
    local d=$1
    shift
    rm -rf "$d"
    { timeout -k 5 300 "$exe" -q -o "$d" "$@" >/dev/null 2>"$d.err" </dev/null; rc=$?; } 2>/dev/null
    local r
    r=$(report "$d.err")
    if [ -n "$r" ]; then fail "$d" "sanitizer report or abort: $r"; return 1; fi
    return 0
}

# --- 1. stopped at step 60, continued: the same bytes as the whole run (the paper's
# mapping, then MAPPING SMOOTH, whose next step also reads the cells' centroids) ---
stopped_and_continued() {  # DECK TAG
    local deck=$1 tag=$2 whole="$tmp/$2whole"
    run "$whole" "$deck" || exit 1
    check "${tag}whole run" $rc "exit status $rc: $(head -n 1 "$whole.err")"
    n_frames=$(frames "$whole/p.txt" 60 | grep -c '^# step')
    check "${tag}whole run: frames after step 60" $([ "$n_frames" = 3 ]; echo $?) "$n_frames frames, expected 3 (80, 100, 120)"
    out_mass=$(rows "$whole/h.txt" 119 | awk '{print $5}')
    check "${tag}whole run: points leave the lattice" $(awk -v m="$out_mass" 'BEGIN { exit !(m > 0) }'; echo $?) "mass_out $out_mass at step 120"

    # continued NAME KERNEL_STOP THREADS_STOP KERNEL_GO THREADS_GO
    continued() {
        local a="$tmp/$tag$1-a" b="$tmp/$tag$1-b"
        run "$a" --kernel "$2" --threads "$3" --steps 60 "$deck" || return
        check "$tag$1: stopped run" $rc "exit status $rc: $(head -n 1 "$a.err")"
        check "$tag$1: state written" $([ -s "$a/s.state" ]; echo $?) "no $a/s.state"
        run "$b" --kernel "$4" --threads "$5" --restart "$a/s.state" "$deck" || return
        check "$tag$1: continued run" $rc "exit status $rc: $(head -n 1 "$b.err")"
        check "$tag$1: first frame at the saved step" $([ "$(grep -m 1 '^# step' "$b/p.txt")" = "# step 60 time 0.024" ]; echo $?) \
            "first frame '$(grep -m 1 '^# step' "$b/p.txt")'"
        check "$tag$1: point table frames after step 60" $(cmp -s <(frames "$whole/p.txt" 60) <(frames "$b/p.txt" 60); echo $?) \
            "differ from the whole run's"
        check "$tag$1: history rows after step 60" $(cmp -s <(rows "$whole/h.txt" 60) <(rows "$b/h.txt" 60) && [ "$(rows "$b/h.txt" 60 | wc -l)" = 60 ]; echo $?) \
            "differ from the whole run's ($(rows "$b/h.txt" 60 | wc -l) rows)"
        check "$tag$1: last VTU frame" $(cmp -s "$whole/v_000120.vtu" "$b/v_000120.vtu"; echo $?) "differs from the whole run's"
        check "$tag$1: last state" $(cmp -s "$whole/s.state" "$b/s.state"; echo $?) "differs from the whole run's"
    }
    # The sanitizer build (a name containing "san") runs the two pairings that make each
    # kernel write a state and the other read it, one of them on two threads: the same code
    # paths (a coverage build: the same lines of lpfdm.cpp and lpfdm.hpp executed by this
    # check with the two as with all five) in a third of the time; the plain build checks
    # every pairing's bytes.
    if sanitizer_build "$exe"; then
        continued "fast to reference" fast 2 reference 1
        continued "reference to fast, 2 threads" reference 1 fast 2
        return
    fi
    continued "fast, 1 thread" fast 1 fast 1
    continued "fast, 2 threads" fast 2 fast 2
    continued "reference" reference 1 reference 1
    continued "fast to reference" fast 2 reference 1
    continued "reference to fast, 2 threads" reference 1 fast 2
    for other in "fast, 2 threads" "reference"; do
        check "the state at step 60 of '$other' is the fast kernel's" $(cmp -s "$tmp/${tag}fast, 1 thread-a/s.state" "$tmp/$tag$other-a/s.state"; echo $?) \
            "the state files differ"
    done
}
stopped_and_continued "$tmp/r.deck" ""
sed 's/^END/MAPPING SMOOTH\nEND/' "$tmp/r.deck" >"$tmp/rs.deck"
stopped_and_continued "$tmp/rs.deck" "smooth: "
# REORDER 7: the state keeps the points' storage order (sorted at step 56, not at 60)
sed 's/^END/REORDER 7\nEND/' "$tmp/r.deck" >"$tmp/rr.deck"
stopped_and_continued "$tmp/rr.deck" "reorder: "
# ADVECT FLIP (with MAPPING SMOOTH): each point's own increment and the nodes the wall
# drove last are state; the reference cycle runs it whichever kernel is asked for. Damped,
# so that the wall still presses on the block at step 60 and points leave the lattice by
# 120 (undamped, the block has sprung away from the wall by step 60, and the nodes it drove
# would not be tested).
sed 's/^END/MAPPING SMOOTH\nADVECT FLIP\nDAMPING 0.4\nEND/' "$tmp/r.deck" >"$tmp/rf.deck"
stopped_and_continued "$tmp/rf.deck" "flip: "
# DAMPING WINDOW: each node's mean increment is state (with MAPPING SMOOTH, whose nodes
# beyond the material read it again)
sed 's/^END/MAPPING SMOOTH\nDAMPING 0.4 WINDOW=0.004\nEND/' "$tmp/r.deck" >"$tmp/rd.deck"
stopped_and_continued "$tmp/rd.deck" "window: "
# SHIFT from the first crowding (ABOVE=1, passes every 10 steps from step 10): the
# potential energy its moves gave (the account's w_shift) and their count are state; with
# the paper's cycle and under ADVECT FLIP (whose squares it moves)
sed 's/^END/SHIFT ABOVE=1\nEND/' "$tmp/r.deck" >"$tmp/rsh.deck"
stopped_and_continued "$tmp/rsh.deck" "shift: "
sed 's/^END/MAPPING SMOOTH\nADVECT FLIP\nDAMPING 0.4\nSHIFT ABOVE=1\nEND/' "$tmp/r.deck" >"$tmp/rfsh.deck"
stopped_and_continued "$tmp/rfsh.deck" "shift, flip: "
for d in rsh rfsh; do  # the passes moved points before step 60 and after it
    "$exe" -q -o "$tmp/$d-moves" "$tmp/$d.deck" >/dev/null 2>&1
    moves=$(awk '!/^#/ && ($1 == 60 || $1 == 120) { printf "%s ", $NF }' "$tmp/$d-moves/h.txt")
    check "$d: points moved by step 60 and after" $(echo "$moves" | awk '{ exit !($1 > 0 && $2 > $1) }'; echo $?) "the history's shifted at steps 60 and 120: $moves"
done
# WATER, DRAIN, LOAD, RESERVOIR (falling from step 25 to 75), GEOSTATIC: each point's pore
# pressure, the volume it last took, the force it carries; the water drained, the flow's
# dissipation and the loads' work are state; the reservoir's level follows the time.
sed 's/^\(MATERIAL 1 MOHR .*\)$/\1 POROSITY=0.4 PERM=1E-4/; s/^END/WATER KW=1E7 TABLE=2\nDRAIN 5 3 8 3\nLOAD 7 3 8 3 TY=-2E4\nRESERVOIR 3.5 TO=1 START=0.01 OVER=0.02\nGEOSTATIC\nEND/' "$tmp/r.deck" >"$tmp/rw.deck"
stopped_and_continued "$tmp/rw.deck" "water: "

# SHAKE and ABSORB: the ground's motion (replayed on restart), the base released at START
# (step 30) keeping its reactions (in the state), local damping switched to SHAKE's
printf '# t a\n0 0\n0.01 20\n0.02 -30\n0.03 10\n0.05 0\n' >"$tmp/m.txt"
sed 's/^END/SHAKE X FILE=m.txt START=0.012 DAMPING=0.1 BASELINE\nABSORB BOTTOM\nEND/' "$tmp/r.deck" >"$tmp/rq.deck"
stopped_and_continued "$tmp/rq.deck" "quake: "
# The same ground and dashpots under ADVECT FLIP: the slip at the shaken nodes is state
# (the account's d_slip), the dashpots' work is counted after the points' change
# (absorb_work); and a wall embedded in the block (a pair of node lines, whose increments
# change every step), whose nodes a restart lists in node order where the run listed them
# in the order the wall took them: the slip is summed in node order either way
sed 's/^END/MAPPING SMOOTH\nADVECT FLIP\nSHAKE X FILE=m.txt START=0.012 DAMPING=0.1 BASELINE\nABSORB BOTTOM\nEND/' "$tmp/r.deck" >"$tmp/rqf.deck"
stopped_and_continued "$tmp/rqf.deck" "quake, flip: "
sed 's/^WALL 1 5.5 3 6.5 3 0 -2$/WALL 1 5.5 2.5 6.5 2.5 0 -2/; s/^END/MAPPING SMOOTH\nADVECT FLIP\nSHAKE X FILE=m.txt BASELINE\nEND/' "$tmp/r.deck" >"$tmp/rqe.deck"
grep -q "^WALL 1 5.5 2.5 6.5 2.5 0 -2$" "$tmp/rqe.deck" || { echo "check_restart.sh: the embedded wall's deck was not made" >&2; exit 1; }
stopped_and_continued "$tmp/rqe.deck" "embedded wall, flip: "

# --- 2. SIGINT: the state of the interrupted step, continued ---
cat >"$tmp/long.deck" <<'EOF'
TITLE run to be stopped
GRID 8 8 0.5
MATERIAL 1 MOHR E=2E7 NU=0.25 RHO=2000 PHI=30 C=1000 SOFTEN=0.3 SCATTER=0.2
CLUSTER 1 0 0 4 2
FIX XY 0 0 4 0
WALL 1 1 2 3 2 0 -0.01
GRAVITY 0 -9.81
DAMPING 0.8
STEP 1E-4 100000000
OUTPUT POINTS p.txt EVERY 1000
OUTPUT HISTORY h.txt EVERY 100
OUTPUT STATE s.state EVERY 10000000
END
EOF
rm -rf "$tmp/int"
{ timeout -k 30 -s INT --preserve-status 2 "$exe" -q -o "$tmp/int" "$tmp/long.deck" >/dev/null 2>"$tmp/int.err" </dev/null; rc=$?; } 2>/dev/null
check "SIGINT: exit status" $([ $rc -eq 130 ]; echo $?) "exit status $rc, expected 130 ($(head -n 2 "$tmp/int.err" | tr '\n' ' '))"
k=$(sed -n -E 's/.*interrupted at step ([0-9]+).*/\1/p' "$tmp/int.err" | head -n 1)
check "SIGINT: the message names the state" $(grep -q 'and the state' "$tmp/int.err"; echo $?) "stderr: $(tail -n 1 "$tmp/int.err")"
if [ -n "$k" ] && [ -s "$tmp/int/s.state" ]; then
    n=$((k / 1000 * 1000 + 2037))  # frames at two multiples of 1000 after k, and at the end
    run "$tmp/int-whole" --steps "$n" "$tmp/long.deck" &&
        run "$tmp/int-go" --steps "$n" --restart "$tmp/int/s.state" "$tmp/long.deck" && {
        check "SIGINT: continued run" $rc "exit status $rc: $(head -n 1 "$tmp/int-go.err")"
        check "SIGINT: point table frames after step $k" \
            $(cmp -s <(frames "$tmp/int-whole/p.txt" "$k") <(frames "$tmp/int-go/p.txt" "$k") && [ "$(frames "$tmp/int-go/p.txt" "$k" | grep -c '^# step')" = 3 ]; echo $?) \
            "differ from the uninterrupted run's"
        check "SIGINT: history rows after step $k" $(cmp -s <(rows "$tmp/int-whole/h.txt" "$k") <(rows "$tmp/int-go/h.txt" "$k"); echo $?) \
            "differ from the uninterrupted run's"
    }
else
    fail "SIGINT: state" "no interrupted step in stderr ('$(tail -n 1 "$tmp/int.err")') or no state file"
fi

# --- 3. state files that are refused ---
good="$tmp/$base-a/s.state"
size=$(stat -c %s "$good")
head -c $((size / 2)) "$good" >"$tmp/truncated.state"
head -c 20 "$good" >"$tmp/short.state"
cp "$good" "$tmp/corrupt.state"
printf '\x55' | dd of="$tmp/corrupt.state" bs=1 seek=$((size / 2)) conv=notrunc 2>/dev/null
cmp -s "$good" "$tmp/corrupt.state" && printf '\xaa' | dd of="$tmp/corrupt.state" bs=1 seek=$((size / 2)) conv=notrunc 2>/dev/null
cp "$good" "$tmp/version.state"
printf '\x06' | dd of="$tmp/version.state" bs=1 seek=12 conv=notrunc 2>/dev/null
echo "x y sxx" >"$tmp/text.state"
sed 's/^SEED 7/SEED 8/' "$tmp/r.deck" >"$tmp/other.deck"
mkdir -p "$tmp/dir.state"
# refused NAME PHRASE STATE ARGS...
refused() {
    local name=$1 phrase=$2 state=$3
    shift 3
    run "$tmp/refused" --restart "$state" "$@" || return
    check "$name: exit status" $([ $rc -eq 2 ]; echo $?) "exit status $rc, expected 2"
    local first
    first=$(head -n 1 "$tmp/refused.err")
    check "$name: message" $([[ $first == "$state: error: "*"$phrase"* ]]; echo $?) "'$first' is not '$state: error: ...$phrase...'"
    check "$name: no output" $([ ! -e "$tmp/refused" ]; echo $?) "the output directory was made: $(ls "$tmp/refused" 2>/dev/null | tr '\n' ' ')"
}
refused "truncated" "truncated" "$tmp/truncated.state" "$tmp/r.deck"
refused "shorter than a header" "truncated" "$tmp/short.state" "$tmp/r.deck"
refused "corrupt" "checksum" "$tmp/corrupt.state" "$tmp/r.deck"
refused "other format version" "version 6" "$tmp/version.state" "$tmp/r.deck"
refused "not a state file" "not an lpfdm state file" "$tmp/text.state" "$tmp/r.deck"
refused "a directory" "directory" "$tmp/dir.state" "$tmp/r.deck"
refused "missing" "cannot open" "$tmp/none.state" "$tmp/r.deck"
refused "other deck" "another deck" "$good" "$tmp/other.deck"
refused "other --seed" "another deck" "$good" --seed 3 "$tmp/r.deck"
refused "other --set" "another deck" "$good" --set MATERIAL1.C=2500 "$tmp/r.deck"
refused "at the last step" "where the run ends" "$tmp/whole/s.state" "$tmp/r.deck"
# the motion file edited between the runs: another record, another scene
mkdir -p "$tmp/edited" && cp "$tmp/rq.deck" "$tmp/edited/rq.deck" && sed 's/^0.02 -30$/0.02 -31/' "$tmp/m.txt" >"$tmp/edited/m.txt"
refused "other motion file" "another deck" "$tmp/quake: $base-a/s.state" "$tmp/edited/rq.deck"
run "$tmp/further" --steps 130 --restart "$tmp/whole/s.state" "$tmp/r.deck" &&
    check "--steps runs a finished state further" $([ $rc -eq 0 ] && [ "$(rows "$tmp/further/h.txt" 0 | wc -l)" = 10 ]; echo $?) \
        "exit status $rc, $(rows "$tmp/further/h.txt" 0 | wc -l) history rows (expected 10)"

echo "restart: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
