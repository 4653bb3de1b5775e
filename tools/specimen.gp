# specimen.gp -- compression specimen before and after loading: frame 0 and
# the last frame of an lpfdm point table side by side, as PNG.
#
# Usage:
#   gnuplot -e "in='points.dat'; out='specimen.png'; L=0.01" tools/specimen.gp
#
# Variables:
#   L       cell size [m]; axes are x/L and y/L                 REQUIRED
#   in      point table                      default 'points.dat'
#   out     PNG file to write                default 'specimen.png'
#   mat     material id to show (others, e.g. the loading cap, are hidden)
#                                                               default 1
#   frame   frame for the right panel, -1 = last frame          default -1
#   title   overall title                                       default ''
#   epmax   top of the colour scale for ep (plastic shear strain) default 0.5
#   ptsize  dot size (gnuplot pointsize; 1 is a dot 6 px across)
#           default: 0.85 of the points' spacing in frame 0, so that the
#           specimen reads as a surface and a shear band as a band
#   size    canvas size in pixels "W,H"  default: 1200 wide, height to fit
#
# Both panels share one set of axis ranges (the extent of the shown
# material over both frames), so the deformation is seen at true scale.

if (!exists("in"))     in = 'points.dat'
if (!exists("out"))    out = 'specimen.png'
if (!exists("mat"))    mat = 1
if (!exists("frame"))  frame = -1
if (!exists("title"))  title = ''
if (!exists("epmax"))  epmax = 0.5
if (!exists("L")) {
    exit error "specimen.gp: set the cell size L in m, e.g. -e \"L=0.01\""
}

# gnuplot only warns about an unreadable file and then draws an empty
# picture, so stop here with an error instead.
if (system(sprintf("test -r '%s' && echo ok", in)) ne "ok") {
    exit error sprintf("specimen.gp: cannot read point table '%s'", in)
}

# Step and time of frame 0 and of the chosen frame, with frames counted
# as gnuplot counts data blocks (two blank lines apart).
# Output: resolved frame, number of frames, step0, time0, step, time.
info = system(sprintf("awk -v f=%d 'BEGIN {b = 0} /^[ \t]*$/ {nb++; next} {if (nb >= 2) b++; nb = 0} /^#[ \t]*step[ \t]/ {s[b] = $3; t[b] = $5} END {if (f < 0) f = b; print f, b + 1, s[0] \" \" t[0], s[f] \" \" t[f]}' '%s'", frame, in))
frame = int(word(info, 1))
if (frame > int(word(info, 2)) - 1) {
    exit error sprintf("specimen.gp: frame %d not in '%s' (frames 0..%d)", frame, in, int(word(info, 2)) - 1)
}

# Common ranges from the shown material in both frames.
sel(v) = (int(column(9)) == mat) ? v / L : NaN
stats in index 0     using (sel($1)):(sel($2)) name 'A' nooutput
stats in index frame using (sel($1)):(sel($2)) name 'B' nooutput
# (stats leaves its variables undefined when no point qualifies)
if (!exists("A_records") || !exists("B_records")) {
    exit error sprintf("specimen.gp: no points of material %d in frame 0 or %d", mat, frame)
}
xlo = (A_min_x < B_min_x) ? A_min_x : B_min_x
xhi = (A_max_x > B_max_x) ? A_max_x : B_max_x
ylo = (A_min_y < B_min_y) ? A_min_y : B_min_y
yhi = (A_max_y > B_max_y) ? A_max_y : B_max_y
pad = 0.03 * ((xhi - xlo > yhi - ylo) ? xhi - xlo : yhi - ylo)

# Panels fill screen x 0.08..0.84 (gap 0.06, so 420 px each at 1200 px);
# vertical margins are fixed in pixels (tic labels and x label below,
# titles above) and the height is chosen so that equal scaling fills
# the panels.
mtop = (strlen(title) > 0) ? 80 : 50
mbot = 60
if (!exists("size")) {
    h = 420.0 * (yhi - ylo + 2 * pad) / (xhi - xlo + 2 * pad) + mtop + mbot
    size = sprintf("1200,%d", (h < 300) ? 300 : (h > 1800) ? 1800 : int(h))
}
H = real(size[strstrt(size, ",") + 1:])   # canvas height in px
W = real(size[1:strstrt(size, ",") - 1])  # canvas width in px

# Dot size: 0.85 of the spacing of the shown material's points in frame 0
# (the most common gap between neighbouring distinct x or y of the points
# as made), at the panels' scale [px per L], a pngcairo point size 1 being
# a dot 6 px across.
if (!exists("ptsize")) {
    gap = real(system(sprintf("awk -v m=%d 'BEGIN {b = 0} /^[ \t]*$/ {nb++; next} {if (nb >= 2) b++; nb = 0} b > 0 {exit} /^[ \t]*[-+.0-9]/ && int($9) == m {print \"x\", $1; print \"y\", $2}' '%s' | sort -k1,1 -k2,2g -u | awk '{if ($1 == p) {g = $2 - v; if (g > 1e-9 * ((v < 0 ? -v : v) + 1)) c[sprintf(\"%%.3g\", g)]++} p = $1; v = $2} END {for (k in c) if (c[k] > n) {n = c[k]; s = k} print (n > 0) ? s : 0}'", mat, in))) / L
    px = 0.35 * W / (xhi - xlo + 2 * pad)
    if ((H - mtop - mbot) / (yhi - ylo + 2 * pad) < px) { px = (H - mtop - mbot) / (yhi - ylo + 2 * pad) }
    ptsize = (gap > 0) ? 0.85 * gap * px / 6.0 : 0.5
    ptsize = (ptsize < 0.25) ? 0.25 : (ptsize > 5) ? 5 : ptsize
}

set terminal pngcairo size @size enhanced font 'DejaVu Sans,11'
set output out

set palette defined (0 '#440154', 1 '#472c7a', 2 '#3b518b', 3 '#2c718e', \
                     4 '#21908d', 5 '#27ad81', 6 '#5cc863', 7 '#aadc32', 8 '#fde725')
set cbrange [0:epmax]
set cblabel 'plastic shear strain e_p [-]'
# Fixed margins keep both panels the same size although only the right
# one carries the colour box.
set colorbox user origin screen 0.88, screen mbot / H size screen 0.025, screen 1 - (mtop + mbot) / H
set size ratio -1
set xrange [xlo - pad:xhi + pad]
set yrange [ylo - pad:yhi + pad]
set xlabel 'x/L [-]'
set key off

set multiplot layout 1,2 margins screen 0.08, screen 0.84, screen mbot / H, screen 1 - mtop / H \
    spacing screen 0.06 title title noenhanced

set ylabel 'y/L [-]'
unset colorbox
set title sprintf("step %s, t = %s s", word(info, 3), word(info, 4)) noenhanced
plot in index 0 using (sel($1)):(sel($2)):7 with points pt 7 ps ptsize lc palette

unset ylabel
set colorbox
set title sprintf("step %s, t = %s s", word(info, 5), word(info, 6)) noenhanced
plot in index frame using (sel($1)):(sel($2)):7 with points pt 7 ps ptsize lc palette

unset multiplot
set output
