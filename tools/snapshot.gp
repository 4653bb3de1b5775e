# snapshot.gp -- one frame of an lpfdm point table as a PNG.
#
# Usage:
#   gnuplot -e "in='points.dat'; out='snap.png'; frame=-1" tools/snapshot.gp
#
# Variables (all optional):
#   in      point table                      default 'points.dat'
#   out     PNG file to write                default 'snapshot.png'
#   frame   frame number, 0 = initial state, -1 = last frame   default -1
#   title   text put before "step N, t = T s"                   default ''
#   color   the column that colours the points: a name of the table's
#           "# columns:" line (x y sxx syy sxy szz ep yielded mat id ux uy) or
#           its number, e.g. color='syy' or color=4, or u: the size of the
#           displacement, sqrt(ux^2 + uy^2)                  default 'ep'
#   cbmin, cbmax  ends of the colour scale, each may be set alone
#           (default: 0 to epmax for ep, else the frame's range)
#   epmax   top of the colour scale for ep (plastic shear strain) default 0.5
#   keypos  where the key goes inside the plot, e.g. 'top right'
#           default: the corner of the plot with the fewest points; a plot
#           too narrow or too low for the key has it below, outside
#   ptsize  dot size (gnuplot pointsize; 1 is a dot 6 px across)
#           default: 0.85 of the points' spacing in frame 0, so that the
#           material reads as a surface and a band as a band
#   xmin, xmax, ymin, ymax   axis limits in m, each may be set alone;
#           unset ends come from the frame's extent and a 2 % margin
#   size    canvas size in pixels "W,H"
#           default: fitted to the plot, at most 1200 x 800 (at least 480 x 360)
#
# Both axes have one scale and tics every same number of metres, spaced so
# that their labels do not touch.
# Points are coloured by ep (column 7) unless color names another column;
# points that have yielded (column 8 = 1) get a thin dark ring so softened
# material can be told apart from elastic material of the same colour.

if (!exists("in"))     in = 'points.dat'
if (!exists("out"))    out = 'snapshot.png'
if (!exists("frame"))  frame = -1
if (!exists("title"))  title = ''
if (!exists("epmax"))  epmax = 0.5
if (!exists("color"))  color = 'ep'

# gnuplot only warns about an unreadable file and then draws an empty
# picture, so stop here with an error instead.
if (system(sprintf("test -r '%s' && echo ok", in)) ne "ok") {
    exit error sprintf("snapshot.gp: cannot read point table '%s'", in)
}

# Frames are gnuplot data blocks (two blank lines apart); count them the
# same way to resolve frame -1 and to find the "# step N time T" line.
# Output: resolved frame, number of frames, step, time.
info = system(sprintf("awk -v f=%d 'BEGIN {b = 0} /^[ \t]*$/ {nb++; next} {if (nb >= 2) b++; nb = 0} /^#[ \t]*step[ \t]/ {s[b] = $3; t[b] = $5} END {if (f < 0) f = b; print f, b + 1, ((f in s) ? s[f] \" \" t[f] : \"? ?\")}' '%s'", frame, in))
frame = int(word(info, 1))
if (frame > int(word(info, 2)) - 1) {
    exit error sprintf("snapshot.gp: frame %d not in '%s' (frames 0..%d)", frame, in, int(word(info, 2)) - 1)
}
label = sprintf("step %s, t = %s s", word(info, 3), word(info, 4))
if (strlen(title) > 0) label = title . " -- " . label

# Axis ranges: the frame's extent with a margin of 2 % of it on each side
# (so edge points stay off the border), or the limits given.
stats in index frame using 1:2 name 'F' nooutput
if (!exists("F_records")) {
    exit error sprintf("snapshot.gp: no points in frame %d of '%s'", frame, in)
}
ext = (F_max_x - F_min_x > F_max_y - F_min_y) ? F_max_x - F_min_x : F_max_y - F_min_y
if (ext <= 0) ext = 1
x0 = F_min_x - 0.02 * (F_max_x - F_min_x) - 0.002 * ext
x1 = F_max_x + 0.02 * (F_max_x - F_min_x) + 0.002 * ext
y0 = F_min_y - 0.02 * (F_max_y - F_min_y) - 0.002 * ext
y1 = F_max_y + 0.02 * (F_max_y - F_min_y) + 0.002 * ext
if (exists("xmin")) x0 = xmin
if (exists("xmax")) x1 = xmax
if (exists("ymin")) y0 = ymin
if (exists("ymax")) y1 = ymax
if (x1 <= x0 || y1 <= y0) {
    exit error sprintf("snapshot.gp: empty axis range x %g..%g, y %g..%g", x0, x1, y0, y1)
}

