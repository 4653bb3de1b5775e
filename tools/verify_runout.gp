# Granular column collapse: normalised run-out (L_inf - L0) / L0 against the aspect
# ratio a = H0 / L0, LPFDM at each rung against the laws of Lube et al. (2005),
# 1.2 a (a < 1.8) and 1.9 a^(2/3) (a > 2.8), and Lajeunesse et al. (2005), 1.8 a (a < 3).
# gnuplot -e "in='out/verify_collapse.tsv'; out='out/verify_runout.png'" tools/verify_runout.gp
# in: a cells ppc runout farthest mass_out_fraction (one header line).
if (!exists("in")) in = 'out/verify_collapse.tsv'
if (!exists("out")) out = 'verify_runout.png'
set terminal pngcairo size 900,700 enhanced font ',11'
set output out
set title 'Granular column collapse: run-out (front: 99 % of the points behind it)'
set logscale xy
set xrange [0.3:6]
set yrange [0.1:20]
set xlabel 'aspect ratio a = H_0 / L_0 [-]'
set ylabel '(L_{/Symbol \245} - L_0) / L_0 [-]'
set key left top
set grid
set datafile separator '\t'
lube(a) = a < 1.8 ? 1.2 * a : (a > 2.8 ? 1.9 * a**(2.0/3) : 1/0)
laj(a) = a < 3 ? 1.8 * a : 1/0
plot lube(x) with lines lw 2 lc 'black' title 'Lube et al. 2005', \
     laj(x) with lines lw 2 dt 2 lc 'black' title 'Lajeunesse et al. 2005 ({/Symbol l} = 1.8)', \
     in using ($3 == 2 && $2 == 8 ? $1 : 1/0):4 every ::1 with points pt 7 ps 1.5 title 'LPFDM, 8 cells over L_0', \
     in using ($3 == 2 && $2 == 16 ? $1 : 1/0):4 every ::1 with points pt 5 ps 1.5 title '16 cells', \
     in using ($3 == 2 && $2 == 32 ? $1 : 1/0):4 every ::1 with points pt 9 ps 1.8 title '32 cells', \
     in using ($3 != 2 ? $1 : 1/0):4 every ::1 with points pt 1 ps 1.5 lc 'gray40' title '8 cells, 1x1 and 4x4 points per cell'
