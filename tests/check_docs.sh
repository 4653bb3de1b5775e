#!/usr/bin/env bash
# The documentation test: every shell command that README.md, decks/README.md,
# tests/README.md and tools/README.md show in a ```sh block is run, as a reader would
# type it, from the top of a temporary copy of the project in which ./lpfdm is the
# program under test. A block fails when it exits non-zero or prints an error; each
# block is one test.
#
# What a document says about a block, on the line just before its opening fence (HTML
# comments, not shown when the page is read):
#   <!-- docs-test: steps=N -->          every lpfdm the block runs (also through make and
#                                        tools/ensemble) stops after N steps: for long runs
#   <!-- docs-test: skip REASON -->      the block is not run; listed here with REASON
#   <!-- docs-test: not "PREFIX" REASON -->  the block's lines that begin with PREFIX are not
#                                        run; listed with REASON (several may stand together)
#   <!-- docs-test: copy-of DECK -->     (before an unlabelled block) the block is that deck
#                                        with its comment cards shortened: every other line
#                                        of each must be the other's, in the same order
# Only ```sh blocks are commands; ```cpp, ```cmake, ```python and unlabelled blocks are
# not run here (the embedding example and the CMake recipes have their own checks:
# check_embed.sh, check_cmake.sh).
#
# usage: tests/check_docs.sh EXE   (runs once, for the plain build of the program)
# DOCS_ONLY=FILE runs one document's blocks. One line per failure, the blocks not run
# with their reasons, and last "docs: N passed, M failed".
set -u
. "$(dirname "$0")/lib.sh"
plain_build_only docs "${1:-}"
need_program docs "$@"
cd "$(dirname "$0")/.." || exit 2

docs=${DOCS_ONLY:-README.md decks/README.md tests/README.md tools/README.md}
limit=${DOCS_BLOCK_SECONDS:-300}  # seconds per block
passed=0 failed=0
fail() { echo "FAIL docs $1"; failed=$((failed + 1)); }

tmp=$(mktemp -d) || exit 2
trap 'rm -rf "$tmp"' EXIT
# The copy: the project's own files as a checkout has them (no build directory, no
# outputs), ./lpfdm the program under test, newer than its sources so that make takes it
# as built.
copy=$tmp/lpfdm
mkdir -p "$copy"
tar -cf - Makefile CMakeLists.txt lpfdm.cpp lpfdm.hpp README.md LICENSE decks tests tools | tar -xf - -C "$copy" || exit 2
cat >"$copy/lpfdm" <<EOF
#!/bin/sh
# The program under test; DOCS_STEPS shortens the run (a later --steps still wins).
exec "$exe" \${DOCS_STEPS:+--steps "\$DOCS_STEPS"} "\$@"
EOF
chmod +x "$copy/lpfdm"
touch -d '-1 hour' "$copy/lpfdm.cpp" "$copy/lpfdm.hpp"

