#!/usr/bin/env bash
# make bench: particle-steps per second on the benchmark scenes (decks/bench_*.deck),
# one table at the end.
#   bash tools/bench.sh [EXE] [RUNS]          (default ./lpfdm, 5 runs per median)
# Every figure is the median of RUNS runs (min and max go to stderr with the details).
#
# Two kinds of scene:
#   - the 400-step scenes of 65 536 points, and the same at 1 048 576 points with
#     --refine 4 --steps 60 (bench_elastic.deck, bench_mohr.deck): speed at one moment of
#     a run; 1 and 2 threads (their runs interleaved), the reference kernel (the plain
#     cycle, one thread, --kernel reference) on the same steps, the program with points,
#     cells and nodes one at a time (--no-avx2) and, with git history, the plain serial
#     loop of commit BEFORE, compiled by this script;
#   - whole runs (bench_peer.deck: an elastic block brought to rest, 2000 steps;
#     bench_flow.deck: a collapse in full flow, 4000 steps): the whole run, its first
#     10 % of steps (a run of those steps) and its last 10 % (the state saved by one run
#     of 90 % of the steps, OUTPUT STATE, continued with --restart), each with 1 and 2
#     threads; the reference kernel on the same first and last 10 % (it is slow: not
#     the whole run); the plain serial loop of commit BEFORE on the whole run, beside a
#     whole run of the program timed the same way (the summary line's figure, the steps
#     with their output: that version has no --profile), and what it gave; and the
#     result of the run (the peer scene's sigma_yy error against the column at rest, the
#     flow's front travel in cells and fraction yielded).
# The whole-run scenes are timed by --profile: particle-steps over the sum of the times
# of the phases of the cycle (the steps alone: not the frames and the state written).
# The ratios to the reference kernel and to the plain loop, measured in the same run, are
# what compares across machines, and only to within about a fifth (tools/README.md: one
# kernel gave 3.20 and 2.56 times the plain loop on two machines of one class); the
# absolute figures do not.
#
# Environment:
#   BENCH_SCENES="elastic-65k mohr-65k elastic-1M mohr-1M peer flow"  the scenes to run
#                (default all: about 6 minutes with RUNS=3 on an idle machine of 2 cores,
#                10 with 5; much longer if another program holds a core, where two
#                threads can run several times slower than one)
#   BEFORE=4fdf066   the commit whose plain serial loop is built for the 400-step scenes;
#                BEFORE= (empty) skips it
#   BENCH_MODES="peer mohr-65k flow"  also the modes' table: each of those scenes with
#                the paper's mapping, MAPPING SMOOTH, and MAPPING SMOOTH with ADVECT FLIP
#                (a copy of the deck with the cards added), 1 and 2 threads, all runs
#                interleaved, timed by --profile; flow over its first 400 steps (FLIP's
#                whole run takes minutes). Default: none (BENCH_SCENES=none runs it alone)
set -u
cd "$(dirname "$0")/.."
exe=${1:-./lpfdm}; runs=${2:-5}
before_rev=${BEFORE-4fdf066}
want=${BENCH_SCENES:-elastic-65k mohr-65k elastic-1M mohr-1M peer flow}  # (none: no scene)
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
load_start=$(cut -d' ' -f1-3 /proc/loadavg)
# name | deck | extra options | kind (short: the deck's steps as they are; whole: whole-run measures)
scenes=(
  "elastic-65k|decks/bench_elastic.deck||short"
  "mohr-65k|decks/bench_mohr.deck||short"
  "elastic-1M|decks/bench_elastic.deck|--refine 4 --steps 60|short"
  "mohr-1M|decks/bench_mohr.deck|--refine 4 --steps 60|short"
  "peer|decks/bench_peer.deck||whole"
  "flow|decks/bench_flow.deck||whole"
)
log() { echo "$*" >&2; }
command -v "$exe" >/dev/null 2>&1 || [ -x "$exe" ] || { log "bench: no program $exe"; exit 2; }

before=""
if [ -n "$before_rev" ] && git rev-parse -q --verify "$before_rev^{commit}" >/dev/null 2>&1; then
  mkdir -p "$tmp/before"
  git show "$before_rev:lpfdm.hpp" >"$tmp/before/lpfdm.hpp" && git show "$before_rev:lpfdm.cpp" >"$tmp/before/lpfdm.cpp" &&
    g++ -std=c++17 -O2 -o "$tmp/before/lpfdm" "$tmp/before/lpfdm.cpp" -lfmt && before="$tmp/before/lpfdm"
fi

