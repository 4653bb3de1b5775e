# animate.gp -- all frames of an lpfdm point table as an animated GIF.
#
# Usage:
#   gnuplot -e "in='points.dat'; out='run.gif'; delay=20" tools/animate.gp
#
# Variables (all optional):
#   in      point table                      default 'points.dat'
#   out     GIF file to write                default 'animation.gif'
#   title   text put before "step N, t = T s" on every frame   default ''
#   epmax   top of the colour scale for ep (plastic shear strain) default 0.5
#   delay   time between frames in 1/100 s                      default 20
#   ptsize  dot size (gnuplot pointsize)                        default 0.5
#   keypos  where the key goes inside the plot                  default 'top right'
#   size    canvas size in pixels "W,H"     default: 900 wide, height to fit
#   xmin, xmax, ymin, ymax   axis limits in m, each may be set alone;
#           unset ends come from the extent of all frames together
#
# The axes stay fixed over the whole animation so that motion of the
# material is seen as motion, not as rescaling.  Colours are those of
# snapshot.gp; yielded points get a dark rim drawn underneath the dot,
# because libgd fills a small ring symbol solid and would hide the colour.

if (!exists("in"))     in = 'points.dat'
if (!exists("out"))    out = 'animation.gif'
if (!exists("title"))  title = ''
if (!exists("epmax"))  epmax = 0.5
if (!exists("delay"))  delay = 20
if (!exists("ptsize")) ptsize = 0.5

# gnuplot only warns about an unreadable file and then draws empty
# frames, so stop here with an error instead.
if (system(sprintf("test -r '%s' && echo ok", in)) ne "ok") {
    exit error sprintf("animate.gp: cannot read point table '%s'", in)
}

# Step and time of every frame, as "step time step time ...".  Frames are
# counted as gnuplot counts data blocks (two blank lines apart).
steps = system(sprintf("awk 'BEGIN {b = 0} /^[ \t]*$/ {nb++; next} {if (nb >= 2) b++; nb = 0} /^#[ \t]*step[ \t]/ {s[b] = $3; t[b] = $5} END {for (i = 0; i <= b; i++) printf \"%%s %%s \", ((i in s) ? s[i] : \"?\"), ((i in t) ? t[i] : \"?\")}' '%s'", in))
nframes = words(steps) / 2

# Extent of all frames; a margin of 2 % keeps edge points off the border.
stats in using 1:2 nooutput
dx = 0.02 * (STATS_max_x - STATS_min_x)
dy = 0.02 * (STATS_max_y - STATS_min_y)
if (!exists("xmin")) xmin = STATS_min_x - dx
if (!exists("xmax")) xmax = STATS_max_x + dx
if (!exists("ymin")) ymin = STATS_min_y - dy
if (!exists("ymax")) ymax = STATS_max_y + dy

# Fit the canvas height to the aspect of the fixed ranges (about 220 px
# go to the colour box and labels, 160 px to title, key and tic labels).
if (!exists("size")) {
    h = 700.0 * (ymax - ymin) / (xmax - xmin) + 160
    size = sprintf("900,%d", (h < 300) ? 300 : (h > 1400) ? 1400 : int(h))
}

set terminal gif animate delay delay size @size enhanced font 'DejaVu Sans,10'
set output out

set palette defined (0 '#440154', 1 '#472c7a', 2 '#3b518b', 3 '#2c718e', \
                     4 '#21908d', 5 '#27ad81', 6 '#5cc863', 7 '#aadc32', 8 '#fde725')
set cbrange [0:epmax]
set cblabel 'plastic shear strain e_p [-]'
set size ratio -1
set xrange [xmin:xmax]
set yrange [ymin:ymax]
set xlabel 'x [m]'
set ylabel 'y [m]'
if (!exists("keypos")) keypos = 'top right'
eval sprintf("set key inside %s opaque box samplen 1 width 1", keypos)

do for [i = 0:nframes - 1] {
    label = sprintf("step %s, t = %s s", word(steps, 2*i + 1), word(steps, 2*i + 2))
    if (strlen(title) > 0) { label = title . " -- " . label }
    set title label noenhanced
    plot in index i using 1:($8 > 0.5 ? $2 : NaN) with points pt 7 ps 1.8*ptsize \
             lc rgb '#000000' notitle, \
         ''  index i using 1:2:7 with points pt 7 ps ptsize lc palette notitle, \
         NaN with points pt 6 ps 1.5 lc rgb '#202020' title 'yielded (dark rim)'
}
set output
