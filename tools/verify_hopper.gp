# Discharge through a slot: steady rate against slot width D (log-log) for each rung,
# with the 2D Beverloo slope 3/2.
# gnuplot -e "in='out/verify_hopper.tsv'; out='out/verify_hopper.png'" tools/verify_hopper.gp
# in: cells_per_L0 ppc D_m D_cells rate beverloo_C (one header line).
if (!exists("in")) in = 'out/verify_hopper.tsv'
if (!exists("out")) out = 'verify_hopper.png'
set terminal pngcairo size 900,700 enhanced font ',11'
set output out
set title 'Discharge through a slot of width D (rate from 1 s to 2 s)'
set logscale xy
set xrange [0.2:1.2]
set yrange [300:20000]
set xlabel 'slot width D [m]'
set ylabel 'discharge [kg/s per m]'
set key left top
set grid
set datafile separator '\t'
plot in using ($1 == 8 && $2 == 2 ? $3 : 1/0):5 every ::1 with linespoints pt 7 ps 1.5 title 'L = 0.125 m (2 to 8 cells)', \
     in using ($1 == 16 && $2 == 2 ? $3 : 1/0):5 every ::1 with linespoints pt 5 ps 1.5 title 'L = 0.0625 m (4 to 16 cells)', \
     in using ($2 != 2 ? $3 : 1/0):5 every ::1 with points pt 1 ps 1.5 lc 'gray40' title 'L = 0.125 m, 1x1 and 4x4 points per cell', \
     8000 * x**1.5 with lines dt 2 lc 'black' title 'D^{3/2}'