rate() {  # exe, threads, deck, options -> particle-steps/s of one run (the program's summary line)
  OMP_NUM_THREADS=$2 "$1" -o "$tmp/o" $4 "$3" 2>/dev/null | sed -nE 's/.* ([0-9.e+]+) particle-steps\/s.*/\1/p'
}
# timed STEPS THREADS DIR OPTIONS... : one run with --profile, STEPS steps run;
# prints "rate peak_MiB bytes_per_point phases", rate = points x STEPS / (sum of the
# phase times), or "-" when the run failed. Writes DIR/stdout.
timed() {
  local steps=$1 t=$2 dir=$3; shift 3
  mkdir -p "$dir"
  OMP_NUM_THREADS=$t "$exe" --profile -o "$dir" "$@" >"$dir/stdout" 2>"$dir/stderr"
  awk -v steps="$steps" '
    /^profile: threads/ { for (i = 1; i <= NF; i++) { if ($i == "memory") mib = $(i + 1); if ($(i + 1) == "bytes") bpp = $i } }
    /^profile: [a-z_]+ +[0-9.]+ s / { sum += $3; ph = ph sprintf(" %s %s", $2, $3) }
    /^lpfdm: [0-9]+ steps/ { pts = $4; wall = $6; r = $8; for (i = 1; i < NF; i++) if ($i == "outflow") out = $(i + 1) + 0 }
    END {
      if (sum <= 0 || pts == "") { print "- - -"; exit }
      # points x steps (the bench scenes keep every point); the summary'"'"'s figure if some left
      ps = (out == 0) ? pts * steps : r * wall
      printf "%.4g %s %s%s\n", ps / sum, mib, bpp, ph
    }' "$dir/stdout"
}
stats() {  # numbers on stdin -> "median min max"
  grep -E '^[0-9]' | sort -g | awk '{a[NR]=$1} END {if (NR == 0) {print "- - -"; exit} m = (NR % 2) ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2; printf "%.3g %.3g %.3g\n", m, a[1], a[NR]}'
}
ratio() { awk -v a="$1" -v b="$2" 'BEGIN { if (a + 0 > 0 && b + 0 > 0) printf "%.2f", a / b; else printf "-" }'; }
med() { echo "${1%% *}"; }
# col FILE K: column K of FILE's lines (the runs of one measure)
col() { cut -d' ' -f"$2" "$1"; }

# result_of NAME DECK TABLE: what a whole run gave, from its point table ("-" without one)
result_of() {
  local name=$1 deck=$2 table=$3 L f0 f1 y
  [ -s "$table" ] || { echo "-"; return; }
  case $name in
  peer)
    # sigma_yy against the column at rest, -rho g (H - Y), at each point's height at
    # step 0, relative L2 error over all points (tools/verify_column.awk)
    awk -v H=32 -v rho=2000 -v g=9.81 -v E=1e7 -v nu=0.3 -f tools/verify_column.awk "$table" |
      awk '{ printf "syy L2 error %.2f %%", 100 * $3 }' ;;
  flow)
    # the front (99 % of the points behind it, tools/verify_front.awk) at step 0 and at
    # the end, in cells; the fraction of the points that have yielded at the end
    L=$(awk 'toupper($1) == "GRID" { print $4 }' "$deck")
    f0=$(awk '/^# step/ { f++ } f == 1' "$table" | awk -f tools/verify_front.awk)
    f1=$(awk -f tools/verify_front.awk "$table")
    y=$(awk '/^# step/ { n = s = 0; next } /^[0-9-]/ { n++; s += $8 } END { if (n) printf "%.1f", 100 * s / n }' "$table")
    awk -v a="$f0" -v b="$f1" -v L="$L" -v y="$y" 'BEGIN { split(a, p, " "); split(b, q, " ")
      printf "front +%.0f cells (farthest point +%.0f), %s %% yielded", (q[1] - p[1]) / L, (q[2] - p[2]) / L, y }' ;;
  *) echo "-" ;;
  esac
}

