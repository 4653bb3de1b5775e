#!/usr/bin/env bash
# Every stable limit a deck's comments quote is the program's: for each deck of decks/
# whose comments ("* ..." lines and the text after "!") say "stable limit ... NUMBER s"
# (no comma or semicolon between the words and the number: "0.4 of the stable limit, a
# margin" quotes nothing), the number must be the limit the program computes, rounded to
# the digits the comment prints. The program gives its limit when refused a step far too
# large: "time step 1000 s is above the stable limit X s" (--set STEP.DT=1E3 --steps 1,
# which stops before the first step and writes nothing). The same for the pore water's
# limit, which a comment quotes as "the flow's NUMBER s" (or "the flow's stable limit
# NUMBER s"): "time step 1000 s is above the pore water's stable limit X s".
#
# usage: tests/check_limits.sh EXE   (runs once, for the plain build of the program)
#
# One line per failure, and last "limits: N passed, M failed".
set -u

. "$(dirname "$0")/lib.sh"
plain_build_only limits "${1:-}"
need_program limits "$@"
cd "$(dirname "$0")/.." || exit 2

tmp=$(mktemp -d) || exit 2
trap 'rm -rf "$tmp"' EXIT
passed=0 failed=0
fail() { echo "FAIL $1: $2"; failed=$((failed + 1)); }
ok() { passed=$((passed + 1)); }

# quotes DECK [PHRASE]: one quoted limit a line, as the comment prints it, after PHRASE
# ("stable limit" by default; "the flow's" for the pore water's).
quotes() {
    awk -v phrase="${2:-stable limit}" '/^[ \t]*\*/ {sub(/^[ \t]*\*/, ""); t = t " " $0; next}
         index($0, "!") {t = t " " substr($0, index($0, "!") + 1)}
         END {
             n = "[0-9]+(\\.[0-9]*)?([eE][-+]?[0-9]+)?"
             while ((i = index(tolower(t), phrase)) > 0) {
                 t = substr(t, i + length(phrase))
                 if (phrase != "stable limit") sub(/^ *stable limit/, "", t)
                 if (!match(t, n " s([^A-Za-z0-9]|$)")) break
                 if (substr(t, 1, RSTART - 1) ~ /[,;]/) continue
                 q = substr(t, RSTART, RLENGTH); sub(/ s.*/, "", q); print q
             }
         }' "$1"
}

# same Q P: whether P rounded to the significant digits of Q (as printed) is Q.
same() {
    awk -v q="$1" -v p="$2" 'BEGIN {
        m = q; sub(/[eE].*/, "", m); gsub(/\./, "", m); sub(/^0+/, "", m)
        d = length(m); if (d < 1) d = 1
        e = int(log(q) / log(10) + 1e-9); if (10 ^ e > q * (1 + 1e-12)) e--
        tol = 0.5 * 10 ^ (e - d + 1)
        exit !((p - q <= tol * (1 + 1e-9)) && (q - p <= tol * (1 + 1e-9)))
    }'
}

decks=0 flows=0
for deck in decks/*.deck; do
    name=$(basename "$deck")
    quotes "$deck" >"$tmp/q"
    quotes "$deck" "the flow's" >"$tmp/qf"
    [ -s "$tmp/q" ] || [ -s "$tmp/qf" ] || continue
    [ -s "$tmp/q" ] && decks=$((decks + 1))
    [ -s "$tmp/qf" ] && flows=$((flows + 1))
    timeout 20 "$exe" -q -n 1 --set STEP.DT=1E3 -o "$tmp/out" "$deck" >"$tmp/msg" 2>&1
    for kind in mechanical water; do
        if [ $kind = mechanical ]; then q_file=$tmp/q what="stable limit"
        else q_file=$tmp/qf what="pore water's stable limit"; fi
        [ -s "$q_file" ] || continue
        limit=$(sed -n "s/.*is above the $what \\([0-9.eE+-]*\\) s.*/\\1/p" "$tmp/msg" | head -n 1)
        if [ -z "$limit" ]; then
            fail "$name" "the program gave no $what for a step of 1000 s: $(head -c 300 "$tmp/msg" | tr '\n' '|')"
            continue
        fi
        while read -r q; do
            if same "$q" "$limit"; then ok; else
                fail "$name" "the comment quotes a $what of $q s; the program's is $limit s"
            fi
        done <"$q_file"
    done
done
# the pore water's limit: consolidation.deck quotes it
[ "$flows" -ge 1 ] && ok || fail "decks" "no deck quotes the flow's stable limit (consolidation.deck did)"
# the decks of the ladder that quote a limit (a deck quoting none is not checked)
[ "$decks" -ge 10 ] && ok || fail "decks" "only $decks decks quote a stable limit the check could read"

echo "limits: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
