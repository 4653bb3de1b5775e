# Does a cut stand? From a history: a cut at rest has an unbalanced-force ratio that
# falls by orders of magnitude each second under local damping (down to rounding,
# about 1e-15); a collapsing or creeping cut keeps it near 1e-3 or above.
# Stands when the last row's unbal is below 1e-7, or below a tenth of its value at two
# thirds of the run. Output: 1 (stands) or 0 (collapses), the two unbal values.
/^# step/ { for (i = 2; i <= NF; i++) col[$i] = i - 1; next }
/^#/ || NF == 0 || $1 == "step" { next }  # "step time ...": the column names
{ t[++n] = $col["time"]; u[n] = $col["unbal"] }
END {
    tend = t[n]; k = n
    while (k > 1 && t[k] > tend * 2 / 3) k--
    stands = (u[n] < 1e-7 || u[n] < 0.1 * u[k]) ? 1 : 0
    printf "%d %.3g %.3g\n", stands, u[k], u[n]
}
