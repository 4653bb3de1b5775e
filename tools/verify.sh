#!/usr/bin/env bash
# Verification ladder: runs the decks/verify_*.deck cases (and column.deck) at a ladder of
# lattice resolutions (--refine 1, 2, 4) and points per cell (1x1, 2x2, 4x4 where it
# matters), measures each against its closed-form or published reference, and writes
#   OUT/verify.tsv          case, cells over the characteristic length, points per cell,
#                           steps, wall time [s], particle-steps/s, measured, reference,
#                           relative error, and the CPU time of the runs [s] (user + system,
#                           which other jobs on a shared machine disturb far less)
#   OUT/verify_orders.tsv   observed order of convergence between successive rungs
#   OUT/verify_collapse.tsv OUT/verify_hopper.tsv   per-run details of those two cases
#   OUT/verify_work_precision.png  error against wall time (log-log), one line per case
#   OUT/verify_convergence.png     error against cell size, with the observed orders
#   OUT/verify_runout.png          granular collapse against the published laws
#   OUT/verify_hopper.png          discharge rate against slot width
#
# Usage: bash tools/verify.sh ./lpfdm out [case ...]
#   cases: column column_stiff ringing ringing_stiff psc cut footing collapse hopper
#   VERIFY_REPEAT=3  wall time = median of this many runs (runs longer than
#   VERIFY_LONG=20   seconds are timed once: their noise is small against their length)
#   VERIFY_THREADS=1 threads per run (--threads); one thread measures the method, not the
#                    machine's other jobs (a thread waiting at a barrier for a core that
#                    another job holds makes a shared machine's times erratic)
#   VERIFY_APPEND=1  add rows to an existing OUT/verify.tsv (e.g. after one case) instead
#                    of starting it anew; orders and pictures are made from all its rows
#   VERIFY_MAPPING=SMOOTH  run each deck with MAPPING SMOOTH (a copy of the deck with the
#                    card added); the rows' cases end in _smooth (make verify runs the
#                    column, PSC and footing both ways, for the work-precision diagram)
#   VERIFY_ADVECT=FLIP  and with ADVECT FLIP (needs VERIFY_MAPPING=SMOOTH); the rows'
#                    cases end in _smooth_flip (make verify runs those three cases so too)
#   VERIFY_WINDOW=t  run each deck with --set DAMPING.WINDOW=t (local damping about each
#                    node's mean motion); the rows' cases end in _window (make verify runs
#                    the compression so, in each mode)
# A run is timed from the program's own summary line (the time of the steps and of the
# output written during them, without start-up); the cut's time is the sum of its
# bisection runs, each timed once; the hopper's the sum of its four slot widths.
set -u
exe=${1:-./lpfdm}
out=${2:-out}
shift 2 2>/dev/null || shift $#
cases=${*:-column column_stiff ringing ringing_stiff psc cut footing collapse hopper}
repeat=${VERIFY_REPEAT:-3}
long=${VERIFY_LONG:-20}
threads=${VERIFY_THREADS:-1}
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/.." && pwd)
decks=$root/decks
mapping=${VERIFY_MAPPING:-PAPER}
advect=${VERIFY_ADVECT:-EQ12}
window=${VERIFY_WINDOW:-}
suffix=$([ "$mapping" = PAPER ] || echo "_$(tr 'A-Z' 'a-z' <<<"$mapping")")$([ "$advect" = EQ12 ] || echo "_$(tr 'A-Z' 'a-z' <<<"$advect")")${window:+_window}
ladders=$out/verify
work=$out/verify$suffix
mkdir -p "$work" "$ladders"
tsv=$out/verify.tsv
command -v "$exe" >/dev/null 2>&1 || [ -x "$exe" ] || { echo "verify: no program $exe" >&2; exit 2; }
if [ ! -s "$tsv" ] || [ "${VERIFY_APPEND:-0}" = 0 ]; then
    printf 'case\tcells\tppc\tsteps\twall_s\tpsteps_per_s\tmeasured\treference\trel_error\tcpu_s\n' >"$tsv"
    printf 'a\tcells\tppc\trunout\tfarthest\tmass_out_fraction\n' >"$out/verify_collapse.tsv"
    printf 'cells_per_L0\tppc\tD_m\tD_cells\trate_kg_per_s_m\tbeverloo_C\n' >"$out/verify_hopper.tsv"