# blocks FILE: writes $tmp/blocks/K.sh for each ```sh block of FILE, with K.meta holding
# its line, steps and reason to skip (separated by the unit separator, \037, so that an
# empty field stays a field) and K.not the "PREFIX<TAB>REASON" lines.
blocks() {
    rm -rf "$tmp/blocks" && mkdir -p "$tmp/blocks"
    awk -v dir="$tmp/blocks" '
        function reset() { steps = ""; skip = ""; nnot = 0 }
        BEGIN { reset() }
        inblock && /^ *```/ { inblock = 0; close(out); reset(); next }
        inblock { sub("^" indent, ""); print > out; next }
        /^ *<!-- *docs-test:/ {
            s = $0; sub(/^ *<!-- *docs-test: */, "", s); sub(/ *--> *$/, "", s)
            if (s ~ /^steps=[0-9]+$/) steps = substr(s, 7)
            else if (s ~ /^skip /) skip = substr(s, 6)
            else if (s ~ /^copy-of /) { }  # (checked by copies)
            else if (s ~ /^not "[^"]+" /) { p = s; sub(/^not "/, "", p); r = p; sub(/".*/, "", p); sub(/^[^"]*" */, "", r)
                                           nots[++nnot] = p "\t" r }
            else { printf "%s:%d: unknown docs-test marker: %s\n", FILENAME, NR, s > "/dev/stderr"; bad = 1 }
            next
        }
        /^ *```sh *$/ {
            k = sprintf("%03d", ++nk); out = dir "/" k ".sh"; indent = $0; sub(/```.*/, "", indent)
            printf "%d\037%s\037%s\n", NR, steps, skip > (dir "/" k ".meta"); close(dir "/" k ".meta")
            printf "" > (dir "/" k ".not")
            for (i = 1; i <= nnot; i++) print nots[i] > (dir "/" k ".not")
            close(dir "/" k ".not"); printf "" > out
            inblock = 1; next
        }
        /^ *$/ { next }
        { reset() }
        END { exit bad }' "$1"
}

# copies DOC: each block marked copy-of DECK must hold the deck's cards as they are.
copies() {
    local deck where lines
    while IFS=$'\t' read -r deck where lines; do
        if [ ! -f "$deck" ]; then fail "$where: copy-of $deck: no such deck"; continue; fi
        if [ "$(grep -v '^\*' "$deck")" = "$(printf '%s' "$lines" | tr '\037' '\n')" ]; then
            passed=$((passed + 1)); echo "ok $where (the cards of $deck)"
        else
            fail "$where: the copy of $deck is not its cards:"
            diff <(grep -v '^\*' "$deck") <(printf '%s' "$lines" | tr '\037' '\n') | sed 's/^/  | /' | head -n 8
        fi
    done < <(awk '
        /^ *<!-- *docs-test: *copy-of / { d = $0; sub(/^ *<!-- *docs-test: *copy-of */, "", d); sub(/ *--> *$/, "", d); want = d; next }
        want != "" && /^ *```/ && !inblock { inblock = 1; deck = want; want = ""; n = 0; lines = ""; next }
        inblock && /^ *```/ { inblock = 0; sub(/\x1f$/, "", lines); print deck "\t" FILENAME ":" start "\t" lines; next }
        inblock { if (!n++) start = NR; if ($0 !~ /^\*/) lines = lines $0 "\x1f"; next }
        !/^ *$/ { want = "" }' "$1")
}

# What an error looks like in a block's output: GNU style "error:" (lpfdm, the compilers,
# tools/ensemble), make's "***", a Python traceback; not a column or a word named error.
errors='error:|\*\*\*|^Traceback'
notrun=()
for doc in $docs; do
    [ -f "$doc" ] && copies "$doc"
    [ -f "$doc" ] || { fail "$doc: no such document"; continue; }
    blocks "$doc" || fail "$doc: a docs-test marker is not understood"
    for meta in "$tmp"/blocks/*.meta; do
        [ -e "$meta" ] || continue
        k=${meta%.meta}
        IFS=$'\037' read -r line steps skip <"$meta"
        where="$doc:$line"
        if [ -n "$skip" ]; then
            notrun+=("$where (whole block): $skip")
            continue
        fi
        # The lines the block keeps: a line (with its continuations) that begins with a
        # listed prefix is left out and listed.
        script=$k.run
        awk -v nots="$k.not" -v where="$where" -v list="$k.list" '
            BEGIN { while ((getline l < nots) > 0) { n++; split(l, a, "\t"); pre[n] = a[1]; why[n] = a[2] } }
            {
                if (!cont) { drop = 0; for (i = 1; i <= n; i++) if (index($0, pre[i]) == 1) { drop = 1; used[i] = 1; printf "%s: %s: %s\n", where, pre[i], why[i] > list } }
                cont = /\\$/
                if (!drop) print
            }
            END { for (i = 1; i <= n; i++) if (!used[i]) printf "%s\n", pre[i] > (list ".unused") }' "$k.sh" >"$script"
        if [ -s "$k.list.unused" ]; then  # a marker that leaves out nothing: the line it meant now runs, or is gone
            fail "$where: no line of the block begins with $(sed 's/.*/"&"/' "$k.list.unused" | paste -sd ' ')"
        fi
        [ -s "$k.list" ] && while IFS= read -r l; do notrun+=("$l"); done <"$k.list"
        if ! grep -qv '^[[:space:]]*\(#.*\)\{0,1\}$' "$script"; then
            [ -s "$k.list" ] || notrun+=("$where (whole block): it holds no command")
            continue  # every line of it listed as not run
        fi
        start=$SECONDS
        (cd "$copy" && DOCS_STEPS=$steps timeout -k 10 "$limit" bash -e -o pipefail "$script") >"$tmp/log" 2>&1 </dev/null
        rc=$?
        took=$((SECONDS - start))
        if [ $rc -ne 0 ]; then
            fail "$where: exit status $rc after $took s${steps:+ (steps=$steps)}:"
            sed 's/^/    /' "$script"
            tail -n 8 "$tmp/log" | sed 's/^/  | /'
        elif grep -Eiq "$errors" "$tmp/log"; then
            fail "$where: printed an error${steps:+ (steps=$steps)}:"
            sed 's/^/    /' "$script"
            grep -Ei -m 3 "$errors" "$tmp/log" | sed 's/^/  | /'
        else
            passed=$((passed + 1))
            echo "ok $where ($took s${steps:+, steps=$steps})"
        fi
    done
done
if [ ${#notrun[@]} -gt 0 ]; then
    echo "docs: shown but not run here:"
    printf '  %s\n' "${notrun[@]}"
fi
echo "docs: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
