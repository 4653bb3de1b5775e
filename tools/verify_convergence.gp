# Convergence of the verification ladder: |relative error| against the cell size over
# the case's characteristic length (log-log), one line per case, the observed order
# between the two finest rungs in the key.
# gnuplot -e "dir='out/verify'; cases='...'; orders=' case=p ...'; out='out/verify_convergence.png'" tools/verify_convergence.gp
if (!exists("dir")) dir = 'out/verify'
if (!exists("out")) out = 'verify_convergence.png'
if (!exists("orders")) orders = ''
o = ' '.orders
ord(c) = (pos = strstrt(o, ' '.c.'='), pos > 0 ? ' (p = '.word(o[pos + 1:], 1)[strlen(c) + 2:].')' : '')
set terminal pngcairo size 1200,800 enhanced font ',11'
set output out
set title 'lpfdm verification: error against cell size (2x2 points per cell; p: observed order, finest pair)'
set logscale xy
set format y '10^{%L}'
set xlabel 'cell size / characteristic length [-]'
set ylabel '|relative error| [-]'
set key outside right top
set grid
plot for [c in cases] dir.'/ladder_'.c.'.dat' using (1.0 / $2):4 with linespoints lw 2 pt 7 title c.ord(c) noenhanced, \
     [0.01:0.3] 0.3 * x with lines dt 2 lc 'gray' title 'slope 1', \
     [0.01:0.3] 1.0 * x**2 with lines dt 3 lc 'gray' title 'slope 2'
