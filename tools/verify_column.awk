# Confined elastic column at rest under self-weight: compares the last frame of a point
# table with the closed-form column (closed form), evaluated at each point's
# initial height Y (a point keeps the weight of the material above it, so in the
# material's own coordinates sigma_yy = -rho g (H - Y) holds exactly, also at large strain).
#   settlement of a point at Y, with the stress updated from strain increments of the
#   current configuration (sigma_yy = M ln(stretch)):
#     u(Y) = Y - (M / rho g) exp(-rho g H / M) (exp(rho g Y / M) - 1)
#   and the small-strain form rho g (2 H Y - Y^2) / (2 M) for comparison.
# Input: -v H= -v rho= -v g= -v E= -v nu=   Output, one line:
#   syy_rms syy_ref_rms syy_L2err  u_top u_top_ref u_top_err  u_top_small_ref
/^# step/ { frame++; next }
/^#/ || NF < 10 || $1 == "x" { next }  # "x y ...": the column names
frame == 1 { y0[$10] = $2; next }
{ last[$10] = $0 }
END {
    M = E * (1 - nu) / ((1 + nu) * (1 - 2 * nu)); a = rho * g / M
    ytop = -1
    for (id in y0) if (y0[id] > ytop) ytop = y0[id]
    for (id in last) {
        split(last[id], f, " ")
        Y = y0[id]; ref = -rho * g * (H - Y)
        e2 += (f[4] - ref)^2; r2 += ref^2; m2 += f[4]^2
        if (Y > ytop - 1e-9) {
            n++; u += Y - f[2]
            uref += Y - exp(-a * H) * (exp(a * Y) - 1) / a
            usm += a * (2 * H * Y - Y * Y) / 2
        }
    }
    u /= n; uref /= n; usm /= n
    printf "%.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", sqrt(m2 / NR), sqrt(r2 / NR), sqrt(e2 / r2), u, uref, (u - uref) / uref, usm
}
