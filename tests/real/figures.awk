# Fit figures of docs/recording-format.md over a time window of a simulated recording:
#   nrmse = RMS(ref - est) / range(ref), max = max|ref - est| / range(ref), both in %.
# usage: awk -F, -v ref=S -v est=S_model [-v from=T0] [-v to=T1] -f figures.awk SIM.csv
# Prints "NRMSE MAX T_AT_MAX"; "nan nan nan" when the window is empty or the channels absent.
BEGIN { if (from == "") from = -1e300; if (to == "") to = 1e300 }
/^#/ { next }
!header { for (i = 1; i <= NF; ++i) col[$i] = i; header = 1
          if (!(ref in col) || !(est in col)) exit; next }
{
  t = $col["t"] + 0
  if (t < from || t >= to) next
  r = $col[ref] + 0; e = r - $col[est]; n++; ss += e * e
  if (n == 1 || r < lo) lo = r
  if (n == 1 || r > hi) hi = r
  a = e < 0 ? -e : e
  if (a > worst) { worst = a; at = t }
}
END {
  if (n == 0 || hi <= lo) { print "nan nan nan"; exit }
  printf "%.3f %.3f %.4g\n", 100 * sqrt(ss / n) / (hi - lo), 100 * worst / (hi - lo), at
}
