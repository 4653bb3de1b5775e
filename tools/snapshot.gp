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
#   epmax   top of the colour scale for ep (plastic shear strain) default 0.5
#   ptsize  dot size (gnuplot pointsize)                        default 0.3
#   xmin, xmax, ymin, ymax   axis limits in m, each may be set alone;
#           unset ends are autoscaled
#   size    canvas size in pixels "W,H"                         default '1200,800'
#
# Points are coloured by ep (column 7); points that have yielded
# (column 8 = 1) get a thin dark ring so softened material can be told
# apart from elastic material of the same ep.

if (!exists("in"))     in = 'points.dat'
if (!exists("out"))    out = 'snapshot.png'
if (!exists("frame"))  frame = -1
if (!exists("title"))  title = ''
if (!exists("epmax"))  epmax = 0.5
if (!exists("ptsize")) ptsize = 0.3
if (!exists("size"))   size = '1200,800'

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
set cbrange [0:epmax]
set cblabel 'plastic shear strain e_p'
set size ratio -1
set xlabel 'x [m]'
set ylabel 'y [m]'
set title label noenhanced
set key outside top center horizontal
# Autoscaling would round the ranges out to the next tic; keep them tight.
set autoscale fix
set offsets graph 0.02, graph 0.02, graph 0.02, graph 0.02
if (exists("xmin")) set xrange [xmin:]
if (exists("xmax")) set xrange [:xmax]
if (exists("ymin")) set yrange [ymin:]
if (exists("ymax")) set yrange [:ymax]

# The ring symbol is drawn at data size, too small to read in the key,
# so the key entry comes from an empty curve with a larger symbol.
plot in index frame using 1:2:7 with points pt 7 ps ptsize lc palette notitle, \
     ''  index frame using 1:($8 > 0.5 ? $2 : NaN) with points pt 6 ps ptsize \
         lw 0.4 lc rgb '#202020' notitle, \
     NaN with points pt 6 ps 1.5 lw 1 lc rgb '#202020' title 'yielded (dark ring)'
set output
