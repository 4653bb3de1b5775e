#!/usr/bin/env bash
# The output must not depend on the number of threads: run the same decks with 1 and 2
# threads and compare every output file byte for byte. Ends with "threads: N passed, M failed".
set -u
exe=${1:-./lpfdm}
cd "$(dirname "$0")/.."
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
passed=0 failed=0
for run in threads_mohr:threads_points:threads_history threads_advect:threads_advect_points:threads_advect_history \
           threads_outflow:threads_outflow_points:threads_outflow_history; do
  IFS=: read -r deck points history <<<"$run"
  for t in 1 2; do
    if ! timeout 300 "$exe" -q --threads "$t" -o "$tmp/$deck.$t" "tests/decks/$deck.deck"; then
      echo "FAIL: $deck with $t thread(s) did not finish cleanly"; failed=$((failed + 1))
    fi
  done
  for f in "$points.txt" "$history.txt"; do
    # (the provenance lines "# run: ..." name the number of threads: they are skipped)
    if [ -s "$tmp/$deck.1/$f" ] && grep -q '^# run: threads 1 ' "$tmp/$deck.1/$f" &&
       cmp -s <(grep -v '^# run: ' "$tmp/$deck.1/$f") <(grep -v '^# run: ' "$tmp/$deck.2/$f"); then
      passed=$((passed + 1))
    else
      echo "FAIL: $f of $deck differs between 1 and 2 threads"; failed=$((failed + 1))
    fi
  done
done
echo "threads: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
