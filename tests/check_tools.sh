#!/usr/bin/env bash
# The gnuplot scripts of tools/ on output of the program: snapshot.gp colours by any
# column named on the command line (or refuses a name the table lacks), puts its key in
# the emptiest corner; history.gp labels each axis with its column's unit.
#
# usage: tests/check_tools.sh EXE
#
# One line per failure, and last "tools: N passed, M failed".
set -u

. "$(dirname "$0")/lib.sh"
need_program tools "$@"
cd "$(dirname "$0")/.." || exit 2

tmp=$(mktemp -d) || exit 2
trap 'rm -rf "$tmp"' EXIT
passed=0 failed=0
fail() { echo "FAIL $1: $2"; failed=$((failed + 1)); }
ok() { passed=$((passed + 1)); }
if ! command -v gnuplot >/dev/null; then
    fail "gnuplot" "not installed (make deps installs it)"
    echo "tools: $passed passed, $failed failed"
    exit 1
fi
timeout 120 "$exe" -q -n 300 -o "$tmp" decks/cliff.deck 2>/dev/null
points=$tmp/cliff_points.txt history=$tmp/cliff_history.txt
[ -s "$points" ] && [ -s "$history" ] || fail "cliff" "the run wrote no tables"

# gp NAME SCRIPT SETTINGS [AFTER]: runs gnuplot; sets $rc, its messages in $tmp/gp.
gp() { timeout 60 gnuplot -e "$3" "$2" ${4:+-e "$4"} >"$tmp/gp" 2>&1; rc=$?; }

for color in "'syy'" 4 "'ep'" "'yielded'"; do
    rm -f "$tmp/s.png"
    gp "color=$color" tools/snapshot.gp "in='$points'; out='$tmp/s.png'; color=$color" "print 'colour:', ccol, clabel, ' key:', keypos"
    if [ $rc -eq 0 ] && [ -s "$tmp/s.png" ]; then ok; else fail "snapshot color=$color" "exit $rc: $(tr '\n' '|' <"$tmp/gp")"; fi
done
gp "syy" tools/snapshot.gp "in='$points'; out='$tmp/s.png'; color='syy'" "print 'colour:', ccol, clabel"
if grep -q 'colour: 4 stress.*\[Pa\]' "$tmp/gp"; then ok; else fail "snapshot color='syy'" "not column 4 in Pa: $(tr '\n' '|' <"$tmp/gp")"; fi
gp "nope" tools/snapshot.gp "in='$points'; out='$tmp/n.png'; color='nope'"
if [ $rc -ne 0 ] && grep -q "no column 'nope'" "$tmp/gp"; then ok; else fail "snapshot color='nope'" "exit $rc: $(tr '\n' '|' <"$tmp/gp")"; fi
gp "0" tools/snapshot.gp "in='$points'; out='$tmp/n.png'; color=0"
if [ $rc -ne 0 ]; then ok; else fail "snapshot color=0" "accepted a column 0"; fi
# the cliff falls to the right: its last frame leaves the top right corner empty
gp "key" tools/snapshot.gp "in='$points'; out='$tmp/s.png'" "print 'key:', keypos"
if grep -q 'key: top right' "$tmp/gp"; then ok; else fail "snapshot key" "not in the empty top right corner: $(tr '\n' '|' <"$tmp/gp")"; fi

# history.gp: each axis label carries the unit of its column
while read -r col unit; do
    gp "$col" tools/history.gp "in='$history'; out='$tmp/h.png'; xcol='time'; ycol='$col'" "print xlabel; print ylabel"
    if [ $rc -eq 0 ] && grep -q -F "time [s]" "$tmp/gp" && grep -q -F "$col [$unit]" "$tmp/gp"; then ok; else
        fail "history ycol=$col" "labels are not 'time [s]' and '$col [$unit]': $(tr '\n' '|' <"$tmp/gp")"; fi
done <<'UNITS'
ke J/m
mass_out kg/m
unbal -
ry N/m
UNITS
gp "scaled" tools/history.gp "in='$history'; out='$tmp/h.png'; xcol='time'; ycol='ke'; yscale=0.001" "print ylabel"
if grep -q -F "ke [J/m] × 0.001" "$tmp/gp"; then ok; else fail "history yscale" "label: $(tr '\n' '|' <"$tmp/gp")"; fi

echo "tools: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
