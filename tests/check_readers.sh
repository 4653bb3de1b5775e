#!/usr/bin/env bash
# Program-level checks that a point table and a history load in the usual readers
# without hand work (decks/README.md, "Column names for other readers"):
#   - numpy.genfromtxt(FILE, names=True): the column names, and every row's values;
#   - pandas.read_csv(FILE, sep=r"\s+", comment="#"): the same;
#   - gnuplot's columnheader: a column plotted by name, titled by its name;
#   - the header keeps its contract: '#' lines with version, deck, units and the column
#     names, the columns starting "x y sxx syy sxy szz", each frame starting
#     "# step N time T", frames two blank lines apart.
# numpy and pandas are Debian's python3-numpy and python3-pandas (make test-deps).
#
# usage: tests/check_readers.sh EXE
# Last line "readers: N passed, M failed".
set -u

. "$(dirname "$0")/lib.sh"
need_program readers "$@"

tmp=$(mktemp -d) || exit 2
trap 'rm -rf "$tmp"' EXIT
passed=0 failed=0
pass() { passed=$((passed + 1)); }
fail() { echo "FAIL $1: $2"; failed=$((failed + 1)); }

cat >"$tmp/r.deck" <<'EOF'
TITLE readers
GRID 8 6 0.5
MATERIAL 1 ELASTIC E=2E7 NU=0.25 RHO=2000
MATERIAL 2 MOHR E=5E7 NU=0.3 RHO=1900 PHI=35 C=1E3 SOFTEN=0.5
CLUSTER 1 0 0 4 1
CLUSTER 2 0 1 2 2.5 PPC=3
FIX XY 0 0 4 0
WALL 1 3 0.5 3 2.5 -0.5 0
GRAVITY 0 -9.81
STEP 1E-4 30
OUTPUT POINTS p.txt EVERY 10
OUTPUT HISTORY h.txt EVERY 3
END
EOF
if ! timeout -k 5 60 "$exe" -q -o "$tmp/out" "$tmp/r.deck" >/dev/null 2>"$tmp/err"; then
    fail "run" "$(head -n 1 "$tmp/err")"
    echo "readers: $passed passed, $failed failed"
    exit 1
fi
pts=$tmp/out/p.txt hist=$tmp/out/h.txt

# --- the header contract ---
first=$(head -n 1 "$pts")
[ "$first" = "x y sxx syy sxy szz ep yielded mat id ux uy" ] && pass || fail "point table: first line" "'$first'"
first=$(head -n 1 "$hist")
[ "$first" = "step time ke mass_in mass_out w1_fx w1_fy w1_dx w1_dy unbal rx ry f1_rx f1_ry e_kin e_strain e_grav w_walls w_fixes w_gravity d_damping d_plastic energy_error parked packed" ] && pass || fail "history: first line" "'$first'"
for want in "^# lpfdm [0-9.]+ point table$" "^# deck: " "^# units: " "^# columns: x y sxx syy sxy szz " "^# step 0 time 0$"; do
    grep -q -E "$want" "$pts" && pass || fail "point table header" "no line matching '$want'"
done
for want in "^# lpfdm [0-9.]+ history$" "^# deck: " "^# units: " "^# step time ke mass_in mass_out "; do
    grep -q -E "$want" "$hist" && pass || fail "history header" "no line matching '$want'"
done
# every frame: two blank lines, then "# step N time T"
frames=$(grep -c '^# step [0-9]' "$pts")
gaps=$(awk 'prev2 == "" && prev1 == "" && NR > 2 && /^# step [0-9]/ { n++ } { prev2 = prev1; prev1 = $0 } END { print n + 0 }' "$pts")
[ "$frames" = 4 ] && [ "$gaps" = 3 ] && pass || fail "point table frames" "$frames frames, $gaps of them after two blank lines (expected 4 and 3)"

# --- numpy and pandas ---
python=""
for p in python3 /usr/bin/python3; do
    if "$p" -c 'import numpy, pandas' 2>/dev/null; then python=$p; break; fi