fi

# ------------------------------------------------------------------ running ---

# run DIR DECK [options...]: runs the program, timed as the median of $repeat runs
# (RUN_TIMES overrides; once if the first run takes longer than $long s). Sets STEPS,
# WALL (s, of the steps and the output written during them, from the program's summary),
# CPU (s, user + system of the whole process, median) and PSTEPS (particle-steps).
run() {
    local dir=$1 deck=$2; shift 2
    local line walls=() cpus=() k n times=${RUN_TIMES:-$repeat} TIMEFORMAT='%U %S'
    mkdir -p "$dir"
    if [ "$mapping" != PAPER ] || [ "$advect" != EQ12 ]; then  # the deck with MAPPING and ADVECT cards (before END, if any)
        awk -v m="MAPPING $mapping" -v a="ADVECT $advect" '/^[ \t]*[Ee][Nn][Dd]([ \t!]|$)/ && !done { print m; print a; done = 1 } { print } END { if (!done) { print m; print a } }' "$deck" >"$dir/$(basename "$deck")"
        deck=$dir/$(basename "$deck")
    fi
    for ((k = 0; k < times; k++)); do
        { time "$exe" --threads "$threads" -o "$dir" ${window:+--set DAMPING.WINDOW=$window} "$@" "$deck" >"$dir/stdout.txt" 2>"$dir/stderr.txt"; } 2>"$dir/time.txt"
        line=$(grep '^lpfdm: [0-9]* steps' "$dir/stdout.txt")
        if [ -z "$line" ]; then
            echo "verify: run failed: $exe -o $dir $* $deck" >&2
            sed 's/^/  /' "$dir/stderr.txt" >&2
            STEPS=0 WALL=nan PSTEPS=0 CPU=nan
            return 1
        fi
        # lpfdm: N steps, P points, T s, R particle-steps/s; ...
        n=$(awk '{print $2}' <<<"$line")
        walls+=("$(awk '{print $6}' <<<"$line")")
        cpus+=("$(awk '{print $1 + $2}' "$dir/time.txt")")
        [ "$k" = 0 ] && PSTEPS=$(awk '{print $6 * $8}' <<<"$line")
        awk -v w="${walls[0]}" -v l="$long" 'BEGIN { exit !(w > l) }' && break
    done
    STEPS=$n
    WALL=$(printf '%s\n' "${walls[@]}" | sort -g | awk '{w[NR] = $1} END {print w[int((NR + 1) / 2)]}')
    CPU=$(printf '%s\n' "${cpus[@]}" | sort -g | awk '{w[NR] = $1} END {print w[int((NR + 1) / 2)]}')
}

# row CASE CELLS PPC STEPS WALL PSTEPS MEASURED REFERENCE [ERROR]
# (error default: measured / reference - 1; CPU time from $CPU)
row() {
    awk -v c="$1$suffix" -v n="$2" -v p="$3" -v s="$4" -v w="$5" -v ps="$6" -v m="$7" -v r="$8" -v e="${9:-}" -v cpu="$CPU" 'BEGIN {
        if (e == "") e = (m == "nan" || r == 0) ? "nan" : m / r - 1
        printf "%s\t%d\t%d\t%d\t%.4g\t%.4g\t%.7g\t%.7g\t%.4g\t%.4g\n", c, n, p, s, w, (w > 0 ? ps / w : 0), m, r, e, cpu }' >>"$tsv"
    printf '%-22s cells %3d  ppc %d  %8.2f s  measured %-12s reference %-12s error %s\n' "$1$suffix" "$2" "$3" "$5" "$7" "$8" \
        "$(tail -1 "$tsv" | cut -f9)"
}

