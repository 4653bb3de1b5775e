# Work-precision diagram of the verification ladder: |relative error| against wall time
# (log-log), one line per case, two points per cell, rungs --refine 1, 2, 4; a case's
# MAPPING SMOOTH and ADVECT FLIP rows dashed and dotted in its colour.
# gnuplot -e "dir='out/verify'; cases='column_syy psc_q ...'; out='out/verify_work_precision.png'" tools/verify_work_precision.gp
# dir holds ladder_<case>.dat: case cells wall_s |error| measured (written by verify.sh).
if (!exists("dir")) dir = 'out/verify'
if (!exists("out")) out = 'verify_work_precision.png'
# A case and its variants (_smooth: MAPPING SMOOTH, _smooth_flip: and ADVECT FLIP; _window:
# DAMPING WINDOW, a thick line) share a colour, the colour of the case's first word in
# `cases`; the variant sets line and point.
colours = '#1f77b4 #d62728 #2ca02c #ff7f0e #9467bd #8c564b #e377c2 #17becf #bcbd22 #000000 #7f7f7f #aec7e8'
do for [vi = 1:words(colours)] { set linetype vi lc rgb word(colours, vi) }
set linetype cycle words(colours)
variant_cut(c) = (va = strstrt(c, '_smooth'), vw = strstrt(c, '_window'), va > 0 && (vw == 0 || va < vw) ? va : vw)
variant_base(c) = (vb = variant_cut(c), vb > 0 ? c[1:vb - 1] : c)
variant_width(c) = strstrt(c, '_window') > 0 ? 4 : 2
variant_colour(c) = sum [vi = 1:words(cases)] (word(cases, vi) eq variant_base(c) ? vi : 0)
variant_dash(c) = strstrt(c, '_flip') > 0 ? 3 : (strstrt(c, '_smooth') > 0 ? 2 : 1)
variant_point(c) = strstrt(c, '_flip') > 0 ? 4 : (strstrt(c, '_smooth') > 0 ? 6 : 7)
set terminal pngcairo size 1200,800 enhanced font ',11'
set output out
set title 'lpfdm verification: error against wall time (2x2 points per cell; --refine 1, 2, 4)'
set logscale xy
set format y '10^{%L}'
set xlabel 'wall time of the run [s] (median of 3 runs; one run above 20 s)'
set ylabel '|relative error| [-]'
set key outside right top
set grid
plot for [c in cases] dir.'/ladder_'.c.'.dat' using 3:4 with linespoints lw variant_width(c) lc variant_colour(c) dt variant_dash(c) pt variant_point(c) title c noenhanced
