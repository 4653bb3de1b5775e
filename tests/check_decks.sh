#!/usr/bin/env bash
# Deck-level checks of the program (a bad deck stops before the first step
# with "deckfile:line:column: error: message", a non-zero exit status and no output).
#
# usage: tests/check_decks.sh EXE
#
# Every tests/decks/*.deck is run as  EXE -q -o DIR tests/decks/NAME.deck  in a fresh,
# empty DIR. The first line of a deck says what must happen:
#   * expect: ok                   exit status 0
#   * expect: LINE:COL: PHRASE     exit status 2; the first line of stderr is
#                                  "tests/decks/NAME.deck:LINE:COL: error: ...PHRASE...",
#                                  every line of stderr is such an error or a warning,
#                                  and DIR is still empty (nothing half-run)
#   * expect: warning LINE:COL: PHRASE
#                                  exit status 0, the first line of stderr is
#                                  "...:LINE:COL: warning: ...PHRASE..."; with --strict
#                                  exit status 2, the same line as an error, DIR empty
# and "* errors: N" among the first comment cards gives the number of error messages
# (one without it): every error of a deck is reported in one run, none twice. Then a missing deck, a directory, an empty file, a binary file and unreadable
# files, made here at run time, must each give exit status 2 and a one-line error.
# Nothing may crash (exit status >= 128, a sanitizer report, an abort) or take longer
# than the time limit. One line per failure, and last "decks: N passed, M failed".
set -u

. "$(dirname "$0")/lib.sh"
need_program decks "$@"
cd "$(dirname "$0")/.." || exit 2

limit=20  # seconds per run
tmp=$(mktemp -d) || exit 2
trap 'chmod -R u+rwx "$tmp" 2>/dev/null; rm -rf "$tmp"' EXIT
passed=0 failed=0
fail() { echo "FAIL $1: $2"; failed=$((failed + 1)); }

# run NAME DECK [OPTION...]: runs the program on DECK into a new empty directory $out;
# sets $rc; stderr is in $tmp/stderr. Returns 1 (and counts a failure) on a crash or a hang.
run() {
    local name=$1 deck=$2
    shift 2
    out="$tmp/out.$name"
    rm -rf "$out" && mkdir -p "$out"
    # (the group's own stderr is silenced: bash would report a killed program there)
    { timeout -k 5 "$limit" "$exe" -q -o "$out" "$@" "$deck" >"$tmp/stdout" 2>"$tmp/stderr" </dev/null; rc=$?; } 2>/dev/null
    if [ $rc -eq 124 ] || [ $rc -eq 137 ]; then
        fail "$name" "no result within $limit s (a hang?)"
        return 1
    fi
    if [ $rc -ge 128 ]; then
        fail "$name" "crashed with exit status $rc: $(head -n 1 "$tmp/stderr")"
        return 1
    fi
    local report
    report=$(grep -m 1 -E 'runtime error:|AddressSanitizer|LeakSanitizer|ThreadSanitizer|terminate called|Assertion .* failed' "$tmp/stderr")
    if [ -n "$report" ]; then
        fail "$name" "sanitizer report or abort (exit status $rc): $report"
        return 1
    fi
    return 0
}

# no_output NAME: the output directory must hold no file at all.
no_output() {
    local files
    files=$(cd "$out" && find . -mindepth 1 2>/dev/null | sed 's|^\./||' | tr '\n' ' ')
    if [ -n "$files" ]; then
        fail "$1" "files were written although the deck is bad: $files"
        return 1
    fi
    return 0
}

