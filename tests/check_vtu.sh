#!/usr/bin/env bash
# Program-level checks of the VTU series (OUTPUT VTU; decks/README.md), read with
# python3's own XML parser, against the point table of the same run:
#   - NAME.pvd parses and lists one frame per point-table frame, with its time;
#   - each ASCII frame parses as VTK XML UnstructuredGrid; its point count and its
#     coordinates are the point table's frame's (the same digits), and so are stress
#     (a 9-component tensor), ep, yielded, material and id; displacement is the position
#     minus the frame-0 position of the same id; velocity is the next frame's position
#     minus this one's over dt (frames every step);
#   - NODES: NAME_nodes.pvd lists an ImageData frame of the lattice per frame; the node
#     masses add up to the history's mass inside, the wall's line moves at its velocity,
#     the fixed nodes not at all;
#   - the BINARY series: the XML before the appended block parses, and the raw arrays
#     decode to the ASCII series' values (points and nodes);
#   - the deck reader: BINARY on another output and an unknown kind are refused.
#
# usage: tests/check_vtu.sh EXE
# Last line "vtu: N passed, M failed".
set -u

. "$(dirname "$0")/lib.sh"
need_program vtu "$@"

tmp=$(mktemp -d) || exit 2
trap 'rm -rf "$tmp"' EXIT
passed=0 failed=0
pass() { passed=$((passed + 1)); }
fail() { echo "FAIL $1: $2"; failed=$((failed + 1)); }

# A Mohr-Coulomb heap on an elastic base pushed by a wall (two materials, yielding), a
# frame every step for 12 steps.
cat >"$tmp/a.deck" <<'EOF'
TITLE vtu
GRID 8 6 0.5
MATERIAL 1 ELASTIC E=2E7 NU=0.25 RHO=2000
MATERIAL 2 MOHR E=5E7 NU=0.3 RHO=1900 PHI=35 C=1E3 PSI=5 SOFTEN=0.5 SCATTER=0.2
CLUSTER 1 0 0 4 1
CLUSTER 2 0 1 2 2.5 PPC=3
FIX XY 0 0 4 0
WALL 1 3 0.5 3 2.5 -0.5 0
GRAVITY 0 -98.1
STEP 1E-4 12
OUTPUT POINTS p.txt EVERY 1
OUTPUT HISTORY h.txt EVERY 1
OUTPUT VTU heap NODES EVERY 1
END
EOF
sed -e 's/^OUTPUT VTU heap NODES EVERY 1/OUTPUT VTU heap BINARY NODES EVERY 1/' "$tmp/a.deck" >"$tmp/b.deck"
python=""
for p in python3 /usr/bin/python3; do
    if "$p" -c 'import xml.etree.ElementTree' 2>/dev/null; then python=$p; break; fi
done
if [ -z "$python" ]; then
    fail "python3" "no python3 to read the XML with (Debian package python3)"
    echo "vtu: $passed passed, $failed failed"
    exit 1
fi

for d in a b; do
    rm -rf "$tmp/$d"
    if timeout -k 5 120 "$exe" -q -o "$tmp/$d" "$tmp/$d.deck" >/dev/null 2>"$tmp/$d.err"; then pass; else fail "run $d.deck" "$(head -n 1 "$tmp/$d.err")"; fi
done

# The checks, one line each: "ok NAME" or "FAIL NAME: why".
"$python" - "$tmp" >"$tmp/result" 2>&1 <<'EOF'
import math, os, struct, sys
import xml.etree.ElementTree as ET
tmp = sys.argv[1]
dt = 1e-4
def ok(name, cond, why=""):
    print(("ok " + name) if cond else ("FAIL %s: %s" % (name, why)))

# The point table: frames as lists of rows (strings), with step and time.
frames = []
for line in open(os.path.join(tmp, "a", "p.txt")):
    w = line.split()
    if line.startswith("# step "):
        frames.append({"step": int(w[2]), "time": float(w[4]), "rows": []})
    elif w and not line.startswith("#") and w[0] != "x":
        frames[-1]["rows"].append(w)
ok("point table frames", len(frames) == 13, "%d frames, expected 13" % len(frames))

