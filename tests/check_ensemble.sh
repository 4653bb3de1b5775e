#!/usr/bin/env bash
# tools/ensemble (parameter studies; decks/README.md) against known answers:
#   - a two-point sweep of MATERIAL1.RHO on the elastic column of decks/column.deck,
#     brought to rest, measuring last:ry: the base reaction is the column's weight
#     rho g W H, W and H read from the deck's CLUSTER card;
#   - two keys (MATERIAL1.RHO and GRAVITY.GY): every combination (4 runs, the first key
#     slowest) and --zip (2 runs), one column per key in index.tsv and summary.tsv, each
#     row rho |g| W H; with --seeds as well, every combination with every seed; --zip
#     with lists of unequal length refused;
#   - rung 5 of decks/README.md, its command as the document prints it, with `-- --steps
#     1000`: accepted although a short run draws warnings, heights 2 to 8 m, the 2 m cut
#     standing and the 8 m one moving; the same runs measured again (--summarize) by
#     height, outflow and min:e_grav (a taller cut settles more and loses more potential
#     energy, nothing leaves); the same ensemble as --jobs-only, its jobs.txt run
#     line by line as a Slurm array would, then --summarise: the same table;
#   - the cliff's --jobs-only of the Slurm section (500 seeds): jobs.txt and index.tsv,
#     nothing run; --summarise of it reports the runs as not finished (exit status 1);
#   - every shipped deck (decks/*.deck) accepted by --jobs-only with a sweep of gravity
#     and a measure it can give (runout, or last:ke where it writes no point table); the
#     two that write nothing (the speed benchmarks) refused, naming OUTPUT POINTS;
#   - refusals with exit status 2, nothing written: an unknown key and a value out of
#     range (the message names the value), options after -- that lpfdm refuses, -o after
#     --, a measure the deck's outputs cannot give (runout without a point table, outflow
#     without a history, a history column it does not have); a --strict after -- still
#     accepted (the one-step probe leaves it out).
#
# Runs once, for the plain build (plain_build_only): what is tested is the script, and
# the runs it makes are short runs of shipped decks, which the other checks already run
# with the sanitizer build; under the sanitizers they would only take minutes longer.
#
# usage: tests/check_ensemble.sh EXE
# One line per failure, and last "ensemble: N passed, M failed".
set -u

. "$(dirname "$0")/lib.sh"
plain_build_only ensemble "${1:-}"
need_program ensemble "$@"
cd "$(dirname "$0")/.." || exit 2
root=$PWD

tmp=$(mktemp -d) || exit 2
trap 'rm -rf "$tmp"' EXIT
passed=0 failed=0
fail() { echo "FAIL $1: $2"; failed=$((failed + 1)); }
ok() { passed=$((passed + 1)); }

# ens NAME ARGS...: runs tools/ensemble ARGS with --exe EXE (two jobs at a time); sets $rc,
# its stdout and stderr in $tmp/NAME.out and $tmp/NAME.err.
ens() {
    local name=$1
    shift
    timeout 120 tools/ensemble -j 2 --exe "$exe" "$@" >"$tmp/$name.out" 2>"$tmp/$name.err"
    rc=$?
}
said() { tr '\n' '|' <"$tmp/$1.err" | cut -c 1-400; }
# header FILE: the column names of a table (its first line not a comment), tab-separated.
header() { grep -v '^#' "$1" 2>/dev/null | head -n 1; }
# rows FILE: the table without its comments and column names.
rows() { grep -v '^#' "$1" 2>/dev/null | tail -n +2; }

