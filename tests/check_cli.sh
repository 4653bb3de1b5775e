#!/usr/bin/env bash
# The command line: GNU option forms, every mistake of the options and the deck in one
# run, warnings and --strict, and the provenance lines of each output file (after its names line).
#
# usage: tests/check_cli.sh EXE
#
# One line per failure, and last "cli: N passed, M failed".
set -u

. "$(dirname "$0")/lib.sh"
need_program cli "$@"
cd "$(dirname "$0")/.." || exit 2

limit=60  # seconds per run
tmp=$(mktemp -d) || exit 2
trap 'rm -rf "$tmp"' EXIT
passed=0 failed=0
fail() { echo "FAIL $1: $2"; failed=$((failed + 1)); }
ok() { passed=$((passed + 1)); }

# run NAME ARGS...: runs EXE ARGS with -o a new empty directory $out; sets $rc, stderr in $err.
run() {
    local name=$1
    shift
    out="$tmp/out.$name" err="$tmp/err.$name"
    rm -rf "$out" && mkdir -p "$out"
    { timeout -k 5 "$limit" "$exe" -o "$out" "$@" >"$tmp/stdout" 2>"$err" </dev/null; rc=$?; } 2>/dev/null
    if [ $rc -ge 124 ]; then fail "$name" "crashed, hung or was killed: exit status $rc ($(head -n 1 "$err"))"; return 1; fi
    return 0
}
# expect NAME STATUS ARGS...: the run ends with STATUS.
expect() {
    local name=$1 want=$2
    shift 2
    run "$name" "$@" || return 1
    if [ $rc -ne "$want" ]; then fail "$name" "exit status $rc, expected $want ($(head -n 1 "$err"))"; return 1; fi
    ok
}
# says NAME PHRASE: stderr of the last run holds PHRASE.
says() {
    if grep -q -F -- "$2" "$err"; then ok; else fail "$1" "stderr does not say '$2': $(tr '\n' '|' <"$err")"; fi
}
deck=tests/decks/threads_outflow.deck

