# Work-precision diagram of the verification ladder: |relative error| against wall time
# (log-log), one line per case, two points per cell, rungs --refine 1, 2, 4.
# gnuplot -e "dir='out/verify'; cases='column_syy psc_q ...'; out='out/verify_work_precision.png'" tools/verify_work_precision.gp
# dir holds ladder_<case>.dat: case cells wall_s |error| measured (written by verify.sh).
if (!exists("dir")) dir = 'out/verify'
if (!exists("out")) out = 'verify_work_precision.png'
set terminal pngcairo size 1200,800 enhanced font ',11'
set output out
set title 'lpfdm verification: error against wall time (2x2 points per cell; --refine 1, 2, 4)'
set logscale xy
set format y '10^{%L}'
set xlabel 'wall time of the run [s] (median of 3 runs; one run above 20 s)'
set ylabel '|relative error| [-]'
set key outside right top
set grid
plot for [c in cases] dir.'/ladder_'.c.'.dat' using 3:4 with linespoints lw 2 pt 7 title c noenhanced