# ------------------------------------------------------------------- cases ---

# Confined column at rest (column.deck, and the small-strain variant): sigma_yy over
# the points (relative L2 error) and the settlement of the top row of points.
column_case() {  # NAME DECK POINTS_FILE E
    local name=$1 deck=$2 pts=$3 E=$4 r p dir m
    for r in 1 2 4; do
        for p in 1 2 4; do
            dir=$work/$name-r$r-p$p
            run "$dir" "$deck" --refine $r --set CLUSTER1.PPC=$p || continue
            m=$(awk -v H=12 -v rho=2000 -v g=9.81 -v E="$E" -v nu=0.25 -f "$here/verify_column.awk" "$dir/$pts")
            set -- $m
            row "${name}_syy" $((24 * r)) $p "$STEPS" "$WALL" "$PSTEPS" "$1" "$2" "$3"
            row "${name}_settlement" $((24 * r)) $p "$STEPS" "$WALL" "$PSTEPS" "$4" "$5"
        done
    done
}

# Ringing column: period against 4H/c_p, first peak against twice the static settlement.
ringing_case() {  # NAME DECK POINTS_FILE E
    local name=$1 deck=$2 pts=$3 E=$4 r p dir m T
    T=$(awk -v E="$E" 'BEGIN { M = E * 0.75 / (1.25 * 0.5); print 4 * 12 / sqrt(M / 2000) }')
    for r in 1 2 4; do
        for p in 1 2 4; do
            [ $r = 4 ] && [ $p = 4 ] && continue  # 6144 points x 140 frames: the table, not the run, would be timed
            dir=$work/$name-r$r-p$p
            run "$dir" "$deck" --refine $r --set CLUSTER1.PPC=$p || continue
            m=$(awk -v H=12 -v rho=2000 -v g=9.81 -v E="$E" -v nu=0.25 -f "$here/verify_ringing.awk" "$dir/$pts")
            set -- $m
            row "${name}_period" $((24 * r)) $p "$STEPS" "$WALL" "$PSTEPS" "$1" "$T"
            row "${name}_peak" $((24 * r)) $p "$STEPS" "$WALL" "$PSTEPS" "$2" 2
        done
    done
}

# A rigid wall pressed into Mohr-Coulomb soil: the wall's mean pressure from the deck's
# history (verify_wall.awk with the awk variables given) against a closed-form limit,
# at --refine 1, 2, 4 and 1, 2, 4 points per cell (--refine 4 with 2 only).
#   wall_case NAME DECK CELLS_AT_REFINE_1 "CLUSTER IDS" REFERENCE AWK_OPTIONS...
wall_case() {
    local name=$1 deck=$2 cells=$3 clusters=$4 ref=$5 r p k dir m sets
    shift 5
    for r in 1 2 4; do
        for p in 1 2 4; do
            [ $r = 4 ] && [ $p != 2 ] && continue
            dir=$work/${name%%_*}-r$r-p$p
            sets=()
            for k in $clusters; do sets+=(--set "CLUSTER$k.PPC=$p"); done
            run "$dir" "$deck" --refine $r "${sets[@]}" || continue
            m=$(awk "$@" -f "$here/verify_wall.awk" "$dir/$(basename "$deck" .deck)_history.txt")
            row "$name" $((cells * r)) $p "$STEPS" "$WALL" "$PSTEPS" "${m%% *}" "$ref"
        done
    done
}

# Plane-strain compression: mean deviator stress on the yield plateau (wall travel
# from 0.15 mm to 0.3 mm, axial strain 0.075 % to 0.15 %) against 2 c tan(45 + phi/2).
psc_case() {
    wall_case psc_q "$decks/verify_psc.deck" 5 1 \
        "$(awk 'BEGIN { print 2 * 9800 * sin((45 + 28.648 / 2) * atan2(1, 1) / 45) / cos((45 + 28.648 / 2) * atan2(1, 1) / 45) }')" \
        -v wall=1 -v width=0.1 -v from=0.00015
}