def series(d, name="heap"):
    pvd = ET.parse(os.path.join(tmp, d, name + ".pvd")).getroot()
    ds = pvd.findall("./Collection/DataSet")
    return pvd, [(x.get("file"), float(x.get("timestep"))) for x in ds]

def arrays_ascii(path):
    root = ET.parse(path).getroot()
    out = {}
    piece = root.find("./*/Piece")
    for a in root.iter("DataArray"):
        name = a.get("Name") or "Points"
        out[name] = (int(a.get("NumberOfComponents") or 1), a.text.split())
    return root, piece, out

def arrays_binary(path):
    data = open(path, "rb").read()
    at = data.index(b"<AppendedData")
    head = data[:at] + b"</VTKFile>\n"
    root = ET.fromstring(head)  # the XML before the raw block
    raw = data[data.index(b"_", at) + 1:]
    fmt = {"Float64": "d", "Int32": "i", "UInt8": "B", "Int64": "q"}
    out = {}
    for a in root.iter("DataArray"):
        if a.get("format") != "appended":
            continue
        off = int(a.get("offset"))
        (nbytes,) = struct.unpack_from("<Q", raw, off)
        f = fmt[a.get("type")]
        n = nbytes // struct.calcsize(f)
        vals = struct.unpack_from("<%d%s" % (n, f), raw, off + 8)
        out[a.get("Name") or "Points"] = (int(a.get("NumberOfComponents") or 1), [repr(v) for v in vals])
    return root, root.find("./*/Piece"), out

pvd, listed = series("a")
ok("pvd is a Collection", pvd.get("type") == "Collection", pvd.get("type"))
ok("pvd lists every frame", [f for f, _ in listed] == ["heap_%06d.vtu" % fr["step"] for fr in frames],
   "lists %s" % [f for f, _ in listed][:4])
ok("pvd times", all(abs(t - fr["time"]) <= 1e-12 for (_, t), fr in zip(listed, frames)), "times differ from the point table's")

first = {}
ascii_frames = []
for (file, t), fr in zip(listed, frames):
    root, piece, a = arrays_ascii(os.path.join(tmp, "a", file))
    ascii_frames.append(a)
    rows = fr["rows"]
    n = len(rows)
    name = file
    ok(name + " is an UnstructuredGrid", root.get("type") == "UnstructuredGrid", root.get("type"))
    ok(name + " point count", int(piece.get("NumberOfPoints")) == n and int(piece.get("NumberOfCells")) == n,
       "%s points, the table's frame has %d" % (piece.get("NumberOfPoints"), n))
    ok(name + " TimeValue", abs(float(a["TimeValue"][1][0]) - fr["time"]) <= 1e-12, a["TimeValue"][1][0])
    c, xyz = a["Points"]
    ok(name + " coordinates are the table's", c == 3 and all(xyz[3 * k] == r[0] and xyz[3 * k + 1] == r[1] and float(xyz[3 * k + 2]) == 0 for k, r in enumerate(rows)),
       "first point (%s, %s), table (%s, %s)" % (xyz[0], xyz[1], rows[0][0], rows[0][1]))
    c, s = a["stress"]
    close = lambda u, v: abs(float(u) - float(v)) <= 1e-6 * (abs(float(v)) + 1)
    ok(name + " stress tensor", c == 9 and all(close(s[9 * k], r[2]) and close(s[9 * k + 4], r[3]) and close(s[9 * k + 1], r[4]) and close(s[9 * k + 3], r[4])
                                               and close(s[9 * k + 8], r[5]) for k, r in enumerate(rows)), "differs from the table's sxx syy sxy szz")
    ok(name + " ep, yielded, material, id", all(close(a["ep"][1][k], r[6]) and a["yielded"][1][k] == r[7] and a["material"][1][k] == r[8] and a["id"][1][k] == r[9]
                                                for k, r in enumerate(rows)), "differ from the table's")
    cells = a["connectivity"][1], a["offsets"][1], a["types"][1]
    ok(name + " vertex cells", cells[0] == [str(k) for k in range(n)] and cells[1] == [str(k + 1) for k in range(n)] and cells[2] == ["1"] * n, "not one vertex per point")
    if not first:
        first = {r[9]: (float(r[0]), float(r[1])) for r in rows}
    d = a["displacement"][1]
    ok(name + " displacement", all(abs(float(d[3 * k]) - (float(r[0]) - first[r[9]][0])) <= 1e-8 and abs(float(d[3 * k + 1]) - (float(r[1]) - first[r[9]][1])) <= 1e-8
                                   for k, r in enumerate(rows)), "is not the position minus the frame-0 position")
