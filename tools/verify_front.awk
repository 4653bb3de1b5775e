# Run-out of a collapsed granular column from the last frame of a point table: the
# front is the x below which a fraction `keep` (default 0.99) of the points lie (all
# points of one run have the same mass), so that a few points thrown ahead of the
# deposit do not count as the deposit. Output: front, farthest point, points.
BEGIN { if (keep == "") keep = 0.99 }
/^# step/ { n = 0; next }
/^#/ || NF < 10 || $1 == "x" { next }  # "x y ...": the column names
{ x[++n] = $1 }
END {
    # heap sort (portable awk has no sort function)
    for (i = int(n / 2); i >= 1; i--) sift(i, n)
    for (e = n; e > 1; e--) { t = x[1]; x[1] = x[e]; x[e] = t; sift(1, e - 1) }
    k = int(keep * n); if (k < 1) k = 1
    printf "%.9g %.9g %d\n", x[k], x[n], n
}
function sift(i, m,    c, t) {
    while ((c = 2 * i) <= m) {
        if (c < m && x[c + 1] > x[c]) c++
        if (x[i] >= x[c]) return
        t = x[i]; x[i] = x[c]; x[c] = t; i = c
    }
}
