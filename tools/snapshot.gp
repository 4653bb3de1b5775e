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
#           "# columns:" line (x y sxx syy sxy szz ep yielded mat id) or
#           its number, e.g. color='syy' or color=4        default 'ep'
#   cbmin, cbmax  ends of the colour scale, each may be set alone
#           (default: 0 to epmax for ep, else the frame's range)
#   epmax   top of the colour scale for ep (plastic shear strain) default 0.5
#   keypos  where the key goes inside the plot, e.g. 'top right'
#           default: the corner of the plot with the fewest points
#   ptsize  dot size (gnuplot pointsize)                        default 0.3
#   xmin, xmax, ymin, ymax   axis limits in m, each may be set alone;
#           unset ends are autoscaled
#   size    canvas size in pixels "W,H"                         default '1200,800'
#
# Points are coloured by ep (column 7) unless color names another column;
# points that have yielded (column 8 = 1) get a thin dark ring so softened
# material can be told apart from elastic material of the same colour.

if (!exists("in"))     in = 'points.dat'
if (!exists("out"))    out = 'snapshot.png'
if (!exists("frame"))  frame = -1
if (!exists("title"))  title = ''
if (!exists("epmax"))  epmax = 0.5
if (!exists("ptsize")) ptsize = 0.3
if (!exists("size"))   size = '1200,800'
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

set terminal pngcairo size @size enhanced font 'DejaVu Sans,11'
set output out

# viridis: perceptually uniform, readable in grey, bands show up bright.
set palette defined (0 '#440154', 1 '#472c7a', 2 '#3b518b', 3 '#2c718e', \
                     4 '#21908d', 5 '#27ad81', 6 '#5cc863', 7 '#aadc32', 8 '#fde725')
# The colour column, by name (from the "# columns:" line; the names of this
# version if the table has none) or by number, and its label with its unit.
names = system(sprintf("awk '!/^#/ {exit} sub(/^#[ \t]*columns:[ \t]*/, \"\") {print; exit}' '%s'", in))
if (words(names) == 0) names = 'x y sxx syy sxy szz ep yielded mat id'
cname = '' . color
ccol = sum [k = 1:words(names)] ((word(names, k) eq cname) ? k : 0)
digits(s) = strlen(s) > 0 && (sum [k = 1:strlen(s)] (strstrt('0123456789', s[k:k]) > 0 ? 0 : 1)) == 0
if (ccol == 0 && digits(cname)) ccol = int(real(cname))
if (ccol < 1 || ccol > words(names)) {
    print sprintf("snapshot.gp: columns in '%s': %s", in, names)
    exit error sprintf("snapshot.gp: no column '%s' to colour by", cname)
}
cname = word(names, ccol)
clabel = (cname eq 'ep') ? 'plastic shear strain e_p [-]' : \
         (cname[1:1] eq 's' && strlen(cname) == 3) ? sprintf('stress {/Symbol s}_{%s} [Pa] (tension positive)', cname[2:3]) : \
         (cname eq 'x' || cname eq 'y') ? cname . ' [m]' : \
         (cname eq 'yielded') ? 'yielded (1) or not (0) [-]' : \
         (cname eq 'mat') ? 'material id' : (cname eq 'id') ? 'point number' : cname
if (cname eq 'ep') { set cbrange [0:epmax] } else { set cbrange [*:*] }
if (exists("cbmin")) set cbrange [cbmin:]
if (exists("cbmax")) set cbrange [:cbmax]
set cblabel clabel
set size ratio -1
set xlabel 'x [m]'
set ylabel 'y [m]'
set title label noenhanced
# The key goes inside the plot, into the corner where the frame has the
# fewest points (over a quarter of the width and a sixth of the height).
if (!exists("keypos")) {
    keypos = system(sprintf("awk -v f=%d 'BEGIN {b = 0} /^[ \t]*$/ {nb++; next} {if (nb >= 2) b++; nb = 0} /^#/ || b != f {next} {n++; x[n] = $1; y[n] = $2; if (n == 1 || $1 < x0) x0 = $1; if (n == 1 || $1 > x1) x1 = $1; if (n == 1 || $2 < y0) y0 = $2; if (n == 1 || $2 > y1) y1 = $2} END {w = (x1 - x0) / 4; h = (y1 - y0) / 6; for (k = 1; k <= n; k++) {l = x[k] < x0 + w; r = x[k] > x1 - w; t = y[k] > y1 - h; u = y[k] < y0 + h; c[\"top right\"] += r && t; c[\"top left\"] += l && t; c[\"bottom right\"] += r && u; c[\"bottom left\"] += l && u} best = \"top right\"; split(\"top right,top left,bottom right,bottom left\", o, \",\"); for (k = 1; k <= 4; k++) if (c[o[k]] < c[best]) best = o[k]; print best}' '%s'", frame, in))
}
eval sprintf("set key inside %s opaque box samplen 1 width 1", keypos)
# Autoscaling would round the ranges out to the next tic; keep them tight.
set autoscale fix
set offsets graph 0.02, graph 0.02, graph 0.02, graph 0.02
if (exists("xmin")) set xrange [xmin:]
if (exists("xmax")) set xrange [:xmax]
if (exists("ymin")) set yrange [ymin:]
if (exists("ymax")) set yrange [:ymax]

# The ring symbol is drawn at data size, too small to read in the key,
# so the key entry comes from an empty curve with a larger symbol.
plot in index frame using 1:2:ccol with points pt 7 ps ptsize lc palette notitle, \
     ''  index frame using 1:($8 > 0.5 ? $2 : NaN) with points pt 6 ps ptsize \
         lw 0.4 lc rgb '#202020' notitle, \
     NaN with points pt 6 ps 1.5 lw 1 lc rgb '#202020' title 'yielded (dark ring)'
set output