def digit(x):  # the last of 9 significant digits of x
    return 10.0 ** (math.floor(math.log10(abs(x))) - 8) if x else 1e-300
# velocity of frame i: what each point moves to frame i + 1, over dt (points stay in order)
moved = 0
for i in range(len(frames) - 1):
    v = ascii_frames[i]["velocity"][1]
    now = {r[9]: (float(r[0]), float(r[1])) for r in frames[i]["rows"]}
    nxt = {r[9]: (float(r[0]), float(r[1])) for r in frames[i + 1]["rows"]}
    bad = 0
    for k, r in enumerate(frames[i]["rows"]):
        if r[9] not in nxt:
            continue
        for c in (0, 1):
            want = (nxt[r[9]][c] - now[r[9]][c]) / dt
            moved += want != 0
            # the table has 9 digits: a step's motion is known to the last digit of each position
            if abs(float(v[3 * k + c]) - want) > (digit(now[r[9]][c]) + digit(nxt[r[9]][c])) / dt + 1e-6 * abs(want):
                bad += 1
    ok("heap_%06d.vtu velocity" % frames[i]["step"], bad == 0, "%d components are not the next step's motion over dt" % bad)
ok("the points move", moved > 0, "no point moved")

# The lattice's series (NODES): 9 x 7 nodes of 0.5 m.
mass_in = {}
for line in open(os.path.join(tmp, "a", "h.txt")):
    w = line.split()
    if w and not line.startswith("#") and w[0] != "step":
        mass_in[int(w[0])] = float(w[3])
_, nodes = series("a", "heap_nodes")
ok("nodes pvd lists every frame", [f for f, _ in nodes] == ["heap_nodes_%06d.vti" % fr["step"] for fr in frames] and
   [t for _, t in nodes] == [t for _, t in listed], "lists %s" % [f for f, _ in nodes][:4])
node_frames = []
for (file, t), fr in zip(nodes, frames):
    root, piece, a = arrays_ascii(os.path.join(tmp, "a", file))
    node_frames.append(a)
    img = root.find("./ImageData")
    ok(file + " is the lattice", root.get("type") == "ImageData" and img.get("WholeExtent") == "0 8 0 6 0 0" and img.get("Spacing").split() == ["0.5"] * 3
       and piece.get("Extent") == "0 8 0 6 0 0", "%s %s" % (root.get("type"), img.attrib if img is not None else None))
    m = [float(v) for v in a["mass"][1]]
    v = [float(x) for x in a["velocity"][1]]
    ok(file + " arrays", len(m) == 63 and len(v) == 189 and len(a["force"][1]) == 189, "%d masses, %d velocity values" % (len(m), len(v)))
    if fr["step"] > 0:
        ok(file + " mass", abs(sum(m) - mass_in[fr["step"]]) <= 1e-9 * mass_in[fr["step"]], "nodes %r, history %r" % (sum(m), mass_in[fr["step"]]))
        # The wall (inside the base layer) drives the material line it started on, x = 3 - 0.5 t
        # with t the time before the step, interpolated between the columns of nodes either side.
        at = (3 - 0.5 * 1e-4 * (fr["step"] - 1)) / 0.5
        lo = int(at + 1e-9); f = at - lo if at - lo > 1e-9 else 0.0
        node = lambda i, j, c: v[3 * (j * 9 + i) + c]
        wall = [((1 - f) * node(lo, j, c) + (f * node(lo + 1, j, c) if f > 0 else 0.0)) for j in range(1, 6) for c in (0, 1)]
        ok(file + " wall's line at the wall's velocity", all(abs(w - (-0.5 if k % 2 == 0 else 0.0)) <= 1e-8 for k, w in enumerate(wall)), "%s" % wall)
        ok(file + " fixed nodes still", all(v[3 * i] == 0 and v[3 * i + 1] == 0 for i in range(9)), "%s" % v[:27])

