# consolidation.gp -- Terzaghi's one-dimensional consolidation: the pore pressure of every
# point against its depth below the drained top, at a few times, over the closed-form
# isochrones, from an lpfdm point table (decks/consolidation.deck), as PNG.
#
# Usage:
#   gnuplot -e "in='out/consolidation_points.txt'; out='out/consolidation.png'" tools/consolidation.gp
#
# Variables:
#   in      point table (with WATER: its last column is p)   default 'consolidation_points.txt'
#   out     PNG file to write                                default 'consolidation.png'
#   H       layer height [m] (drained top at y = H)          default 2
#   p0      the pore pressure at t = 0+ [Pa]                 default 9761 (q (KW/n) / (KW/n + M))
#   cv      coefficient of consolidation [m^2/s]             default 0.1206
#   frames  the frames to draw (indices, 0 = step 0)         default '5 10 20 30 50'
#   title   plot title                                       default: in
#
# The series: p(z, t) = sum (2 p0 / m) sin(m z / H) exp(-m^2 T), m = pi (2i + 1) / 2,
# T = cv t / H^2, z the depth below the drained top.

if (!exists("in"))     in = 'consolidation_points.txt'
if (!exists("out"))    out = 'consolidation.png'
if (!exists("H"))      H = 2.0
if (!exists("p0"))     p0 = 9761.0
if (!exists("cv"))     cv = 0.1206
if (!exists("frames")) frames = '5 10 20 30 50'
if (!exists("title"))  title = in
if (system(sprintf("test -r '%s' && echo ok", in)) ne "ok") {
    exit error sprintf("consolidation.gp: cannot read point table '%s'", in)
}
# The time of each frame, from its "# step N time T" line.
times = system(sprintf("awk '/^# step /{print $5}' '%s' | tr '\\n' ' '", in))
pcol = system(sprintf("awk 'NR == 1 {print NF; exit}' '%s'", in)) + 0
if (system(sprintf("awk 'NR == 1 {print $NF; exit}' '%s'", in)) ne "p") {
    exit error sprintf("consolidation.gp: '%s' has no pore pressure column p (a deck with WATER writes one)", in)
}

m(i) = pi * (2 * i + 1) / 2
series(z, T) = sum [i = 0:200] (2.0 / m(i)) * sin(m(i) * z / H) * exp(-m(i)**2 * T)

set terminal pngcairo size 800,700 font ',11'
set output out
set title title noenhanced
set xlabel 'p / p_0'
set ylabel 'depth below the drained top z / H'
set yrange [1:0]
set xrange [0:1.05]
set key top right box opaque
set grid
set samples 200
set parametric
set trange [0:1]
nf = words(frames)
plot for [k = 1:nf] \
         '+' using (series($1 * H, cv * word(times, int(word(frames, k)) + 1) / H**2)):1 with lines lw 2 lc k \
         title sprintf('T_v = %.2f, Terzaghi', cv * word(times, int(word(frames, k)) + 1) / H**2), \
     for [k = 1:nf] \
         in index int(word(frames, k)) using (column(pcol) / p0):((H - $2) / H) with points pt 7 ps 1.1 lc k \
         title (k == 1 ? 'lpfdm: the points (one value a cell)' : '')