# --- the same run, whichever form the options take (the outputs but their '# run:' lines agree) ---
strip() { grep -v '^# run: ' "$1"; }
expect "--opt value" 0 -q --steps 7 --seed 3 --threads 1 --kernel scalar "$deck" && cp -r "$out" "$tmp/a"
for form in "--steps=7 --seed=3 --threads=1 --kernel=scalar" "-n 7 --seed 3 -t 1 -k scalar" "-n7 -t1 -kscalar --seed=3" "-qn 7 --seed 3 -t 1 -k scalar"; do
    # shellcheck disable=SC2086
    expect "$form" 0 -q $form "$deck" || continue
    same=1
    for f in "$tmp/a"/*; do cmp -s <(strip "$f") <(strip "$out/$(basename "$f")") || same=0; done
    if [ "$same" = 1 ] && [ -n "$(ls "$tmp/a")" ]; then ok; else fail "$form" "the outputs differ from those of --opt value"; fi
done
expect "options after the deck" 0 "$deck" -q --steps 7
expect "long -D for --set" 0 -q -n 5 -D DAMPING.ALPHA=0.5 --set=GRAVITY.GY=-5 "$deck"
if grep -q -F -- '# run: options --steps 5 --set DAMPING.ALPHA=0.5 --set GRAVITY.GY=-5' "$out"/*_history.txt; then ok; else
    fail "-D in provenance" "the history does not record the two --set: $(grep '^# run: options' "$out"/*_history.txt)"; fi
expect "-V" 0 -V && { grep -q -E '^lpfdm [0-9]+\.[0-9]+\.[0-9]+$' "$tmp/stdout" && ok || fail "-V" "not 'lpfdm X.Y.Z': $(cat "$tmp/stdout")"; }
expect "--version" 0 --version
expect "-h" 0 -h && { grep -q -- '--strict' "$tmp/stdout" && grep -q 'deck cards' "$tmp/stdout" && ok || fail "-h" "no --strict or no deck cards in the help"; }

# --- decks/README.md shows the options of --help, as --help writes them ---
"$exe" --help | sed -n '/^options/,/^$/p' | sed '1d;$d' >"$tmp/help.txt"
sed -n '/^## Running a deck/,/^## /p' decks/README.md | sed -n '/^```$/,/^```$/p' | sed -n '/^  -/,/^```$/p' | sed '$d' >"$tmp/readme.txt"
if [ -s "$tmp/help.txt" ] && cmp -s "$tmp/help.txt" "$tmp/readme.txt"; then ok; else
    fail "README options" "decks/README.md's option list is not --help's: $(diff "$tmp/help.txt" "$tmp/readme.txt" | head -n 4 | tr '\n' '|')"; fi

# --- every mistake of the command line and of the deck in one run; nothing written ---
expect "all mistakes at once" 2 -q --steps 0 --kernel fats --threads=x --set NOPE tests/decks/bad_several.deck
for phrase in "--steps needs a whole number" "--kernel needs fast, scalar or reference, not 'fats' (did you mean fast?)" \
              "--threads needs a whole number" "--set needs CARD.PARAM=VALUE" "bad_several.deck:6:1: error: unknown card 'MATERAL'" \
              "bad_several.deck:13:11: error: number of steps"; do
    says "all mistakes at once" "$phrase"
done
n=$(grep -c 'error: ' "$err")
if [ "$n" -eq 9 ]; then ok; else fail "all mistakes at once" "$n errors, expected 4 of the options and 5 of the deck"; fi
if [ -z "$(ls "$out")" ]; then ok; else fail "all mistakes at once" "files written: $(ls "$out")"; fi
# the deck's messages in the order of the deck
if grep -o 'deck:[0-9]*:[0-9]*' "$err" | sort -t: -k2,2n -k3,3n -c 2>/dev/null; then ok; else fail "sorted" "the deck's messages are not in line order"; fi
expect "missing value" 2 -q "$deck" --steps && says "missing value" "--steps needs a value"
expect "flag with a value" 2 -q --quiet=1 "$deck" && says "flag with a value" "--quiet takes no value"
expect "unknown short option" 2 -q -Z "$deck" && says "unknown short option" "unknown option '-Z'"
expect "no deck" 2 -q && says "no deck" "no deck given"
expect "two decks" 2 -q "$deck" "$deck" && says "two decks" "one deck, please"
expect "--set of a card the deck lacks, with a deck error" 2 -q --set WALL9.VX=1 tests/decks/bad_several.deck && \
    says "--set of a card the deck lacks, with a deck error" "no WALL with id 9"

# --- a misspelt option: told once, with the option meant; its value is not read as a second
#     deck, and the deck is checked all the same ---
nothing_written() { if [ -z "$(ls "$out")" ]; then ok; else fail "$1" "files written: $(ls "$out")"; fi; }
errors() {  # errors NAME N: the last run printed N errors
    local n
    n=$(grep -c 'error: ' "$err")
    if [ "$n" -eq "$2" ]; then ok; else fail "$1" "$n errors, expected $2: $(tr '\n' '|' <"$err")"; fi
}
expect "misspelt option" 2 -q --stesp 10 tests/decks/bad_unknown_card.deck && {
    says "misspelt option" "lpfdm: error: unknown option '--stesp' (did you mean --steps?)"
    says "misspelt option" "tests/decks/bad_unknown_card.deck:6:1: error: unknown card 'FOO'"
    errors "misspelt option" 2
    nothing_written "misspelt option"
}
expect "misspelt option, good deck" 2 -q --stesp 10 "$deck" && { errors "misspelt option, good deck" 1; nothing_written "misspelt option, good deck"; }
expect "misspelt option, value apart from the deck" 2 -q "$deck" --stesp=10 && errors "misspelt option, value apart from the deck" 1
expect "misspelt option, no deck" 2 -q --stesp 10 && says "misspelt option, no deck" "no deck given"
expect "retired --no-avx512" 2 --no-avx512 "$deck" && says "retired --no-avx512" "--no-avx512 is retired"
# The summary line names the kernel that ran, and why when it is not the one asked for.
expect "summary names the kernel" 0 -n 3 --kernel scalar "$deck" &&
    { grep -q -E '; kernel scalar(;|$)' "$tmp/stdout" && ok || fail "summary names the kernel" "$(tail -n 1 "$tmp/stdout")"; }
# The summary line says whether the scene ended at rest (the unbalanced-force ratio below
# 1e-3: the damped column from step 1900 of 6000) or moving (the cliff collapsing).
expect "summary: at rest" 0 decks/column.deck &&
    { grep -q -F '; at rest: unbalanced-force ratio 1.17e-10, below 1e-3 since step 1900 (read every 100 steps)' "$tmp/stdout" && ok ||
        fail "summary: at rest" "$(tail -n 1 "$tmp/stdout")"; }
expect "summary: moving" 0 -n 300 decks/cliff.deck &&
    { grep -q -E '; moving: unbalanced-force ratio [0-9.e+-]+ at the end \(at rest below 1e-3\)$' "$tmp/stdout" && ok ||
        fail "summary: moving" "$(tail -n 1 "$tmp/stdout")"; }
expect "unknown option, value and deck" 2 -q --frobnicate 3 "$deck" && { says "unknown option, value and deck" "unknown option '--frobnicate'"; errors "unknown option, value and deck" 1; }

# --- a long option is written in full: a beginning of one (--thread) is refused, with the option meant ---
for form in "--thread 2" "--thread=2" "--thr 2" "--ker scalar"; do
    name=${form%%[ =]*}
    # shellcheck disable=SC2086
    expect "$form" 2 -q -n 2 $form "$deck" || continue
    full=$(case $name in --thr*) echo --threads ;; *) echo --kernel ;; esac)
    says "$form" "lpfdm: error: unknown option '$name' (did you mean $full? options are written in full)"
    errors "$form" 1
    nothing_written "$form"
done
expect "--qui=1" 2 -q "$deck" --qui=1 && says "--qui=1" "unknown option '--qui' (did you mean --quiet? options are written in full)"
expect "--thread, last" 2 -q "$deck" --thread && says "--thread, last" "unknown option '--thread' (did you mean --threads? options are written in full)"

# --- the deck's messages: a misspelt card alone (not also the card it leaves missing), a
#     cluster past an edge of the lattice, a motion file by the path tried ---
printf 'GRID 4 4 1\nMATERIAL 1 ELASTIC E=5E7 NU=0.3 RHO=2000\nCLUSTR 1 0 0 2 2\nSTEP 1E-4 10\n' >"$tmp/clustr.deck"
expect "misspelt card" 2 -q "$tmp/clustr.deck" && {
    says "misspelt card" "clustr.deck:3:1: error: unknown card 'CLUSTR' (did you mean CLUSTER?)"
    errors "misspelt card" 1
}
# a --set of the card it misspells is that card's error, not one of its own
expect "misspelt card, --set" 2 -q --set CLUSTER1.PPC=4 "$tmp/clustr.deck" && {
    says "misspelt card, --set" "clustr.deck:3:1: error: unknown card 'CLUSTR' (did you mean CLUSTER?)"
    errors "misspelt card, --set" 1
}
expect "--set of a card not there" 2 -q --set CLUSTER2.PPC=4 decks/column.deck && says "--set of a card not there" "--set CLUSTER2.PPC: there is no CLUSTER number 2"
expect "cluster outside" 2 -q tests/decks/bad_cluster_outside.deck && \
    says "cluster outside" "bad_cluster_outside.deck:5:1: error: the cluster box reaches outside the lattice: x1 = 6 m is past its right edge x = 4 m (the lattice is [0, 4] x [0, 4] m)"
mkdir -p "$tmp/quake"
printf 'GRID 4 4 1\nMATERIAL 1 ELASTIC E=5E7 NU=0.3 RHO=2000\nCLUSTER 1 0 0 2 2\nFIX XY 0 0 4 0\nSHAKE X FILE=motion.txt\nSTEP 1E-4 10\n' >"$tmp/quake/shake.deck"
expect "missing motion file" 2 -q "$tmp/quake/shake.deck" && \
    says "missing motion file" "shake.deck:5:14: error: cannot open the motion file '$tmp/quake/motion.txt': No such file or directory (a relative FILE= is read from the deck's directory)"

# --- warnings: to stderr, exit status 0, the run made; --strict: errors, exit 2, nothing written ---
expect "cliff --steps 100" 0 -q --steps 100 decks/cliff.deck && says "cliff --steps 100" "decks/cliff.deck:23:1: warning: EVERY 500 is more than the 100 steps"
rows=$(sed 1d "$out/cliff_history.txt" | grep -v '^#' | grep -c .)  # (line 1: the column names)
if [ "$rows" -eq 1 ] && grep -v '^#' "$out/cliff_history.txt" | grep -q '^100 '; then ok; else fail "cliff --steps 100" "$rows history rows, expected the one of step 100"; fi
expect "cliff --steps 100 --strict" 2 -q --strict --steps 100 decks/cliff.deck && says "cliff --steps 100 --strict" "decks/cliff.deck:23:1: error: EVERY 500"
if [ -z "$(ls "$out")" ]; then ok; else fail "--strict" "files written: $(ls "$out")"; fi
printf 'GRID 4 4 1\nMATERIAL 1 MOHR E=500 NU=0.3 RHO=2 PHI=0.5 C=10\nCLUSTER 1 0 0 2 2\nSTEP 1E-4 10\n' >"$tmp/units.deck"
expect "wrong units" 0 -q "$tmp/units.deck"
n=$(grep -c ': warning: ' "$err")
if [ "$n" -eq 3 ]; then ok; else fail "wrong units" "$n warnings, expected 3 (PHI, E, RHO): $(tr '\n' '|' <"$err")"; fi
expect "a deck without a warning is silent" 0 -q "$deck"
if [ ! -s "$err" ]; then ok; else fail "silent" "stderr: $(head -n 1 "$err")"; fi

# --- provenance: each output file's '# run:' lines follow its names line; the digest is FNV-1a 64 ---
fnv() {  # FNV-1a 64 of a file, in bash's 64-bit arithmetic
    local h=-3750763034362895579 b  # 0xcbf29ce484222325
    for b in $(od -An -v -tu1 "$1"); do h=$(( (h ^ b) * 1099511628211 )); done
    printf '%016x\n' "$h"
}
expect "provenance" 0 -q --threads 2 --refine 2 --steps 6 --seed 9 --set DAMPING.ALPHA=0.7 tests/decks/good_every_card.deck
digest=$(fnv tests/decks/good_every_card.deck)
version=$("$exe" --version | sed 's/^lpfdm //')
files=$(cd "$out" && ls -- *.txt)  # the tables; not the VTK files and the restart file
[ -n "$files" ] || fail "provenance" "no output"
for f in $files; do
    sed -n 2,6p "$out/$f" >"$tmp/head"
    want=$(printf '%s\n' "# run: lpfdm $version" "# run: deck tests/decks/good_every_card.deck (fnv1a64 $digest)" \
        "# run: options --steps 6 --refine 2 --seed 9 --set DAMPING.ALPHA=0.7" "# run: seed 9 steps 6" "# run: threads 2 kernel ")
    ok_all=1
    while IFS= read -r w; do grep -q -F -- "$w" "$tmp/head" || ok_all=0; done <<<"$want"
    if [ "$ok_all" = 1 ]; then ok; else fail "provenance of $f" "its first lines are not the run's: $(tr '\n' '|' <"$tmp/head")"; fi
done

echo "cli: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
