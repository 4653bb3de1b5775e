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
files=$(ls "$out")
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