# Layout in pixels: margins for tic labels and axis labels (left, bottom),
# the title (top) and the colour box with its labels (right); the plot has
# one scale sc [px/m] on both axes. Unless size is given the canvas is cut
# to the plot (at most 1200 x 800), so a tall column is not a strip in a
# wide picture. The key goes below the plot (30 px more) when the plot is
# too narrow or too low to hold it inside.
ml = 90; mr = 190; mt = 50; mb = 60
min(a, b) = (a < b) ? a : b
max(a, b) = (a > b) ? a : b
if (exists("size")) {
    W = int(real(size[1:strstrt(size, ",") - 1])); H = int(real(size[strstrt(size, ",") + 1:]))
} else {
    W = 1200; H = 800
}
scale(b) = min((W - ml - mr) / (x1 - x0), (H - mt - b) / (y1 - y0))   # b: bottom margin
sc = scale(mb)
keybelow = !exists("keypos") && (sc * (x1 - x0) < 260 || sc * (y1 - y0) < 100)
if (keybelow) { mb = mb + 30; sc = scale(mb) }

# Tics: the same step in metres on both axes, the smallest of 1, 2, 5 times
# a power of ten that puts labels at least 50 px apart and the x labels
# (about 8 px a character) 30 px clear of each other. A range holding fewer
# than two tics reaches out to the next ones, so a narrow plot has labels.
nice(v) = (v / 10.0**floor(log10(v)) <= 1.0001 ? 1 : v / 10.0**floor(log10(v)) <= 2.0001 ? 2 : \
           v / 10.0**floor(log10(v)) <= 5.0001 ? 5 : 10) * 10.0**floor(log10(v))
nch(v) = strlen(sprintf("%g", v))
tic = nice(50.0 / sc)
do for [pass = 1:3] {
    chars = max(nch(ceil(x0 / tic) * tic), nch(floor(x1 / tic) * tic))
    chars = max(chars, nch(ceil(x0 / tic) * tic + tic))
    tic = max(tic, nice((8.0 * chars + 30) / sc))
}
if (floor(x1 / tic) - ceil(x0 / tic) < 1) {
    if (!exists("xmin")) { x0 = floor(x0 / tic) * tic }
    if (!exists("xmax")) { x1 = ceil(x1 / tic) * tic }
}
if (floor(y1 / tic) - ceil(y0 / tic) < 1) {
    if (!exists("ymin")) { y0 = floor(y0 / tic) * tic }
    if (!exists("ymax")) { y1 = ceil(y1 / tic) * tic }
}

sc = scale(mb)
pw = sc * (x1 - x0); ph = sc * (y1 - y0)
if (!exists("size")) {
    W = max(480, ceil(pw - 0.01) + ml + mr); H = max(360, ceil(ph - 0.01) + mt + mb)
    size = sprintf("%d,%d", W, H)
}
px0 = ml + (W - ml - mr - pw) / 2.0
py0 = mb + (H - mt - mb - ph) / 2.0

# Dot size: 0.85 of the points' spacing in frame 0 (the most common gap
# between neighbouring distinct x or y of the points as made), a pngcairo
# point size 1 being a dot 6 px across.
if (!exists("ptsize")) {
    gap = real(system(sprintf("awk 'BEGIN {b = 0} /^[ \t]*$/ {nb++; next} {if (nb >= 2) b++; nb = 0} b > 0 {exit} /^[ \t]*[-+.0-9]/ {print \"x\", $1; print \"y\", $2}' '%s' | sort -k1,1 -k2,2g -u | awk '{if ($1 == p) {g = $2 - v; if (g > 1e-9 * ((v < 0 ? -v : v) + 1)) c[sprintf(\"%%.3g\", g)]++} p = $1; v = $2} END {for (k in c) if (c[k] > n) {n = c[k]; s = k} print (n > 0) ? s : 0}'", in)))
    ptsize = (gap > 0) ? 0.85 * gap * sc / 6.0 : 0.5
    ptsize = min(5, max(0.25, ptsize))
}

set terminal pngcairo size @size enhanced font 'DejaVu Sans,11'
set output out

# viridis: perceptually uniform, readable in grey, bands show up bright.
set palette defined (0 '#440154', 1 '#472c7a', 2 '#3b518b', 3 '#2c718e', \
                     4 '#21908d', 5 '#27ad81', 6 '#5cc863', 7 '#aadc32', 8 '#fde725')
