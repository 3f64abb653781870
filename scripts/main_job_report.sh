#!/usr/bin/env bash
# Figures and plots of the main job's recordings (scripts/main_job.sh): for each segment the RMS
# error of the self-sensed signal and of the plant's true one against the setpoint, in % of the
# setpoint's range, over the settled samples (0.2 s after each setpoint step on), and an HTML
# page with an inline SVG plot per segment.
#   scripts/main_job_report.sh OUT_DIR SEGMENT...   (SEGMENT.path holds its recording's path)
set -euo pipefail
out=${1:?usage: scripts/main_job_report.sh OUT_DIR SEGMENT...}
shift
html=$out/main_job.html
{
  echo '<!doctype html><html><head><meta charset="utf-8"><title>selfsense main job</title>'
  echo '<style>body{font-family:sans-serif;margin:2em}svg{border:1px solid #ccc}</style></head><body>'
  echo '<h1>selfsensed on the simulated transducer</h1>'
} >"$html"
for segment in "$@"; do
  file=$(cat "$out/$segment.path")
  # position: S_hat and S; force: T_hat and T.
  if [ "$segment" = force ]; then hat=T_hat truth=T unit=Pa; else hat=S_hat truth=S unit=-; fi
  awk -F, -v hat="$hat" -v truth="$truth" -v seg="$segment" -v unit="$unit" -v svg="$out/$segment.svg" '
    /^#/ { next }
    !header { for (i = 1; i <= NF; i++) col[$i] = i; header = 1; next }
    { n++; t[n] = $col["t"]; r[n] = $col["setpoint"]; h[n] = $col[hat]; x[n] = $col[truth] }
    END {
      lo = hi = r[1]; last_jump = t[1]
      for (i = 1; i <= n; i++) { if (r[i] < lo) lo = r[i]; if (r[i] > hi) hi = r[i] }
      range = hi - lo
      for (i = 2; i <= n; i++) {
        if ((r[i] - r[i - 1]) > 0.01 * range || (r[i - 1] - r[i]) > 0.01 * range) last_jump = t[i]
        if (t[i] - last_jump < 0.2) continue
        m++; eh += (h[i] - r[i]) ^ 2; ex += (x[i] - r[i]) ^ 2
      }
      printf "%s: %d samples (%d settled), setpoint range %.4g %s: %s %.3f %% RMS, true %s %.3f %% RMS\n",
             seg, n, m, range, unit, hat, 100 * sqrt(eh / m) / range, truth, 100 * sqrt(ex / m) / range
      # plot: setpoint black, estimate blue, truth red; about 1500 points
      W = 900; H = 300; step = int(n / 1500) + 1
      ylo = lo - 0.1 * range; yhi = hi + 0.1 * range
      printf "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\">\n", W, H > svg
      split("r h x", names, " "); split("black #1f77b4 #d62728", colours, " ")
      for (k = 1; k <= 3; k++) {
        printf "<polyline fill=\"none\" stroke=\"%s\" stroke-width=\"1\" points=\"", colours[k] > svg
        for (i = 1; i <= n; i += step) {
          v = (k == 1) ? r[i] : (k == 2) ? h[i] : x[i]
          printf "%.1f,%.1f ", W * (t[i] - t[1]) / (t[n] - t[1]), H * (yhi - v) / (yhi - ylo) > svg
        }
        print "\"/>" > svg
      }
      print "</svg>" > svg
    }' "$file" | tee -a "$out/figures.txt"
  {
    echo "<h2>$segment</h2><p>$(tail -1 "$out/figures.txt")</p>"
    echo "<p>black: setpoint, blue: $hat (self-sensed), red: $truth (the plant's truth, never seen by the loop)</p>"
    cat "$out/$segment.svg"
  } >>"$html"
done
echo '</body></html>' >>"$html"
echo "wrote $html"