# The BINARY series against the ASCII one.
_, listed_b = series("b")
ok("binary pvd", listed_b == listed, "lists other frames")
for (file, _), a in zip(listed_b, ascii_frames):
    root, piece, b = arrays_binary(os.path.join(tmp, "b", file))
    same = True
    why = ""
    for name in ["Points", "stress", "ep", "yielded", "material", "velocity", "displacement", "id", "connectivity", "offsets", "types"]:
        ca, va = a[name]
        cb, vb = b.get(name, (0, []))
        if ca != cb or len(va) != len(vb) or any(abs(float(x) - float(y)) > 1e-8 * (abs(float(y)) + 1e-6) for x, y in zip(va, vb)):
            same = False
            why = name
            break
    ok(file + " binary = ascii", same, "array %s differs" % why)
_, nodes_b = series("b", "heap_nodes")
ok("binary nodes pvd", nodes_b == nodes, "lists other frames")
for (file, _), a in zip(nodes_b, node_frames):
    _, _, b = arrays_binary(os.path.join(tmp, "b", file))
    why = [name for name in ("mass", "velocity", "force") if len(a[name][1]) != len(b.get(name, (0, []))[1]) or
           any(abs(float(x) - float(y)) > 1e-8 * (abs(float(y)) + 1e-6) for x, y in zip(a[name][1], b[name][1]))]
    ok(file + " binary = ascii", not why, "arrays %s differ" % why)
EOF
while read -r word rest; do
    case $word in
        ok) pass ;;
        FAIL) fail "${rest%%: *}" "${rest#*: }" ;;
        *) fail "python" "$word $rest" ;;
    esac
done <"$tmp/result"

# The deck reader.
printf 'GRID 4 4 1\nMATERIAL 1 ELASTIC E=1E7 NU=0.3 RHO=2000\nCLUSTER 1 0 0 2 2\nSTEP 1E-4 2\nOUTPUT HISTORY h.txt NODES\n' >"$tmp/e.deck"
"$exe" -q -o "$tmp/e" "$tmp/e.deck" >/dev/null 2>"$tmp/e.err"; rc=$?
if [ $rc -eq 2 ] && grep -q "e.deck:5:22: error: NODES is a word of OUTPUT VTU only" "$tmp/e.err" && [ ! -e "$tmp/e" ]; then pass
else fail "NODES on a history" "exit status $rc: $(head -n 1 "$tmp/e.err")"; fi
printf 'GRID 4 4 1\nMATERIAL 1 ELASTIC E=1E7 NU=0.3 RHO=2000\nCLUSTER 1 0 0 2 2\nSTEP 1E-4 2\nOUTPUT POINTS p.txt BINARY\n' >"$tmp/c.deck"
printf 'GRID 4 4 1\nMATERIAL 1 ELASTIC E=1E7 NU=0.3 RHO=2000\nCLUSTER 1 0 0 2 2\nSTEP 1E-4 2\nOUTPUT VTX v\n' >"$tmp/d.deck"
"$exe" -q -o "$tmp/c" "$tmp/c.deck" >/dev/null 2>"$tmp/c.err"; rc=$?
if [ $rc -eq 2 ] && grep -q "c.deck:5:21: error: BINARY is a word of OUTPUT VTU only" "$tmp/c.err" && [ ! -e "$tmp/c" ]; then pass
else fail "BINARY on a point table" "exit status $rc: $(head -n 1 "$tmp/c.err")"; fi
"$exe" -q -o "$tmp/d" "$tmp/d.deck" >/dev/null 2>"$tmp/d.err"; rc=$?
if [ $rc -eq 2 ] && grep -q "d.deck:5:8: error: unknown output 'VTX' (POINTS, HISTORY, VTU or STATE) (did you mean VTU?)" "$tmp/d.err"; then pass
else fail "unknown output kind" "exit status $rc: $(head -n 1 "$tmp/d.err")"; fi

echo "vtu: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