shopt -s nullglob
decks=(tests/decks/*.deck)
if [ ${#decks[@]} -eq 0 ]; then
    fail "tests/decks" "no deck found"
fi

for deck in "${decks[@]}"; do
    name=$(basename "$deck" .deck)
    expect=$(head -n 1 "$deck" | tr -d '\r')
    errors=$(head -n 5 "$deck" | tr -d '\r' | sed -n -E 's/^\* errors: ([0-9]+)$/\1/p' | head -n 1)
    if [ "$expect" = "* expect: ok" ]; then
        run "$name" "$deck" || continue
        if [ $rc -ne 0 ]; then
            fail "$name" "exit status $rc, expected 0: $(head -n 1 "$tmp/stderr")"
            continue
        fi
        passed=$((passed + 1))
        continue
    fi
    if [[ $expect =~ ^\*\ expect:\ warning\ ([0-9]+):([0-9]+):\ (.+)$ ]]; then
        line=${BASH_REMATCH[1]} col=${BASH_REMATCH[2]} phrase=${BASH_REMATCH[3]}
        run "$name" "$deck" || continue
        first=$(head -n 1 "$tmp/stderr")
        if [ $rc -ne 0 ]; then
            fail "$name" "exit status $rc, expected 0 with a warning (stderr: $first)"
        elif [[ $first != "$deck:$line:$col: warning: "*"$phrase"* ]]; then
            fail "$name" "first message '$first' is not '$deck:$line:$col: warning: ...$phrase...'"
        elif [ -z "$(ls "$out")" ]; then
            fail "$name" "a deck with a warning runs, but no output was written"
        else
            passed=$((passed + 1))
        fi
        run "$name --strict" "$deck" --strict || continue
        first=$(head -n 1 "$tmp/stderr")
        if [ $rc -ne 2 ]; then
            fail "$name --strict" "exit status $rc, expected 2 (stderr: $first)"
        elif [[ $first != "$deck:$line:$col: error: "*"$phrase"* ]]; then
            fail "$name --strict" "first message '$first' is not '$deck:$line:$col: error: ...$phrase...'"
        elif no_output "$name --strict"; then
            passed=$((passed + 1))
        fi
        continue
    fi
    if ! [[ $expect =~ ^\*\ expect:\ ([0-9]+):([0-9]+):\ (.+)$ ]]; then
        fail "$name" "the first line is not '* expect: ok', '* expect: LINE:COL: PHRASE' or '* expect: warning LINE:COL: PHRASE'"
        continue
    fi
    line=${BASH_REMATCH[1]} col=${BASH_REMATCH[2]} phrase=${BASH_REMATCH[3]}
    run "$name" "$deck" || continue
    first=$(head -n 1 "$tmp/stderr")
    prefix="$deck:$line:$col: error: "
    gnu="^$(printf '%s' "$deck" | sed 's/[.[\*^$]/\\&/g'):[0-9]+:[0-9]+: (error|warning): ."
    if [ $rc -ne 2 ]; then
        fail "$name" "exit status $rc, expected 2 (stderr: $first)"
    elif [ "${first#"$prefix"}" = "$first" ]; then
        fail "$name" "first message '$first' is not at '$deck:$line:$col: error: '"
    elif [[ $first != *"$phrase"* ]]; then
        fail "$name" "first message '$first' does not say '$phrase'"
    elif grep -v -q -E "$gnu" "$tmp/stderr"; then
        fail "$name" "a line of stderr is not a '$deck:LINE:COL: error|warning: message': $(grep -v -m 1 -E "$gnu" "$tmp/stderr")"
    elif [ "$(grep -c ': error: ' "$tmp/stderr")" -ne "${errors:-1}" ]; then
        fail "$name" "$(grep -c ': error: ' "$tmp/stderr") errors, expected ${errors:-1} (every problem, one message each): $(tr '\n' '|' <"$tmp/stderr")"
    elif no_output "$name"; then
        passed=$((passed + 1))
    fi
done

# Files that are no deck at all: exit status 2, exactly one line "FILE[:LINE:COL]: error: ..."
# that says PHRASE.
# check_not_a_deck NAME PATH PHRASE
check_not_a_deck() {
    run "$1" "$2" || return
    local lines first
    lines=$(grep -c '' "$tmp/stderr")
    first=$(head -n 1 "$tmp/stderr")
    if [ $rc -ne 2 ]; then
        fail "$1" "exit status $rc, expected 2 (stderr: $first)"
    elif [ "$lines" -ne 1 ]; then
        fail "$1" "$lines lines on stderr, expected one error line"
    elif [ "${first#"$2"}" = "$first" ] || ! [[ ${first#"$2"} =~ ^(:[0-9]+:[0-9]+)?:\ error:\ .+ ]]; then
        fail "$1" "'$first' is not '$2[:LINE:COL]: error: message'"
    elif [[ $first != *"$3"* ]]; then
        fail "$1" "'$first' does not say '$3'"
    elif no_output "$1"; then
        passed=$((passed + 1))
    fi
}

check_not_a_deck "missing file" "$tmp/no-such-file.deck" "cannot open the deck"
mkdir "$tmp/a-directory.deck"
check_not_a_deck "directory as the deck" "$tmp/a-directory.deck" "directory"
: >"$tmp/empty.deck"
check_not_a_deck "empty file" "$tmp/empty.deck" "the deck is empty"
head -c 4096 "$exe" >"$tmp/binary.deck"
check_not_a_deck "binary file" "$tmp/binary.deck" "binary data"
printf 'GRID 4 4 1\nMATERIAL 1 ELASTIC E=5E7 NU=0.3 RHO=2000\n\0\0\0\0CLUSTER 1 0 0 2 2\nSTEP 1E-4 10\n' >"$tmp/nul-bytes.deck"
check_not_a_deck "deck with NUL bytes" "$tmp/nul-bytes.deck" "binary data (byte 0x00)"
cp tests/decks/good_every_card.deck "$tmp/unreadable.deck"
chmod 000 "$tmp/unreadable.deck"
if [ ! -r "$tmp/unreadable.deck" ]; then  # (the superuser reads it anyway)
    check_not_a_deck "unreadable file" "$tmp/unreadable.deck" "cannot open the deck"
fi
if [ -e /proc/self/mem ]; then  # opens, but reading it fails
    check_not_a_deck "file whose reading fails" /proc/self/mem "cannot read the deck"
fi
check_not_a_deck "endless device" /dev/zero "not a regular file"
head -c $((65 * 1024 * 1024)) /dev/zero | tr '\0' ' ' >"$tmp/huge.deck"
check_not_a_deck "deck over 64 MiB" "$tmp/huge.deck" "larger than 64 MiB"
rm -f "$tmp/huge.deck"

# Motion files (SHAKE ... FILE=): missing, empty, not numbers, a line of three numbers,
# times that go back. Exit status 2, nothing written, and the first line of stderr at the
# motion file's own line and column (a missing file: at the card's FILE= value).
# motion_case NAME CONTENT|- WHERE PHRASE
motion_case() {
    local name=$1 content=$2 where=$3 phrase=$4 deck="$tmp/quake/$1.deck"
    mkdir -p "$tmp/quake"
    [ "$content" = - ] || printf '%b' "$content" >"$tmp/quake/$name.txt"
    printf 'GRID 4 4 1\nMATERIAL 1 ELASTIC E=5E7 NU=0.3 RHO=2000\nCLUSTER 1 0 0 4 2\nFIX XY 0 0 4 0\nSHAKE X FILE=%s.txt\nSTEP 1E-4 10\nOUTPUT HISTORY h.txt\n' "$name" >"$deck"
    run "motion file: $name" "$deck" || return
    local first
    first=$(head -n 1 "$tmp/stderr")
    if [ $rc -ne 2 ]; then
        fail "motion file: $name" "exit status $rc, expected 2 (stderr: $first)"
    elif [[ $first != "$where: error: "*"$phrase"* ]]; then
        fail "motion file: $name" "first message '$first' is not '$where: error: ...$phrase...'"
    elif no_output "motion file: $name"; then
        passed=$((passed + 1))
    fi
}
motion_case missing - "$tmp/quake/missing.deck:5:14" "cannot open the motion file"
motion_case empty "" "$tmp/quake/empty.txt:1:1" "holds no samples"
motion_case comments "# time acceleration\n\n" "$tmp/quake/comments.txt:1:1" "holds no samples"
motion_case words "0 0\n0.1 zero\n" "$tmp/quake/words.txt:2:5" "expected a finite number, found 'zero'"
motion_case three "0 0\n0.1 1 2\n" "$tmp/quake/three.txt:2:7" "expected two numbers"
motion_case backwards "0 0\n0.2 1\n0.1 0\n" "$tmp/quake/backwards.txt:3:1" "times must increase"
motion_case binary "0 0\n0.1 \0\0\0\n" "$tmp/quake/binary.txt:2:5" "binary data (byte 0x00)"

# The command line: --opt=value reads as --opt value; --kernel reference writes what the
# fast kernel writes (two threads); a mistaken option or key is named with a suggestion.
# cli NAME EXPECTED_STATUS PHRASE ARGS...: runs EXE -q ARGS into a new directory $out.
cli() {
    local name=$1 want=$2 phrase=$3
    shift 3
    out="$tmp/out.$name"
    rm -rf "$out" && mkdir -p "$out"
    { timeout -k 5 "$limit" "$exe" -q -o "$out" "$@" >"$tmp/stdout" 2>"$tmp/stderr" </dev/null; rc=$?; } 2>/dev/null
    if [ $rc -ne "$want" ]; then
        fail "$name" "exit status $rc, expected $want ($(head -n 1 "$tmp/stderr"))"
    elif [ -n "$phrase" ] && ! grep -q -F -- "$phrase" "$tmp/stderr"; then
        fail "$name" "stderr does not say '$phrase': $(head -n 1 "$tmp/stderr")"
    else
        passed=$((passed + 1))
    fi
}
cli "kernel reference" 0 "" --kernel reference --steps 40 tests/decks/threads_outflow.deck
cp -r "$out" "$tmp/ref"
cli "kernel=fast, steps=40, threads=2" 0 "" --kernel=fast --steps=40 --threads=2 tests/decks/threads_outflow.deck
# (the provenance lines "# run: ..." name the threads and the kernel: they are skipped)
same_run() {
    local f
    [ "$(cd "$1" && ls)" = "$(cd "$2" && ls)" ] || return 1
    for f in "$1"/*; do
        cmp -s <(grep -v '^# run: ' "$f") <(grep -v '^# run: ' "$2/$(basename "$f")") || return 1
    done
}
if [ -s "$tmp/ref/threads_outflow_points.txt" ] && same_run "$tmp/ref" "$out"; then
    passed=$((passed + 1))
else
    fail "reference = fast" "the outputs of --kernel reference and --kernel=fast --threads=2 differ"
fi
cli "unknown kernel" 2 "--kernel needs fast, scalar or reference" --kernel nope decks/column.deck
cli "misspelt option" 2 "(did you mean --threads?)" --threds 2 decks/column.deck
cli "misspelt --set key" 2 "(did you mean SOFTEN?)" --set MATERIAL1.SOFTN=0.5 decks/psc.deck
cli "--set key of another model" 2 "MATERIAL 1 is ELASTIC: PHI is not one of its parameters" --set MATERIAL1.PHI=30 decks/column.deck
cli "--set out of range" 2 "NU must lie in (-1, 0.5)" --set=MATERIAL1.NU=0.5 decks/column.deck

echo "decks: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
