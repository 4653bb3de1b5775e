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
log=$(mktemp); trap 'rm -f "$log"' EXIT
build/tests --no-version=1 >"$log" 2>&1; rc=$?
cat "$log"; count "unit (-O2)" "$log"; [ $rc -eq 0 ] || failed=$((failed + (rc != 0 && failed == 0)))
ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 build/tests-san --no-version=1 --test-case-exclude='*[slow]*' >"$log" 2>&1; rc=$?
tail -n 30 "$log"; count "unit (ASan+UBSan)" "$log"; [ $rc -eq 0 ] || failed=$((failed + (rc != 0 && failed == 0)))
# Program-level checks: every tests/check_*.sh, given the program, ends with "NAME: N passed, M failed".
for script in tests/check_*.sh; do
 for exe in ./lpfdm build/lpfdm-san; do
  out=$(bash "$script" "$exe" 2>&1); rc=$?
  echo "$out" | tail -n 40
  line=$(echo "$out" | grep -E '^[A-Za-z_-]+: [0-9]+ passed, [0-9]+ failed$' | tail -1)
  p=$(sed -E 's/^[A-Za-z_-]+: ([0-9]+) passed.*/\1/' <<<"$line"); f=$(sed -E 's/.* ([0-9]+) failed$/\1/' <<<"$line")
  [[ $p =~ ^[0-9]+$ ]] || p=0; [[ $f =~ ^[0-9]+$ ]] || f=1
  [ $rc -eq 0 ] || [ "$f" -gt 0 ] || f=1
  passed=$((passed + p)); failed=$((failed + f))
 done
done
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
