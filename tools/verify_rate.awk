# Steady discharge rate: least-squares slope of mass_out against time over
# from <= time <= to (kg/s per metre). Output: rate, mass out at the end.
/^# step/ { for (i = 2; i <= NF; i++) col[$i] = i - 1; next }
/^#/ || NF == 0 || $1 == "step" { next }  # "step time ...": the column names
{
    t = $col["time"]; m = $col["mass_out"]; last = m
    if (t >= from && t <= to) { n++; st += t; sm += m; stt += t * t; stm += t * m }
}
END { printf "%.9g %.9g\n", (n * stm - st * sm) / (n * stt - st * st), last }