done
if [ -z "$python" ]; then
    fail "numpy, pandas" "no python3 with numpy and pandas (Debian packages python3-numpy python3-pandas)"
else
    "$python" - "$pts" "$hist" >"$tmp/result" 2>&1 <<'EOF'
import sys, warnings
import numpy, pandas
pts, hist = sys.argv[1], sys.argv[2]
def ok(name, cond, why=""):
    print(("ok " + name) if cond else ("FAIL %s: %s" % (name, why)))
def rows(path):  # the data rows, by hand: not '#', not blank, not the names line
    lines = open(path).read().splitlines()
    return lines[0].split(), [[float(v) for v in l.split()] for l in lines[1:] if l.strip() and not l.startswith("#")]
for path, kind in ((pts, "point table"), (hist, "history")):
    names, want = rows(path)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # a reader that has to guess does not pass
            a = numpy.genfromtxt(path, names=True)
        ok("numpy %s: names" % kind, list(a.dtype.names) == names, "%s" % (a.dtype.names,))
        got = [[float(a[n][k]) for n in names] for k in range(a.shape[0])]
        ok("numpy %s: values" % kind, got == want, "%d rows, %d expected; first %s, expected %s" % (len(got), len(want), got[:1], want[:1]))
        if kind == "point table":
            ok("numpy point table: frames one after the other", a.shape[0] == 4 * 172 and list(a["id"][:3]) == [0, 1, 2], "%d rows" % a.shape[0])
    except Exception as e:
        ok("numpy %s" % kind, False, " ".join(str(e).split())[:200])
    try:
        d = pandas.read_csv(path, sep=r"\s+", comment="#")
        ok("pandas %s: names" % kind, list(d.columns) == names, "%s" % list(d.columns))
        ok("pandas %s: numbers" % kind, all(str(t) in ("float64", "int64") for t in d.dtypes), "column types %s" % set(map(str, d.dtypes)))
        got = [[float(v) for v in r] for r in d.itertuples(index=False)]
        ok("pandas %s: values" % kind, got == want, "%d rows, %d expected" % (len(got), len(want)))
    except Exception as e:
        ok("pandas %s" % kind, False, " ".join(str(e).split())[:200])
EOF
    while read -r word rest; do
        case $word in
            ok) pass ;;
            FAIL) fail "${rest%%: *}" "${rest#*: }" ;;
            *) fail "python" "$word $rest" ;;
        esac
    done <"$tmp/result"
fi

# --- gnuplot's columnheader ---
if command -v gnuplot >/dev/null; then
    (cd "$tmp/out" && gnuplot -e "set table 't1'; plot 'h.txt' using 'time':'ke' title columnheader; set table 't2'; plot 'p.txt' index 0 using 'x':'syy' title columnheader" 2>"$tmp/gp.err")
    t=$(grep -m 1 'Curve title' "$tmp/out/t1" 2>/dev/null)
    n=$(grep -c ' i$' "$tmp/out/t1" 2>/dev/null)
    [ "$t" = '# Curve title: "ke"' ] && [ "$n" = 10 ] && pass || fail "gnuplot history: columnheader" "'$t', $n points (expected \"ke\", 10): $(head -n 1 "$tmp/gp.err")"
    ke=$(awk '/ i$/ { v = $2 } END { print v }' "$tmp/out/t1") want=$(awk '!/^#/ && $1 == 30 { print $3 }' "$hist")
    awk -v a="$ke" -v b="$want" 'BEGIN { d = a - b; exit !(b != 0 && d * d <= (1e-5 * b) ^ 2) }' && pass || fail "gnuplot history: values" "ke at step 30 is $ke, the table's $want"
    t=$(grep -m 1 'Curve title' "$tmp/out/t2" 2>/dev/null)
    n=$(grep -c ' i$' "$tmp/out/t2" 2>/dev/null)
    [ "$t" = '# Curve title: "syy"' ] && [ "$n" = 172 ] && pass || fail "gnuplot point table: columnheader" "'$t', $n points (expected \"syy\", 172)"
else
    fail "gnuplot" "not installed (Debian package gnuplot-nox)"
fi

echo "readers: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