# --- the column's base reaction: the weight rho g W H ---
# At 3000 steps the damped column is at rest: ry is within 2e-6 of its weight (the points
# carry the mass rho W H exactly); 1e-4 allows for what is left of the ringing and
# catches any wrong row (the values differ by factors of 2).
read -r W H < <(awk 'toupper($1) == "CLUSTER" { print $5 - $3, $6 - $4; exit }' decks/column.deck)
# check_weights NAME FILE "RHO GY"...: the rows of FILE (job, RHO [, GY], ry) are these, in
# this order, ry within 1e-4 of rho |g| W H (g 9.81 where the row has no GY).
check_weights() {
    local name=$1 file=$2
    shift 2
    local want got
    want=$(printf '%s\n' "$@")
    got=$(rows "$file" | awk -F'\t' -v W="$W" -v H="$H" -v want="$want" '
        BEGIN { n = split(want, w, "\n") }
        { k++; split(w[k], e, " "); g = (e[2] == "" ? 9.81 : -e[2]); ry = $NF; exact = e[1] * g * W * H
          if ($1 != k || $2 != e[1] || (e[2] != "" && $3 != e[2]) || ry == "NA" || (ry - exact) / exact > 1e-4 || (exact - ry) / exact > 1e-4)
              printf "row %d \"%s\": expected rho %s g %s, ry %.6g; ", k, $0, e[1], g, exact }
        END { if (k != n) printf "%d rows, expected %d", k, n }')
    if [ -z "$got" ]; then ok; else fail "$name" "$got"; fi
}

ens rho -o "$tmp/rho" --sweep MATERIAL1.RHO=1000,2000 --measure last:ry decks/column.deck -- --steps 3000
if [ $rc -eq 0 ]; then ok; else fail "rho sweep" "exit $rc: $(said rho)"; fi
if [ "$(header "$tmp/rho/summary.tsv")" = $'job\tMATERIAL1.RHO\tlast:ry' ] &&
    [ "$(header "$tmp/rho/index.tsv")" = $'job\tMATERIAL1.RHO\trun' ]; then ok; else
    fail "rho sweep" "columns: summary '$(header "$tmp/rho/summary.tsv")', index '$(header "$tmp/rho/index.tsv")'"; fi
check_weights "rho sweep: ry = rho g W H" "$tmp/rho/summary.tsv" 1000 2000
if command -v gnuplot >/dev/null; then
    if [ -s "$tmp/rho/sweep.png" ] && [ -s "$tmp/rho/histogram.png" ]; then ok; else fail "rho sweep" "no sweep.png or histogram.png: $(said rho)"; fi
fi
# measured again, another column
ens again --summarise -o "$tmp/rho" --measure max:ry
if [ $rc -eq 0 ] && [ "$(header "$tmp/rho/summary.tsv")" = $'job\tMATERIAL1.RHO\tmax:ry' ]; then ok; else
    fail "--summarise --measure max:ry" "exit $rc, columns '$(header "$tmp/rho/summary.tsv")': $(said again)"; fi
ens nocol --summarise -o "$tmp/rho" --measure last:nope
if [ $rc -eq 1 ] && grep -q "has no column 'nope'" "$tmp/nocol.err"; then ok; else
    fail "--summarise --measure last:nope" "exit $rc (expected 1 and the history's columns): $(said nocol)"; fi

# --- two keys ---
ens product -o "$tmp/product" --sweep MATERIAL1.RHO=1000,2000 --sweep GRAVITY.GY=-5,-10 --measure last:ry decks/column.deck -- --steps 3000
if [ $rc -eq 0 ]; then ok; else fail "product" "exit $rc: $(said product)"; fi
if [ "$(header "$tmp/product/summary.tsv")" = $'job\tMATERIAL1.RHO\tGRAVITY.GY\tlast:ry' ] &&
    [ "$(header "$tmp/product/index.tsv")" = $'job\tMATERIAL1.RHO\tGRAVITY.GY\trun' ]; then ok; else
    fail "product" "columns: summary '$(header "$tmp/product/summary.tsv")', index '$(header "$tmp/product/index.tsv")'"; fi
check_weights "product: ry = rho |g| W H" "$tmp/product/summary.tsv" "1000 -5" "1000 -10" "2000 -5" "2000 -10"
if command -v gnuplot >/dev/null; then
    if [ -s "$tmp/product/sweep.png" ] && [ "$(grep -c '^# GRAVITY.GY=' "$tmp/product/sweep.dat" 2>/dev/null)" = 2 ]; then ok; else
        fail "product" "no sweep.png with a line for each GRAVITY.GY: $(said product)"; fi
fi

ens zip -o "$tmp/zip" --zip --sweep MATERIAL1.RHO=1000,2000 --sweep GRAVITY.GY=-5,-10 --measure last:ry decks/column.deck -- --steps 3000
if [ $rc -eq 0 ]; then ok; else fail "zip" "exit $rc: $(said zip)"; fi
if [ "$(header "$tmp/zip/summary.tsv")" = $'job\tMATERIAL1.RHO\tGRAVITY.GY\tlast:ry' ]; then ok; else
    fail "zip" "columns: '$(header "$tmp/zip/summary.tsv")'"; fi
check_weights "zip: ry = rho |g| W H" "$tmp/zip/summary.tsv" "1000 -5" "2000 -10"
if command -v gnuplot >/dev/null; then
    if [ -s "$tmp/zip/sweep.png" ]; then ok; else fail "zip" "no sweep.png: $(said zip)"; fi
fi

ens unequal -o "$tmp/unequal" --zip --sweep MATERIAL1.RHO=1000,2000 --sweep GRAVITY.GY=-5,-8,-10 decks/column.deck
if [ $rc -eq 2 ] && grep -q 'equally long' "$tmp/unequal.err" && [ ! -e "$tmp/unequal" ]; then ok; else
    fail "zip of unequal lists" "exit $rc (expected 2, 'equally long', nothing written): $(said unequal)"; fi

# with seeds: every combination with every seed, the seed after the keys
ens seeds --jobs-only -o "$tmp/seeds" --seeds 2 --sweep MATERIAL1.C=9000,9800 --sweep MATERIAL1.PHI=25:5:35 decks/cliff.deck
want=$(for c in 9000 9800; do for p in 25 30 35; do for s in 1 2; do echo "$c $p $s"; done; done; done)
got=$(rows "$tmp/seeds/index.tsv" | cut -f 2-4 | tr '\t' ' ')
if [ $rc -eq 0 ] && [ "$(header "$tmp/seeds/index.tsv")" = $'job\tMATERIAL1.C\tMATERIAL1.PHI\tseed\trun' ] && [ "$got" = "$want" ] &&
    [ "$(wc -l <"$tmp/seeds/jobs.txt")" = 12 ] &&
    sed -n 12p "$tmp/seeds/jobs.txt" | grep -q -- '--seed 2 --set MATERIAL1.C=9800 --set MATERIAL1.PHI=35 decks/cliff.deck'; then ok; else
    fail "two keys with seeds" "exit $rc, index '$(header "$tmp/seeds/index.tsv")' rows '$(tr '\n' '|' <<<"$got")', line 12 of jobs.txt '$(sed -n 12p "$tmp/seeds/jobs.txt" 2>/dev/null)': $(said seeds)"; fi

# --- rung 5 of decks/README.md, as printed there, on fewer steps ---
rung5=$(grep -m 1 -E '^tools/ensemble .*--sweep CLUSTER1\.Y1=.* decks/cut_high\.deck$' decks/README.md)
if [ -z "$rung5" ]; then
    fail "rung 5" "decks/README.md shows no 'tools/ensemble ... --sweep CLUSTER1.Y1=... decks/cut_high.deck' line"
else
    # the reader's directory: decks/ and tools/ of the project, ./lpfdm the program
    mkdir -p "$tmp/reader"
    ln -s "$root/decks" "$tmp/reader/decks" && ln -s "$root/tools" "$tmp/reader/tools" && ln -s "$exe" "$tmp/reader/lpfdm"
    (cd "$tmp/reader" && eval "timeout 120 $rung5 -- --steps 1000") >"$tmp/rung5.out" 2>"$tmp/rung5.err"
    rc=$?
    table=$(ls "$tmp"/reader/out/*/summary.tsv 2>/dev/null | head -n 1)
    if [ $rc -eq 0 ] && [ -n "$table" ]; then ok; else fail "rung 5: $rung5 -- --steps 1000" "exit $rc: $(said rung5)"; fi
    # heights 2..8 m; the 2 m cut stands (its face bulges by 0.5 mm), the 8 m one moves
    # (0.09 m at 1000 steps)
    got=$(rows "$table" | awk -F'\t' '{ h = h $2 " " } NR == 1 { lo = $3 } { hi = $3 }
        END { printf "%s%s", h, (lo != "NA" && hi != "NA" && lo < 0.002 && hi > 0.02) ? "ok" : "runout " lo " at the lowest, " hi " at the highest" }')
    if [ "$got" = "2 3 4 5 6 7 8 ok" ]; then ok; else fail "rung 5" "heights and run-outs: $got"; fi

    # the same as a Slurm array would run it: --jobs-only, each line of jobs.txt, --summarise
    (cd "$tmp/reader" && eval "timeout 60 ${rung5/-o out\//-o out\/array_} --jobs-only -- --steps 1000") >"$tmp/array.out" 2>"$tmp/array.err"
    rc=$?
    jobs=$(ls "$tmp"/reader/out/array_*/jobs.txt 2>/dev/null | head -n 1)
    if [ $rc -eq 0 ] && [ -n "$jobs" ] && [ "$(wc -l <"$jobs")" = 7 ] && ! ls -d "$(dirname "$jobs")"/run_* >/dev/null 2>&1; then
        for k in 1 2 3 4 5 6 7; do (cd "$tmp/reader" && sed -n "${k}p" "$jobs" | timeout 60 bash); done
        (cd "$tmp/reader" && timeout 60 tools/ensemble --summarise -o "$(dirname "${jobs#"$tmp/reader/"}")") >"$tmp/array.out" 2>"$tmp/array.err"
        rc=$?
        if [ $rc -eq 0 ] && cmp -s "$table" "$(dirname "$jobs")/summary.tsv"; then ok; else
            fail "rung 5 as a Slurm array" "--summarise exit $rc, table differs from the direct run's: $(said array)"; fi
    else
        fail "rung 5 --jobs-only" "exit $rc, jobs.txt '${jobs:-none}' should have 7 lines and no run made: $(said array)"
    fi
    # the same runs measured again with the other measures (and the other spelling of
    # --summarise): a taller cut settles more and loses more potential energy (the loss of
    # height 0.13 to 5.2 mm at 1000 steps, e_grav's least -32 to -37 000 J/m), nothing
    # leaves the lattice
    for m in height outflow min:e_grav; do
        (cd "$tmp/reader" && timeout 60 tools/ensemble --summarize -o "$(dirname "${table#"$tmp/reader/"}")" --measure "$m") >"$tmp/remeasure.out" 2>"$tmp/remeasure.err"
        rc=$?
        got=$(rows "$table" | awk -F'\t' -v m="$m" '{ v = $3 } $3 == "NA" { bad = 1 } NR > 1 && m == "height" && v <= prev { bad = 1 }
            NR > 1 && m == "min:e_grav" && v >= prev { bad = 1 } m == "outflow" && v != 0 { bad = 1 } m == "min:e_grav" && v >= 0 { bad = 1 }
            NR == 1 && m == "height" && v >= 0.001 { bad = 1 } { prev = v; all = all " " $3 } END { print (bad ? "wrong:" : "ok") all }')
        if [ $rc -eq 0 ] && [ "$(header "$table" | cut -f 3)" = "$m" ] && [ "${got%% *}" = ok ]; then ok; else
            fail "rung 5 --summarize --measure $m" "exit $rc, column '$(header "$table" | cut -f 3)', values $got: $(said remeasure)"; fi
    done
fi

# --- the Slurm section's --jobs-only of the cliff, as printed (nothing is run) ---
cliff=$(grep -m 1 -E '^tools/ensemble --jobs-only .* decks/cliff\.deck$' decks/README.md)
if [ -z "$cliff" ]; then
    fail "cliff --jobs-only" "decks/README.md shows no 'tools/ensemble --jobs-only ... decks/cliff.deck' line"
else
    (cd "$tmp/reader" && eval "timeout 60 $cliff") >"$tmp/cliff.out" 2>"$tmp/cliff.err"
    rc=$?
    jobs=$(grep -l cliff.deck "$tmp"/reader/out/*/jobs.txt 2>/dev/null | head -n 1)
    n=$(sed -nE 's/.*--seeds ([0-9]+).*/\1/p' <<<"$cliff")
    if [ $rc -eq 0 ] && [ -n "$jobs" ] && [ "$(wc -l <"$jobs")" = "$n" ] &&
        [ "$(rows "$(dirname "$jobs")/index.tsv" | wc -l)" = "$n" ] &&
        sed -n "${n}p" "$jobs" | grep -q -- "--seed $n decks/cliff.deck" &&
        ! ls -d "$(dirname "$jobs")"/run_* >/dev/null 2>&1; then ok; else
        fail "$cliff" "exit $rc: jobs.txt '${jobs:-none}' should have $n lines, the last --seed $n, and no run made: $(said cliff)"
    fi
    if [ -n "$jobs" ]; then
        (cd "$tmp/reader" && timeout 60 tools/ensemble --summarise -o "$(dirname "${jobs#"$tmp/reader/"}")") >"$tmp/unrun.out" 2>"$tmp/unrun.err"
        rc=$?
        if [ $rc -eq 1 ] && grep -q 'run 1 .* did not finish' "$tmp/unrun.err"; then ok; else
            fail "--summarise of runs not run" "exit $rc (expected 1, 'did not finish'): $(said unrun)"; fi
    fi
fi

# --- every shipped deck accepted (one step of each value, warnings and all), with a
# measure it can give: runout where it writes a point table, else last:ke of its history;
# a deck that writes neither (the speed benchmarks) is refused, naming the card ---
refused=""
for deck in decks/*.deck; do
    name=$(basename "$deck" .deck)
    m=runout
    grep -q '^OUTPUT *POINTS' "$deck" || m=last:ke
    if ! grep -q '^OUTPUT' "$deck"; then
        ens "deck_$name" --jobs-only -o "$tmp/decks/$name" --sweep GRAVITY.GY=-9.81,-9 "$deck"
        [ $rc -eq 2 ] && grep -q 'writes no point table.*OUTPUT POINTS' "$tmp/deck_$name.err" && [ ! -e "$tmp/decks/$name" ] ||
            refused="$refused $name (writes nothing to measure, but exit $rc: $(said "deck_$name"))"
        continue
    fi
    ens "deck_$name" --jobs-only --measure "$m" -o "$tmp/decks/$name" --sweep GRAVITY.GY=-9.81,-9 "$deck"
    [ $rc -eq 0 ] && [ "$(wc -l <"$tmp/decks/$name/jobs.txt" 2>/dev/null)" = 2 ] || refused="$refused $name (exit $rc: $(said "deck_$name"))"
done
if [ -z "$refused" ]; then ok; else fail "shipped decks refused by --jobs-only --sweep GRAVITY.GY=-9.81,-9" "$refused"; fi

# --- refusals: exit status 2, the value named, nothing written ---
# refused NAME PHRASE ARGS...: tools/ensemble ARGS must exit 2, say PHRASE, write no -o DIR.
refused() {
    local name=$1 phrase=$2
    shift 2
    ens "$name" -o "$tmp/$name" "$@"
    if [ $rc -eq 2 ] && grep -q -F -- "$phrase" "$tmp/$name.err" && [ ! -e "$tmp/$name" ]; then ok; else
        fail "refused $name: $*" "exit $rc (expected 2, '$phrase', nothing written): $(said "$name")"; fi
}
refused badkey "--set MATERIAL1.NOPE=3" --sweep MATERIAL1.NOPE=3 decks/cut_high.deck
refused badvalue "--set MATERIAL1.PHI=95" --sweep MATERIAL1.PHI=20,95 decks/cut_high.deck
refused badopt "FOO.X" --seeds 2 decks/cliff.deck -- --set FOO.X=1
refused outdir "not '-o' after --" --seeds 2 decks/cliff.deck -- -o elsewhere
refused twice "given twice" --sweep MATERIAL1.C=1,2 --sweep material1.c=3 decks/cut_high.deck
refused nopoints "writes no point table" --sweep GRAVITY.GY=-9.81,-9 decks/verify_psc.deck
refused nohistory "writes no history" --sweep GRAVITY.GY=-9.81,-9 --measure outflow decks/verify_taylor.deck
refused nocolumn "has no column 'nope'" --sweep GRAVITY.GY=-9.81,-9 --measure max:nope decks/column.deck
ens strict --jobs-only -o "$tmp/strict" --sweep MATERIAL1.RHO=1000,2000 decks/column.deck -- --strict
if [ $rc -eq 0 ] && grep -q -- '--strict' "$tmp/strict/jobs.txt"; then ok; else fail "-- --strict" "exit $rc, refused by the probe: $(said strict)"; fi

# --help is the usage comment, with the options of several keys
if tools/ensemble --help | grep -q -- '--zip'; then ok; else fail "--help" "does not describe --zip"; fi

echo "ensemble: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