rows=()
for sc in "${scenes[@]}"; do
  IFS='|' read -r name deck opts kind <<<"$sc"
  case " $want " in *" $name "*) ;; *) continue ;; esac
  log "== $name ($deck $opts)"
  if [ "$kind" = short ]; then
    # One and two threads interleaved, run by run, so that a slow spell of the machine
    # falls on both and their ratio (the target is 1.7) holds; --profile gives the peak
    # memory and the phases.
    : >"$tmp/r1"; : >"$tmp/r2"; : >"$tmp/m1"; : >"$tmp/m2"
    for r in $(seq "$runs"); do
      for t in 1 2; do
        OMP_NUM_THREADS=$t "$exe" --profile -o "$tmp/o" $opts "$deck" >"$tmp/p$t" 2>/dev/null
        sed -nE 's/.* ([0-9.e+]+) particle-steps\/s.*/\1/p' "$tmp/p$t" >>"$tmp/r$t"
        sed -nE 's/.*peak memory ([0-9.]+) MiB, ([0-9.]+) bytes per point.*/\1 \2/p' "$tmp/p$t" >>"$tmp/m$t"
        [ "$r" = 1 ] && log "   $t thread(s), phases [s]:$(awk '/^profile: [a-z_]+ +[0-9.]+ s / { printf " %s %s", $2, $3 }' "$tmp/p$t")"
      done
    done
    pts=$(sed -nE 's/^lpfdm: [0-9]+ steps, ([0-9]+) points.*/\1/p' "$tmp/p1"); steps=$(sed -nE 's/^lpfdm: ([0-9]+) steps.*/\1/p' "$tmp/p1")
    one=$(stats <"$tmp/r1"); two=$(stats <"$tmp/r2")
    log "   1 thread  $one (median min max)"; log "   2 threads $two"
    mem1=$(col "$tmp/m1" 1 | stats); mem2=$(col "$tmp/m2" 1 | stats); bpp=$(col "$tmp/m1" 2 | stats)
    # The reference kernel, the plain loop of BEFORE (if built) and one-thread runs of the
    # program, interleaved run by run; then the program one value at a time against the default.
    : >"$tmp/f"; : >"$tmp/ref"; : >"$tmp/bef"
    for r in $(seq "$runs"); do
      rate "$exe" 1 "$deck" "$opts" >>"$tmp/f"
      rate "$exe" 1 "$deck" "$opts --kernel reference" >>"$tmp/ref"
      [ -n "$before" ] && rate "$before" 1 "$deck" "$opts" >>"$tmp/bef"
    done
    fast=$(stats <"$tmp/f"); ref=$(stats <"$tmp/ref"); bef=$(stats <"$tmp/bef")
    log "   1 thread  $fast (again, beside the reference kernel $ref and the plain loop of ${before_rev:-none} $bef)"
    narrow="- - -"; wide="- - -"
    if "$exe" --help 2>/dev/null | grep -q -- --no-avx2; then
      pair=$(for r in $(seq "$runs"); do echo "$(rate "$exe" 1 "$deck" "$opts --no-avx2") $(rate "$exe" 1 "$deck" "$opts")"; done)
      narrow=$(cut -d' ' -f1 <<<"$pair" | stats); wide=$(cut -d' ' -f2 <<<"$pair" | stats)
      log "   one value at a time $narrow, beside the default $wide"
    fi
    befcell="-"; [ -n "$before" ] && befcell="$(med "$bef") ($(ratio "$(med "$fast")" "$(med "$bef")"))"
    rows+=("| $name | $pts | $steps | $(med "$one") | $(med "$two") ($(ratio "$(med "$two")" "$(med "$one")")x) | - | - | $(med "$ref") | $(ratio "$(med "$fast")" "$(med "$ref")") | $befcell | $(med "$narrow") ($(ratio "$(med "$wide")" "$(med "$narrow")")) | $(med "$mem1") / $(med "$mem2") | $(med "$bpp") | |")
    continue
  fi

  # Whole-run scene: a copy of the deck that also saves its state at the end.
  steps=$(awk 'toupper($1) == "STEP" { print $3 }' "$deck")
  tenth=$((steps / 10)); resume=$((steps - tenth))
  base=$(basename "$deck" .deck)
  awk -v s="OUTPUT STATE $base.state" '/^[ \t]*[Ee][Nn][Dd]([ \t!]|$)/ && !done { print s; done = 1 } { print } END { if (!done) print s }' "$deck" >"$tmp/$base.deck"
  copy=$tmp/$base.deck
  mkdir -p "$tmp/plain" && plain=$tmp/plain/$base.deck
  grep -v -i -E '^[[:space:]]*SHIFT([[:space:]!]|$)' "$deck" >"$plain"
  # The state at 90 % of the steps (two threads: the same bytes as one), continued by every last-10 % run.
  OMP_NUM_THREADS=2 "$exe" -q -o "$tmp/$name-state" --steps "$resume" "$copy" 2>/dev/null
  state=$tmp/$name-state/$base.state
  [ -s "$state" ] || log "   no state written at step $resume: the last 10 % is not measured"
  for m in whole1 whole2 first1 first2 last1 last2 reffirst reflast plainw progw cw cf cl; do : >"$tmp/$m"; done
  consult() { sed -nE 's/.*Mohr-Coulomb consult.* ([0-9.]+) ns per point-update.*/\1/p' "$1/stdout"; }  # its ns, from --profile
  for r in $(seq "$runs"); do
    # interleaved run by run, so that a slow spell of the machine falls on all of them
    timed "$steps" 1 "$tmp/$name-w1-$r" "$copy" >>"$tmp/whole1"
    consult "$tmp/$name-w1-$r" >>"$tmp/cw"
    timed "$steps" 2 "$tmp/$name-w2-$r" "$copy" >>"$tmp/whole2"
    timed "$tenth" 1 "$tmp/$name-f1" --steps "$tenth" "$copy" >>"$tmp/first1"
    consult "$tmp/$name-f1" >>"$tmp/cf"
    timed "$tenth" 2 "$tmp/$name-f2" --steps "$tenth" "$copy" >>"$tmp/first2"
    timed "$tenth" 1 "$tmp/$name-f0" --kernel reference --steps "$tenth" "$copy" >>"$tmp/reffirst"
    if [ -s "$state" ]; then
      timed "$tenth" 1 "$tmp/$name-l1" --restart "$state" "$copy" >>"$tmp/last1"
      consult "$tmp/$name-l1" >>"$tmp/cl"
      timed "$tenth" 2 "$tmp/$name-l2" --restart "$state" "$copy" >>"$tmp/last2"
      timed "$tenth" 1 "$tmp/$name-l0" --kernel reference --restart "$state" "$copy" >>"$tmp/reflast"
    fi
    # the plain loop of BEFORE on the whole run (the deck as it is, less the cards that
    # version cannot read, SHIFT: it writes no state), beside the program's own whole run
    # of that same deck timed the same way (its summary line: the steps with their
    # output), one thread each
    if [ -n "$before" ]; then
      rate "$before" 1 "$plain" "" >>"$tmp/plainw"
      cp "$tmp/o/${base}_points.txt" "$tmp/$name-plain-points.txt" 2>/dev/null
      rate "$exe" 1 "$plain" "" >>"$tmp/progw"
    fi
    [ "$r" -lt "$runs" ] && rm -rf "$tmp/$name-w1-$r" "$tmp/$name-w2-$r"  # (the last run's table is measured below)
  done
  pts=$(sed -nE 's/^lpfdm: [0-9]+ steps, ([0-9]+) points.*/\1/p' "$tmp/$name-w1-$runs/stdout")
  for m in whole1 whole2 first1 first2 last1 last2 reffirst reflast plainw progw; do
    eval "$m=\$(col \"\$tmp/$m\" 1 | stats)"
    log "   $(printf '%-9s' "$m") $(eval echo "\$$m") (median min max)"
  done
  for m in whole1 first1 last1 reffirst reflast; do
    [ -s "$tmp/$m" ] && log "   $(printf '%-9s' "$m") phases [s] of its first run:$(head -1 "$tmp/$m" | cut -d' ' -f4-)"
  done
  mem1=$(col "$tmp/whole1" 2 | stats); mem2=$(col "$tmp/whole2" 2 | stats); bpp=$(col "$tmp/whole1" 3 | stats)
  # The result of the run, from the point table of the last one-thread whole run.
  check=$(result_of "$name" "$deck" "$tmp/$name-w1-$runs/${base}_points.txt")
  if [ -s "$tmp/cw" ]; then  # the Mohr-Coulomb consult's ns a point-update (--profile), one thread
    check="$check; consult $(med "$(stats <"$tmp/cw")") ns a point-update (first / last 10 %: $(med "$(stats <"$tmp/cf")") / $(med "$(stats <"$tmp/cl")"))"
  fi
  log "   $check"
  befcell="-"
  if [ -n "$before" ] && [ -s "$tmp/plainw" ]; then
    befcell="$(med "$plainw") ($(ratio "$(med "$progw")" "$(med "$plainw")"), whole run)"
    log "   plain loop of $before_rev, whole run: $plainw; the program beside it, timed alike: $progw (median min max)"
    log "   plain loop of $before_rev, its result: $(result_of "$name" "$deck" "$tmp/$name-plain-points.txt")"
  fi
  rows+=("| $name | $pts | $steps | $(med "$whole1") | $(med "$whole2") ($(ratio "$(med "$whole2")" "$(med "$whole1")")x) | $(med "$first1") / $(med "$first2") | $(med "$last1") / $(med "$last2") | $(med "$reffirst") / $(med "$reflast") (10 %) | $(ratio "$(med "$first1")" "$(med "$reffirst")") / $(ratio "$(med "$last1")" "$(med "$reflast")") | $befcell | - | $(med "$mem1") / $(med "$mem2") | $(med "$bpp") | $check |")
