# Wall force from a history: q = -w<wall>_fy / width (the force the wall exerts on the
# material, downward positive, per metre of width), against the wall's travel -w<wall>_dy.
# Columns are found by name in the header line.
#   -v wall=1 -v width=W [-v scale=S]    q is divided by S (e.g. c for q/c)
#   -v at=D      value of q at travel D (linear interpolation), or
#   -v from=D0   mean and maximum of q over travel >= D0
# Output: value (at) or "mean max" (from), then the largest travel seen.
BEGIN { if (scale == "") scale = 1 }
/^# step/ {
    for (i = 2; i <= NF; i++) col[$i] = i - 1
    fy = col["w" wall "_fy"]; dy = col["w" wall "_dy"]
    next
}
/^#/ || NF == 0 || $1 == "step" { next }  # "step time ...": the column names
{
    d = -$dy; q = -$fy / width / scale
    if (at != "" && !done && d >= at) {
        v = (d > dprev) ? qprev + (q - qprev) * (at - dprev) / (d - dprev) : q
        done = 1
    }
    if (from != "" && d >= from) { s += q; n++; if (n == 1 || q > m) m = q }
    dprev = d; qprev = q; dmax = d
}
END {
    if (at != "") printf "%.9g %.9g\n", done ? v : "nan", dmax
    else printf "%.9g %.9g %.9g\n", n ? s / n : "nan", n ? m : "nan", dmax
}