# Strip footing: q / c at 1.4 cm of settlement against 2 + pi.
footing_case() {
    wall_case footing_q_over_c "$decks/verify_footing.deck" 4 "1 2" "$(awk 'BEGIN { print 2 + 4 * atan2(1, 1) }')" \
        -v wall=1 -v width=1 -v scale=20000 -v at=0.014
}

# Vertical cut: bisection on gravity between 0.85 and 1.25 times the reference's
# critical gravity, six halvings (final bracket 0.6 % of g wide); gamma H_c / c from
# the middle of the last bracket.
cut_case() {
    local r p dir lo hi g k m steps wall ps cpu ref gref failed
    ref=$(awk 'BEGIN { d = atan2(1, 1) / 45; print 3.83 * sin((45 + 28.648 / 2) * d) / cos((45 + 28.648 / 2) * d) }')
    gref=$(awk -v n="$ref" 'BEGIN { print n * 9800 / (1700 * 4) }')
    for r in 1 2 4; do
        for p in 1 2 4; do
            [ $r != 1 ] && [ $p != 2 ] && continue
            lo=$(awk -v g="$gref" 'BEGIN { print 0.85 * g }'); hi=$(awk -v g="$gref" 'BEGIN { print 1.25 * g }')
            steps=0 wall=0 ps=0 cpu=0 failed=0
            for ((k = 0; k < 6; k++)); do
                g=$(awk -v a="$lo" -v b="$hi" 'BEGIN { printf "%.6f", (a + b) / 2 }')
                dir=$work/cut-r$r-p$p
                RUN_TIMES=1 run "$dir" "$decks/verify_cut.deck" --refine $r --set CLUSTER1.PPC=$p --set GRAVITY.GY=-"$g" || { failed=1; break; }
                steps=$((steps + STEPS)); wall=$(awk -v a="$wall" -v b="$WALL" 'BEGIN { print a + b }')
                ps=$(awk -v a="$ps" -v b="$PSTEPS" 'BEGIN { print a + b }'); cpu=$(awk -v a="$cpu" -v b="$CPU" 'BEGIN { print a + b }')
                m=$(awk -f "$here/verify_cut.awk" "$dir/verify_cut_history.txt")
                echo "  cut r$r ppc $p: g = $g m/s2: $([ "${m%% *}" = 1 ] && echo stands || echo collapses) (unbal $m)"
                if [ "${m%% *}" = 1 ]; then lo=$g; else hi=$g; fi
            done
            m=$(awk -v a="$lo" -v b="$hi" 'BEGIN { printf "%.6g", 1700 * (a + b) / 2 * 4 / 9800 }')
            [ $failed = 1 ] && m=nan
            CPU=$cpu row cut_gammaHc_over_c $((8 * r)) $p "$steps" "$wall" "$ps" "$m" "$ref"
        done
    done
}

