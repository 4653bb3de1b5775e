#!/usr/bin/env bash
# Runs every test of `make test`: unit tests at -O2 and under ASan+UBSan, then the
# deck-level checks with both builds of the program. Ends with "N passed, N failed".
set -u
cd "$(dirname "$0")/.."
passed=0 failed=0
count() {  # $1: label, $2: log; adds doctest's "test cases" totals
  local line p f
  line=$(grep -E '^\[doctest\] test cases:' "$2" | tail -1)
  p=$(sed -E 's/.*\| *([0-9]+) passed.*/\1/' <<<"$line"); f=$(sed -E 's/.*\| *([0-9]+) failed.*/\1/' <<<"$line")
  [[ $p =~ ^[0-9]+$ ]] || p=0; [[ $f =~ ^[0-9]+$ ]] || f=1
  echo "$1: $p passed, $f failed"
  passed=$((passed + p)); failed=$((failed + f))
}
log=$(mktemp); log2=$(mktemp); trap 'rm -f "$log" "$log2"' EXIT
# The two unit runs are independent: one core each (the kernel's own threads stay at one).
OMP_NUM_THREADS=1 build/tests --no-version=1 >"$log" 2>&1 & pid1=$!
OMP_NUM_THREADS=1 ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
  build/tests-san --no-version=1 --test-case-exclude='*[slow]*' >"$log2" 2>&1 & pid2=$!
wait $pid1; rc=$?
cat "$log"; count "unit (-O2)" "$log"; [ $rc -eq 0 ] || failed=$((failed + (rc != 0 && failed == 0)))
wait $pid2; rc=$?
tail -n 30 "$log2"; count "unit (ASan+UBSan)" "$log2"; [ $rc -eq 0 ] || failed=$((failed + (rc != 0 && failed == 0)))
# Program-level checks: every tests/check_*.sh, given the program, ends with "NAME: N passed, M failed".
# One lane per build of the program, the two lanes side by side (one core each); each lane
# writes its log and its totals, printed afterwards in a fixed order.
lane() {  # $1: program, $2: log; last line of the log "P F"
  local script out rc line p f lp=0 lf=0
  for script in tests/check_*.sh; do
    out=$(bash "$script" "$1" 2>&1); rc=$?
    echo "$out" | tail -n 40
    line=$(echo "$out" | grep -E '^[A-Za-z_-]+: [0-9]+ passed, [0-9]+ failed$' | tail -1)
    p=$(sed -E 's/^[A-Za-z_-]+: ([0-9]+) passed.*/\1/' <<<"$line"); f=$(sed -E 's/.* ([0-9]+) failed$/\1/' <<<"$line")
    [[ $p =~ ^[0-9]+$ ]] || p=0; [[ $f =~ ^[0-9]+$ ]] || f=1
    [ $rc -eq 0 ] || [ "$f" -gt 0 ] || f=1
    lp=$((lp + p)); lf=$((lf + f))
  done >"$2"
  echo "$lp $lf" >>"$2"
}
lane1=$(mktemp); lane2=$(mktemp); trap 'rm -f "$log" "$log2" "$lane1" "$lane2"' EXIT
lane ./lpfdm "$lane1" & pid1=$!
lane build/lpfdm-san "$lane2" & pid2=$!
wait $pid1 $pid2
for l in "$lane1" "$lane2"; do
  sed '$d' "$l"
  read -r p f < <(tail -n 1 "$l")
  [[ $p =~ ^[0-9]+$ && $f =~ ^[0-9]+$ ]] || { p=0; f=1; }
  passed=$((passed + p)); failed=$((failed + f))
done
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
