#!/usr/bin/env bash
# The output must not depend on the number of threads: run the same deck with 1 and 2
# threads and compare every output file byte for byte. Ends with "threads: N passed, M failed".
set -u
exe=${1:-./lpfdm}
cd "$(dirname "$0")/.."
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
passed=0 failed=0
for t in 1 2; do
  if ! timeout 300 "$exe" -q --threads "$t" -o "$tmp/t$t" tests/decks/threads_mohr.deck; then
    echo "FAIL: the run with $t thread(s) did not finish cleanly"; failed=$((failed + 1))
  fi
done
for f in threads_points.txt threads_history.txt; do
  if [ -s "$tmp/t1/$f" ] && cmp -s "$tmp/t1/$f" "$tmp/t2/$f"; then
    passed=$((passed + 1))
  else
    echo "FAIL: $f differs between 1 and 2 threads"; failed=$((failed + 1))
  fi
done
echo "threads: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