# Granular collapse: run-out against Lube et al. (2005): 1.2 a up to a = 1.8 and
# 1.9 a^(2/3) from a = 2.8 (the branch nearer in a between them).
collapse_case() {
    local a r p dir m ref mo
    for a in 0.5 1 2 4; do
        ref=$(awk -v a=$a 'BEGIN { print (a <= 2.3) ? 1.2 * a : 1.9 * a ^ (2 / 3) }')
        for r in 1 2 4; do
            for p in 1 2 4; do
                [ $r != 1 ] && [ $p != 2 ] && continue
                dir=$work/collapse-a$a-r$r-p$p
                run "$dir" "$decks/verify_collapse.deck" --refine $r --set CLUSTER1.PPC=$p --set CLUSTER1.Y1=$a || continue
                m=$(awk -f "$here/verify_front.awk" "$dir/verify_collapse_points.txt")
                mo=$(awk '/^# step/ { for (i = 2; i <= NF; i++) c[$i] = i - 1; next } /^#/ || NF == 0 || $1 == "step" { next }
                          { f = $c["mass_out"] / ($c["mass_in"] + $c["mass_out"]) } END { printf "%.4g", f }' "$dir/verify_collapse_history.txt")
                set -- $m
                row "collapse_a$a" $((8 * r)) $p "$STEPS" "$WALL" "$PSTEPS" "$(awk -v f="$1" 'BEGIN { print f - 1 }')" "$ref"
                printf '%s\t%d\t%d\t%.5g\t%.5g\t%s\n' $a $((8 * r)) $p "$(awk -v f="$1" 'BEGIN { print f - 1 }')" \
                    "$(awk -v f="$2" 'BEGIN { print f - 1 }')" "$mo" >>"$out/verify_collapse.tsv"
            done
        done
    done
}

# Discharge through a slot of 2, 4, 6, 8 cells (of the coarsest lattice): the exponent
# of the steady rate (slope of the outflow over 1 s to 2 s) against D, against 3/2.
hopper_case() {
    local r p d D dir m steps wall ps cpu fit failed
    for r in 1 2; do
        for p in 1 2 4; do
            [ $r != 1 ] && [ $p != 2 ] && continue
            steps=0 wall=0 ps=0 cpu=0 failed=0
            : >"$work/hopper-r$r-p$p.dat"
            for d in 2 4 6 8; do
                D=$(awk -v d=$d 'BEGIN { print d * 0.125 }')
                dir=$work/hopper-r$r-p$p-d$d
                run "$dir" "$decks/verify_hopper.deck" --refine $r --set CLUSTER1.PPC=$p \
                    --set FIX1.X1="$(awk -v D="$D" 'BEGIN { print 3 - D / 2 }')" \
                    --set FIX2.X0="$(awk -v D="$D" 'BEGIN { print 3 + D / 2 }')" || { failed=1; continue; }
                steps=$((steps + STEPS)); wall=$(awk -v a="$wall" -v b="$WALL" 'BEGIN { print a + b }')
                ps=$(awk -v a="$ps" -v b="$PSTEPS" 'BEGIN { print a + b }'); cpu=$(awk -v a="$cpu" -v b="$CPU" 'BEGIN { print a + b }')
                m=$(awk -v from=1 -v to=2 -f "$here/verify_rate.awk" "$dir/verify_hopper_history.txt")
                echo "$D ${m%% *}" >>"$work/hopper-r$r-p$p.dat"
                printf '%d\t%d\t%s\t%d\t%.6g\t%.4g\n' $((8 * r)) $p "$D" $((d * r)) "${m%% *}" \
                    "$(awk -v q="${m%% *}" -v D="$D" 'BEGIN { print q / (2000 * sqrt(9.81) * D ^ 1.5) }')" >>"$out/verify_hopper.tsv"
            done
            fit=$(awk -f "$here/verify_fit.awk" "$work/hopper-r$r-p$p.dat")
            [ $failed = 1 ] && fit=nan
            CPU=$cpu row hopper_exponent $((2 * r)) $p "$steps" "$wall" "$ps" "${fit%% *}" 1.5
        done
    done
}

for c in $cases; do
    echo "== $c"
    case $c in
    column) column_case column "$decks/column.deck" column_points.txt 2e7 ;;
    column_stiff) column_case column_stiff "$decks/verify_column_stiff.deck" verify_column_stiff_points.txt 2e9 ;;
    ringing) ringing_case ringing "$decks/verify_ringing.deck" verify_ringing_points.txt 2e7 ;;
    ringing_stiff) ringing_case ringing_stiff "$decks/verify_ringing_stiff.deck" verify_ringing_stiff_points.txt 2e9 ;;
    psc) psc_case ;;
    cut) cut_case ;;
    footing) footing_case ;;
    collapse) collapse_case ;;
    hopper) hopper_case ;;
    *) echo "verify: unknown case $c" >&2 ;;
    esac
done

