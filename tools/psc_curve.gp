# psc_curve.gp -- plane-strain compression test: normalised deviator stress
# q/c against axial strain, from an lpfdm history file, as PNG.
#
# Usage:
#   gnuplot -e "in='history.dat'; out='psc.png'; width=0.5; height=1.0; c=20e3; phi=30" tools/psc_curve.gp
#
# Variables:
#   width   specimen width [m]                          REQUIRED
#   height  initial specimen height [m]                 REQUIRED
#   c       cohesion [Pa]                               REQUIRED
#   phi     friction angle [deg]                        REQUIRED
#   in      history file                 default 'history.dat'
#   out     PNG file to write            default 'psc_curve.png'
#   wall    id K of the loading wall (columns wK_fy, wK_dy)   default 1
#   title   plot title                   default: in
#
# The confining pressure is zero, so the deviator stress is the axial
# stress: q = -wK_fy / width (the wall pushes down, fy < 0) and the axial
# strain is -wK_dy / height.  The Mohr-Coulomb unconfined strength
# 2 c tan(45 deg + phi/2) is drawn for comparison.  The specimen
# dimensions and strength have no meaningful defaults and must be given.

if (!exists("in"))    in = 'history.dat'
if (!exists("out"))   out = 'psc_curve.png'
if (!exists("wall"))  wall = 1
if (!exists("title")) title = in
if (!exists("width") || !exists("height") || !exists("c") || !exists("phi")) {
    exit error "psc_curve.gp: set width, height (m), c (Pa) and phi (deg), e.g. -e \"width=0.5; height=1; c=20e3; phi=30\""
}

# gnuplot only warns about an unreadable file and then draws an empty
# picture, so stop here with an error instead.
if (system(sprintf("test -r '%s' && echo ok", in)) ne "ok") {
    exit error sprintf("psc_curve.gp: cannot read history file '%s'", in)
}

# Wall columns move with the number of walls: look them up by name in
# the last "# step time ..." comment line before the data.
header = system(sprintf("awk 'NR == 1 && !/^#/ {h = $0; next} !/^#/ {exit} {sub(/^#[ \t]*/, \"\")} $1 == \"step\" && $2 !~ /^[0-9]/ {h = $0} END {print h}' '%s'", in))
colidx(name) = sum [k = 1:words(header)] ((word(header, k) eq name) ? k : 0)
ify = colidx(sprintf("w%d_fy", wall))
idy = colidx(sprintf("w%d_dy", wall))
if (ify == 0 || idy == 0) {
    print sprintf("psc_curve.gp: columns in '%s': %s", in, header)
    exit error sprintf("psc_curve.gp: no columns w%d_fy / w%d_dy in '%s'", wall, wall, in)
}

qpeak = 2 * tan((45 + phi / 2.0) * pi / 180)
strain(dy) = -100.0 * dy / height
qc(fy) = -fy / width / c

# Peak of the computed curve, reported in the key.
stats in using (qc(column(ify))) name 'Q' nooutput

set terminal pngcairo size 1000,650 enhanced font 'DejaVu Sans,11'
set output out
set xlabel 'axial strain ε_a [%]'
set ylabel 'deviator stress q / c [-]'
set title title noenhanced
set grid
set key bottom right box opaque
set yrange [0:*]
set xrange [0:*]
set arrow from graph 0, first qpeak to graph 1, first qpeak nohead dt 2 lw 1.5 lc rgb '#b2182b'
set label sprintf("Mohr–Coulomb unconfined peak 2 tan(45° + φ/2) = %.3f  (φ = %g°)", qpeak, phi) \
    at graph 0.02, first qpeak offset 0, 0.8 tc rgb '#b2182b' noenhanced
# Keep the reference line inside the picture even if the run stays below it.
if (Q_max < 1.1 * qpeak) set yrange [0:1.15 * qpeak]
plot in using (strain(column(idy))):(qc(column(ify))) with lines lw 2 lc rgb '#21908d' \
    title sprintf("wall %d, peak q/c = %.3f", wall, Q_max)
set output
