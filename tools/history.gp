# history.gp -- one column of an lpfdm history file against another, as PNG.
#
# Usage:
#   gnuplot -e "in='history.dat'; out='ke.png'; xcol='time'; ycol='ke'" tools/history.gp
#   gnuplot -e "in='history.dat'; xcol='w1_dy'; ycol='w1_fy'; xscale=-1000; yscale=-1; xlabel='top wall travel [mm]'; ylabel='top wall force [N/m]'" tools/history.gp
#
# Variables (all optional):
#   in       history file                       default 'history.dat'
#   out      PNG file to write                  default 'history.png'
#   xcol     column name for x                  default 'time'
#   ycol     column name for y                  default 'ke'
#   xscale   factor applied to x                default 1
#   yscale   factor applied to y                default 1
#   xlabel   x axis label                       default: xcol [its unit] (× xscale)
#   ylabel   y axis label                       default: ycol [its unit] (× yscale)
#   title    plot title                         default: in
#   logy     1 = logarithmic y axis (e.g. for ke, unbal)   default 0
#
# Column positions depend on the number of walls, so columns are looked
# up by name in the header line "# step time ke ...".

if (!exists("in"))     in = 'history.dat'
if (!exists("out"))    out = 'history.png'
if (!exists("xcol"))   xcol = 'time'
if (!exists("ycol"))   ycol = 'ke'
if (!exists("xscale")) xscale = 1
if (!exists("yscale")) yscale = 1
# The unit of each column of a history (per wall: w<id>_fx _fy in N/m, _dx _dy in m;
# per TRACK: t<n>_x _y _ux _uy in m).
tail2(n) = strlen(n) > 2 ? n[strlen(n) - 1:strlen(n)] : ''
unit(n) = (n eq 'time') ? 's' : (n eq 'ke') ? 'J/m' : (n eq 'mass_in' || n eq 'mass_out') ? 'kg/m' : \
          (n eq 'rx' || n eq 'ry') ? 'N/m' : (n eq 'step' || n eq 'unbal' || n eq 'parked' || n eq 'packed') ? '-' : \
          (n[1:1] eq 'w' && (tail2(n) eq 'fx' || tail2(n) eq 'fy')) ? 'N/m' : \
          (n[1:1] eq 'w' && (tail2(n) eq 'dx' || tail2(n) eq 'dy')) ? 'm' : \
          (n[1:1] eq 't' && strstrt(n, '_') > 2 && (tail2(n) eq 'ux' || tail2(n) eq 'uy' || tail2(n) eq '_x' || tail2(n) eq '_y')) ? 'm' : '?'
axis(n, f) = (f == 1) ? sprintf("%s [%s]", n, unit(n)) : sprintf("%s [%s] × %g", n, unit(n), f)
if (!exists("xlabel")) xlabel = axis(xcol, xscale)
if (!exists("ylabel")) ylabel = axis(ycol, yscale)
if (!exists("title"))  title = in
if (!exists("logy"))   logy = 0

# gnuplot only warns about an unreadable file and then draws an empty
# picture, so stop here with an error instead.
if (system(sprintf("test -r '%s' && echo ok", in)) ne "ok") {
    exit error sprintf("history.gp: cannot read history file '%s'", in)
}

# The names come from the first line of the history ("step time ke ..."),
# or from the last comment line whose first name is "step" (read before
# the first data row; "# step N time T" lines of a point table do not
# count), as older histories have only that one.
header = system(sprintf("awk 'NR == 1 && !/^#/ {h = $0; next} !/^#/ {exit} {sub(/^#[ \t]*/, \"\")} $1 == \"step\" && $2 !~ /^[0-9]/ {h = $0} END {print h}' '%s'", in))
colidx(name) = sum [k = 1:words(header)] ((word(header, k) eq name) ? k : 0)
if (words(header) == 0) {
    exit error sprintf("history.gp: no '# step time ...' header line in '%s'", in)
}
ix = colidx(xcol)
iy = colidx(ycol)
if (ix == 0 || iy == 0) {
    # exit error cuts long messages, so the column list goes first.
    print sprintf("history.gp: columns in '%s': %s", in, header)
    exit error sprintf("history.gp: no column '%s' in '%s'", (ix == 0) ? xcol : ycol, in)
}

set terminal pngcairo size 1000,650 enhanced font 'DejaVu Sans,11'
set output out
set xlabel xlabel noenhanced
set ylabel ylabel noenhanced
set title title noenhanced
set grid
set key off
if (logy) set logscale y
plot in using (column(ix) * xscale):(column(iy) * yscale) with lines lw 1.5 lc rgb '#21908d'
set output