# ------------------------------------------------------------ orders, plots ---

# Observed order between successive rungs of the same case and points per cell:
# p = log(e1 / e2) / log(n2 / n1) with e the relative error and n the cells over the
# characteristic length. For the collapse (no exact reference) also the self-convergence
# order from three rungs, log(|m1 - m2| / |m2 - m3|) / log 2, as case "<case>_self".
printf 'case\tppc\tcells_from\tcells_to\torder\n' >"$out/verify_orders.tsv"
awk -F'\t' 'NR > 1 {
        k = $1 SUBSEP $3; n[k]++; c[k, n[k]] = $2; e[k, n[k]] = ($9 < 0 ? -$9 : $9); m[k, n[k]] = $7
        if (!(k in seen)) { seen[k] = 1; order[++nk] = k }
    }
    END {
        for (q = 1; q <= nk; q++) {
            k = order[q]; split(k, kp, SUBSEP)
            for (i = 2; i <= n[k]; i++)
                if (e[k, i - 1] > 0 && e[k, i] > 0 && c[k, i] > c[k, i - 1])
                    printf "%s\t%s\t%d\t%d\t%.3g\n", kp[1], kp[2], c[k, i - 1], c[k, i], log(e[k, i - 1] / e[k, i]) / log(c[k, i] / c[k, i - 1])
            if (kp[1] ~ /^collapse/ && n[k] >= 3) {
                d1 = m[k, 1] - m[k, 2]; d2 = m[k, 2] - m[k, 3]
                if (d1 != 0 && d2 != 0) printf "%s_self\t%s\t%d\t%d\t%.3g\n", kp[1], kp[2], c[k, 1], c[k, 3], log((d1 < 0 ? -d1 : d1) / (d2 < 0 ? -d2 : d2)) / log(2)
            }
        }
    }' "$tsv" >>"$out/verify_orders.tsv"

if command -v gnuplot >/dev/null 2>&1; then
    # One data block per case (two points per cell only: the refinement ladder).
    awk -F'\t' 'NR > 1 && $3 == 2 { e = ($9 < 0 ? -$9 : $9); if (e > 0) print $1, $2, $5, e, $7 > (dir "/ladder_" $1 ".dat") }' dir="$ladders" "$tsv"
    # Left out of the two diagrams: the collapse (no exact reference; it has its own picture)
    # and the stiff column's settlement (its error is below the point table's 9 digits).
    list=$(awk -F'\t' 'NR > 1 && $3 == 2 && $1 !~ /^collapse|^column_stiff_settlement/ && !s[$1]++ { printf "%s ", $1 }' "$tsv")
    orders=$(awk -F'\t' 'NR > 1 && $2 == 2 && $1 !~ /_self$/ { o[$1] = $5 } END { for (k in o) printf "%s=%s ", k, o[k] }' "$out/verify_orders.tsv")
    gnuplot -e "dir='$ladders'; cases='$list'; orders='$orders'; out='$out/verify_work_precision.png'" "$here/verify_work_precision.gp"
    gnuplot -e "dir='$ladders'; cases='$list'; orders='$orders'; out='$out/verify_convergence.png'" "$here/verify_convergence.gp"
    [ "$(wc -l <"$out/verify_collapse.tsv")" -gt 1 ] && gnuplot -e "in='$out/verify_collapse.tsv'; out='$out/verify_runout.png'" "$here/verify_runout.gp"
    [ "$(wc -l <"$out/verify_hopper.tsv")" -gt 1 ] && gnuplot -e "in='$out/verify_hopper.tsv'; out='$out/verify_hopper.png'" "$here/verify_hopper.gp"
else
    echo "verify: gnuplot not found: no pictures" >&2
fi
echo "verify: $tsv ($(($(wc -l <"$tsv") - 1)) rows), $out/verify_orders.tsv; pictures in $out/"
column -t -s $'\t' "$out/verify_orders.tsv" 2>/dev/null || cat "$out/verify_orders.tsv"
