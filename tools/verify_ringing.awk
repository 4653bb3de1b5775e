# Ringing column: from a point table with frequent frames, the mean settlement u(t) of
# the top row of points. Period: from the crossings of the middle level (halfway between
# the lowest and the highest sample), found by linear interpolation (a crossing is an
# inflection point of u, where a straight line fits best); an odd number of crossings
# is used, first and last in the same direction, so that a level slightly off the
# true middle shifts both alike: period = 2 (t_last - t_first) / (crossings - 1).
# Peak: the first maximum, by a parabola through the largest sample and its neighbours,
# over the static settlement of the same points (finite-strain form, see
# verify_column.awk). Input: -v H= -v rho= -v g= -v E= -v nu=
# Output: period peak_over_static u_static crossings
/^# step/ { if (frame) close_frame(); frame++; t = $5; next }
/^#/ || NF < 10 || $1 == "x" { next }  # "x y ...": the column names
frame == 1 { y0[$10] = $2; if ($2 > ytop) ytop = $2; next }
{ if (y0[$10] > ytop - 1e-9) { su += y0[$10] - $2; nu_ += 1 } }
function close_frame() {
    if (frame == 1) { nt = 0; tt[nt] = t; uu[nt] = 0; nt++; return }
    tt[nt] = t; uu[nt] = su / nu_; nt++; su = 0; nu_ = 0
}
END {
    close_frame()
    M = E * (1 - nu) / ((1 + nu) * (1 - 2 * nu)); a = rho * g / M
    us = ytop - exp(-a * H) * (exp(a * ytop) - 1) / a
    lo = uu[0]; hi = uu[0]
    for (k = 1; k < nt; k++) { if (uu[k] < lo) lo = uu[k]; if (uu[k] > hi) hi = uu[k] }
    mid = (lo + hi) / 2; nc = 0
    for (k = 1; k < nt; k++)
        if ((uu[k-1] - mid) * (uu[k] - mid) < 0 || (uu[k] == mid && k < nt - 1))
            tc[nc++] = tt[k-1] + (mid - uu[k-1]) * (tt[k] - tt[k-1]) / (uu[k] - uu[k-1])
    if (nc % 2 == 0) nc--
    period = nc > 1 ? 2 * (tc[nc-1] - tc[0]) / (nc - 1) : 0
    for (k = 1; k < nt - 1; k++) {
        if (uu[k] > uu[k-1] && uu[k] >= uu[k+1] && uu[k] > us) {
            d1 = (uu[k+1] - uu[k-1]) / 2; d2 = uu[k+1] - 2 * uu[k] + uu[k-1]
            peak = d2 != 0 ? uu[k] - d1 * d1 / (2 * d2) : uu[k]
            break
        }
    }
    printf "%.9g %.9g %.9g %d\n", period, peak / us, us, nc
}
