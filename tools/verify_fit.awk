# Least-squares fit of log y = log C + p log x over lines "x y".
# Output: exponent p, prefactor C.
NF >= 2 && $1 > 0 && $2 > 0 { n++; a = log($1); b = log($2); sa += a; sb += b; saa += a * a; sab += a * b }
END { p = (n * sab - sa * sb) / (n * saa - sa * sa); printf "%.9g %.9g\n", p, exp((sb - p * sa) / n) }