# The colour column, by name (from the "# columns:" line; the names of this
# version if the table has none) or by number, and its label with its unit.
names = system(sprintf("awk '!/^#/ {exit} sub(/^#[ \t]*columns:[ \t]*/, \"\") {print; exit}' '%s'", in))
if (words(names) == 0) names = 'x y sxx syy sxy szz ep yielded mat id ux uy'
cname = '' . color
colnum(n) = sum [k = 1:words(names)] ((word(names, k) eq n) ? k : 0)
uxcol = colnum('ux')
uycol = colnum('uy')
ccol = colnum(cname)
digits(s) = strlen(s) > 0 && (sum [k = 1:strlen(s)] (strstrt('0123456789', s[k:k]) > 0 ? 0 : 1)) == 0
if (ccol == 0 && digits(cname)) ccol = int(real(cname))
if (cname eq 'u' && uxcol > 0 && uycol > 0) {
    ccol = 0  # |u|, from the columns ux and uy
} else {
    if (ccol < 1 || ccol > words(names)) {
        print sprintf("snapshot.gp: columns in '%s': %s (and u, the displacement's size, where ux and uy are)", in, names)
        exit error sprintf("snapshot.gp: no column '%s' to colour by", cname)
    }
    cname = word(names, ccol)
}
cvalue(dummy) = ccol > 0 ? column(ccol) : sqrt(column(uxcol)**2 + column(uycol)**2)
clabel = (cname eq 'ep') ? 'plastic shear strain e_p [-]' : \
         (cname[1:1] eq 's' && strlen(cname) == 3) ? sprintf('stress {/Symbol s}_{%s} [Pa] (tension positive)', cname[2:3]) : \
         (cname eq 'x' || cname eq 'y') ? cname . ' [m]' : \
         (cname eq 'ux' || cname eq 'uy') ? 'displacement ' . cname . ' since step 0 [m]' : \
         (cname eq 'u') ? 'displacement |u| since step 0 [m]' : \
         (cname eq 'yielded') ? 'yielded (1) or not (0) [-]' : \
         (cname eq 'mat') ? 'material id' : (cname eq 'id') ? 'point number' : cname
if (cname eq 'ep') { set cbrange [0:epmax] } else { set cbrange [*:*] }
if (exists("cbmin")) set cbrange [cbmin:]
if (exists("cbmax")) set cbrange [:cbmax]
set cblabel clabel
# The colour box beside the plot, as high as the plot (at least 200 px).
cbh = max(ph, min(200, H - mt - mb))
set colorbox user origin screen (px0 + pw + 20) / W, screen (py0 + ph / 2 - cbh / 2) / H \
    size screen 22.0 / W, screen cbh / H
set lmargin at screen px0 / W
set rmargin at screen (px0 + pw) / W
set bmargin at screen py0 / H
set tmargin at screen (py0 + ph) / H
set size ratio -1
set xrange [x0:x1]
set yrange [y0:y1]
set xtics tic
set ytics tic
set xlabel 'x [m]'
set ylabel 'y [m]'
set title label noenhanced
# The key goes inside the plot, into the corner where the frame has the
# fewest points (over a quarter of the width and a sixth of the height).
if (!exists("keypos")) {
    keypos = system(sprintf("awk -v f=%d 'BEGIN {b = 0} /^[ \t]*$/ {nb++; next} {if (nb >= 2) b++; nb = 0} /^#/ || b != f {next} {n++; x[n] = $1; y[n] = $2; if (n == 1 || $1 < x0) x0 = $1; if (n == 1 || $1 > x1) x1 = $1; if (n == 1 || $2 < y0) y0 = $2; if (n == 1 || $2 > y1) y1 = $2} END {w = (x1 - x0) / 4; h = (y1 - y0) / 6; for (k = 1; k <= n; k++) {l = x[k] < x0 + w; r = x[k] > x1 - w; t = y[k] > y1 - h; u = y[k] < y0 + h; c[\"top right\"] += r && t; c[\"top left\"] += l && t; c[\"bottom right\"] += r && u; c[\"bottom left\"] += l && u} best = \"top right\"; split(\"top right,top left,bottom right,bottom left\", o, \",\"); for (k = 1; k <= 4; k++) if (c[o[k]] < c[best]) best = o[k]; print best}' '%s'", frame, in))
}
if (keybelow) {
    set key at screen (px0 + pw / 2) / W, screen 6.0 / H center bottom opaque box samplen 1 width 1
} else {
    eval sprintf("set key inside %s opaque box samplen 1 width 1", keypos)
}

# The ring symbol is drawn at data size, too small to read in the key,
# so the key entry comes from an empty curve with a larger symbol.
plot in index frame using 1:2:(cvalue(0)) with points pt 7 ps ptsize lc palette notitle, \
     ''  index frame using 1:($8 > 0.5 ? $2 : NaN) with points pt 6 ps ptsize \
         lw 0.5 lc rgb '#202020' notitle, \
     NaN with points pt 6 ps 1.5 lw 1 lc rgb '#202020' title 'yielded (dark ring)'
set output