done

if [ ${#rows[@]} -gt 0 ]; then
echo
echo "Particle-steps/s, median of $runs runs, $($exe --version 2>/dev/null | head -1)$(git rev-parse -q --short HEAD >/dev/null 2>&1 && echo " (commit $(git rev-parse --short HEAD)$(git diff --quiet HEAD -- lpfdm.hpp lpfdm.cpp 2>/dev/null || echo ' with changes'))")."
echo "Whole-run scenes: first / last 10 % of the steps; the reference kernel (one thread) on those same steps, and the ratio of one thread to it on each."
echo "The ratios to the reference kernel and to the plain loop compare across machines, and only to within about a fifth (tools/README.md); the absolute figures do not."
echo
echo "| scene | points | steps | 1 thread | 2 threads | first 10 %, 1 / 2 threads | last 10 %, 1 / 2 threads | reference kernel | 1 thread / reference | plain loop of ${before_rev:--} (ratio) | one at a time (ratio) | peak MiB, 1 / 2 threads | bytes per point | result |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
printf '%s\n' "${rows[@]}" | sed -E 's/e\+0?([0-9])/e\1/g'  # 4.12e+07 -> 4.12e7
fi

# The modes (BENCH_MODES): what the accurate cycle costs against the paper's, per
# particle-step, on the same scene and build, their runs interleaved.
mrows=()
for name in ${BENCH_MODES:-}; do
  case $name in
  peer) deck=decks/bench_peer.deck; opts="" ;;
  mohr-65k) deck=decks/bench_mohr.deck; opts="" ;;
  flow) deck=decks/bench_flow.deck; opts="--steps 400" ;;
  *) log "bench: no modes scene '$name' (peer, mohr-65k, flow)"; continue ;;
  esac
  steps=${opts#--steps }; [ -n "$opts" ] || steps=$(awk 'toupper($1) == "STEP" { print $3 }' "$deck")
  log "== modes: $name ($deck $opts)"
  for m in paper smooth flip; do
    cards=""; [ $m = smooth ] && cards="MAPPING SMOOTH"; [ $m = flip ] && cards="MAPPING SMOOTH\nADVECT FLIP"
    awk -v c="$cards" '/^[ \t]*[Ee][Nn][Dd]([ \t!]|$)/ && !done { if (c != "") print c; done = 1 } { print } END { if (!done && c != "") print c }' "$deck" >"$tmp/mode-$m.deck"
    : >"$tmp/mode-$m-1"; : >"$tmp/mode-$m-2"
  done
  for r in $(seq "$runs"); do
    for t in 1 2; do
      for m in paper smooth flip; do
        timed "$steps" $t "$tmp/mode-run" $opts "$tmp/mode-$m.deck" | cut -d' ' -f1 >>"$tmp/mode-$m-$t"
      done
    done
  done
  pts=$(sed -nE 's/^lpfdm: [0-9]+ steps, ([0-9]+) points.*/\1/p' "$tmp/mode-run/stdout")
  cells="| $name | $pts | $steps |"
  for m in paper smooth flip; do
    one=$(stats <"$tmp/mode-$m-1"); two=$(stats <"$tmp/mode-$m-2")
    log "   $(printf '%-6s' $m) 1 thread $one, 2 threads $two (median min max)"
    eval "${m}1=\$(med \"\$one\")"; eval "${m}2=\$(med \"\$two\")"
    if [ $m = paper ]; then cells="$cells $(med "$one") / $(med "$two") |"
    else cells="$cells $(med "$one") / $(med "$two") ($(ratio "$paper1" "$(med "$one")") / $(ratio "$paper2" "$(med "$two")")) |"; fi
  done
  mrows+=("$cells")
done
if [ ${#mrows[@]} -gt 0 ]; then
  echo
  echo "Modes: particle-steps/s, 1 / 2 threads, median of $runs runs (in brackets the cost per particle-step against the paper's mapping, 1 / 2 threads):"
  echo
  echo "| scene | points | steps | MAPPING PAPER (default) | MAPPING SMOOTH | MAPPING SMOOTH, ADVECT FLIP |"
  echo "|---|---|---|---|---|---|"
  printf '%s\n' "${mrows[@]}" | sed -E 's/e\+0?([0-9])/e\1/g'
fi
echo
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), load average before the runs $load_start, at the end $(cut -d' ' -f1-3 /proc/loadavg) (the benchmark's own runs count in it: 1 to 2)"
