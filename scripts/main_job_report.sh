#!/usr/bin/env bash
# Figures and plots of the main job's recordings (scripts/main_job.sh): for each tracking segment
# the RMS error of the self-sensed signal and of the plant's true one against the setpoint, in %
# of the setpoint's range, over the settled samples (0.2 s after each setpoint step on); for the
# damping run's segments (undamped, damped) the ring-down after the impulse: the time from the
# largest deviation of true S (and of S_hat) from its rest to the last sample outside 5 % of that
# deviation, the rest being the mean of the recording's last 40 %. The HTML page
# (OUT_DIR/main_job.html) is written by `selfsense main-job-page` with the reports' plotting code:
# per segment its figures line and plots with axes in s, 1e-6 of strain, MPa and kV/mm, the
# tracking error under each run, spans outside the armed state and faults marked; and the faulted
# runs the main job repeated (OUT_DIR/faults.txt) with the recordings they spoiled.
# For the self-heating segments (heating-adapted, heating-plain: a fast sine in open loop, then
# position steps) the position figures over the steps (the settled samples in position mode; the
# sine never settles anyway: its setpoint moves by more than 1 % of the range per sample), then the self-sensing error S_hat - S over the
# settled samples of the steps (in % of the setpoint's range) and over the sine (in % of true S's
# range there), the plant's temperature (`temp`) at the start, at the sine's end (the last
# open-loop sample) and at the end, and the adaptation's equivalent temperature
# (`temp_equivalent`) at the same moments; and one line `self-heating:` setting the two runs
# beside each other.
# Figures count the samples of the armed state only (the recording's `state` column); each line
# says how many others it excluded. A recording in which the loop faulted gets no figure: a line
# naming the fault's time, cycle and faults instead, and the exit status is 1 once the page is
# written.
#   scripts/main_job_report.sh OUT_DIR SEGMENT...   (SEGMENT.path holds its recording's path)
# SELFSENSE_CLI: the selfsense tool (default: build/src/cli/selfsense of this tree).
set -euo pipefail
out=${1:?usage: scripts/main_job_report.sh OUT_DIR SEGMENT...}
shift
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cli=${SELFSENSE_CLI:-$root/build/src/cli/selfsense}
[ -x "$cli" ] || { echo "FAILED: no selfsense tool at $cli (set SELFSENSE_CLI)" >&2; exit 1; }
rm -f "$out/figures.txt" "$out/main_job.html"
# The armed samples of a recording (awk, before the segment's own rules): `state` 2 is armed;
# others are counted in `excluded`, the first faulted one (state 0) kept: its t, cycle, faults.
armed_only='
  function fault_names(bits,   i, s) {
    split("power_up driver_error driver_timeout stale_sample input_not_finite input_out_of_range estimate_out_of_range reconstruction overrun watchdog amplifier_fault", fault_name, " ")
    for (i = 1; i <= 11; i++) if (int(bits / 2 ^ (i - 1)) % 2) s = s (s == "" ? "" : ", ") fault_name[i]
    return s == "" ? "none latched" : s
  }
  /^#/ { next }
  !header { for (i = 1; i <= NF; i++) col[$i] = i; header = 1; next }
  $col["state"] != 2 {
    excluded++
    if ($col["state"] == 0 && !faulted++) { fault_t = $col["t"]; fault_cycle = $col["cycle"]; fault_bits = $col["faults"] }
    next
  }
  # no_figure(): true (and a line said why) when the recording faulted or has no armed sample.
  function no_figure(seg, n) {
    if (faulted) {
      printf "%s: no figure: the loop faulted at t = %.10g s (cycle %d: %s); %d of %d samples outside the armed state\n",
             seg, fault_t, fault_cycle, fault_names(fault_bits), excluded, n + excluded
      return 1
    }
    if (n == 0) { printf "%s: no figure: no sample in the armed state (%d outside it)\n", seg, excluded; return 1 }
    return 0
  }
'
# ring_down SEGMENT FILE: the figures line on stdout.
ring_down() {
  awk -F, -v seg="$1" "$armed_only"'
    { n++; t[n] = $col["t"]; x[n] = $col["S"]; h[n] = $col["S_hat"] }
    function rest(v,   i, m, s) { for (i = int(0.6 * n); i <= n; i++) { s += v[i]; m++ } return s / m }
    function ring(v, base,   i, d, peak, at, last) {
      peak = 0; at = 1
      for (i = 1; i <= n; i++) { d = v[i] - base; if (d < 0) d = -d; if (d > peak) { peak = d; at = i } }
      last = at
      for (i = at; i <= n; i++) { d = v[i] - base; if (d < 0) d = -d; if (d > 0.05 * peak) last = i }
      PEAK = peak
      return t[last] - t[at]
    }
    END {
      if (no_figure(seg, n)) exit 1
      bx = rest(x); bh = rest(h)
      rh = ring(h, bh); rx = ring(x, bx); peak = PEAK
      printf "%s: %d armed samples (%d outside the armed state excluded), peak deviation of true S %.3g, ring-down to 5 %%: true S %.1f ms, S_hat %.1f ms\n",
             seg, n, excluded, peak, 1000 * rx, 1000 * rh
    }' "$2"
}

# heating SEGMENT FILE: the self-heating run's figures line on stdout.
heating() {
  awk -F, -v seg="$1" "$armed_only"'
    {
      n++; t[n] = $col["t"]; r[n] = $col["setpoint"]; h[n] = $col["S_hat"]; x[n] = $col["S"]
      mode[n] = $col["mode"]
      temp[n] = ("temp" in col) ? $col["temp"] : "nan"
      eq[n] = ("temp_equivalent" in col) ? $col["temp_equivalent"] : "nan"
    }
    function degc(v) { return v == "nan" ? "-" : sprintf("%.1f", v) }
    END {
      if (no_figure(seg, n)) exit 1
      lo = hi = r[1]; last_jump = t[1]
      for (i = 1; i <= n; i++) { if (r[i] < lo) lo = r[i]; if (r[i] > hi) hi = r[i] }
      range = hi - lo
      sine_end = 0; slo = shi = x[1]
      for (i = 1; i <= n; i++) {
        if (mode[i] != 2) continue
        sine_end = i; ss += (h[i] - x[i]) ^ 2; sn++
        if (x[i] < slo) slo = x[i]; if (x[i] > shi) shi = x[i]
      }
      for (i = 2; i <= n; i++) {
        if ((r[i] - r[i - 1]) > 0.01 * range || (r[i - 1] - r[i]) > 0.01 * range) last_jump = t[i]
        if (t[i] - last_jump < 0.2 || mode[i] != 0) continue  # position mode only
        m++; eh += (h[i] - r[i]) ^ 2; ex += (x[i] - r[i]) ^ 2; es += (h[i] - x[i]) ^ 2
      }
      if (m == 0 || sine_end == 0) { printf "%s: no figure: %d settled samples, %d of the sine\n", seg, m, sn; exit 1 }
      printf "%s: %d armed samples (%d settled; %d outside the armed state excluded), setpoint range %.4g to %.4g (strain): S_hat %.3f %% RMS, true S %.3f %% RMS; S_hat - S %.3f %% RMS on the steps, %.3f %% RMS of its range over the sine; plant %s -> %s degC at the sine'"'"'s end (t = %.2f s), %s at the end; equivalent %s -> %s degC, %s at the end\n",
             seg, n, m, excluded, lo, hi, 100 * sqrt(eh / m) / range, 100 * sqrt(ex / m) / range,
             100 * sqrt(es / m) / range, 100 * sqrt(ss / sn) / (shi - slo),
             degc(temp[1]), degc(temp[sine_end]), t[sine_end], degc(temp[n]),
             degc(eq[1]), degc(eq[sine_end]), degc(eq[n])
    }' "$2"
}

faulted=0
for segment in "$@"; do
  file=$(cat "$out/$segment.path")
  if [ "$segment" = undamped ] || [ "$segment" = damped ]; then
    ring_down "$segment" "$file" | tee -a "$out/figures.txt" || faulted=1
    continue
  fi
  if [ "$segment" = heating-adapted ] || [ "$segment" = heating-plain ]; then
    heating "$segment" "$file" | tee -a "$out/figures.txt" || faulted=1
    continue
  fi
  # position: S_hat and S against a strain setpoint; force: T_hat and T against a stress one.
  if [ "$segment" = force ]; then hat=T_hat truth=T unit=' Pa'; else hat=S_hat truth=S unit=' (strain)'; fi
  awk -F, -v hat="$hat" -v truth="$truth" -v seg="$segment" -v unit="$unit" "$armed_only"'
    { n++; t[n] = $col["t"]; r[n] = $col["setpoint"]; h[n] = $col[hat]; x[n] = $col[truth] }
    END {
      if (no_figure(seg, n)) exit 1
      lo = hi = r[1]; last_jump = t[1]
      for (i = 1; i <= n; i++) { if (r[i] < lo) lo = r[i]; if (r[i] > hi) hi = r[i] }
      range = hi - lo
      for (i = 2; i <= n; i++) {
        if ((r[i] - r[i - 1]) > 0.01 * range || (r[i - 1] - r[i]) > 0.01 * range) last_jump = t[i]
        if (t[i] - last_jump < 0.2) continue
        m++; eh += (h[i] - r[i]) ^ 2; ex += (x[i] - r[i]) ^ 2
      }
      printf "%s: %d armed samples (%d settled; %d outside the armed state excluded), setpoint range %.4g to %.4g%s: %s %.3f %% RMS, true %s %.3f %% RMS\n",
             seg, n, m, excluded, lo, hi, unit, hat, 100 * sqrt(eh / m) / range, truth, 100 * sqrt(ex / m) / range
    }' "$file" | tee -a "$out/figures.txt" || faulted=1
done
if grep -q '^undamped: .* ring-down to 5' "$out/figures.txt" && grep -q '^damped: .* ring-down to 5' "$out/figures.txt"; then
  ms() { sed -n "s/^$1: .* true S \([0-9.]*\) ms, S_hat \([0-9.]*\) ms/\\$2/p" "$out/figures.txt"; }
  awk -v ux="$(ms undamped 1)" -v dx="$(ms damped 1)" -v uh="$(ms undamped 2)" -v dh="$(ms damped 2)" \
    'BEGIN { printf "damping: ring-down shortened %.1fx on true S, %.1fx on S_hat (goal 10x)\n", ux / dx, uh / dh }' |
    tee -a "$out/figures.txt"
fi
if grep -q '^heating-adapted: .* true S' "$out/figures.txt" && grep -q '^heating-plain: .* true S' "$out/figures.txt"; then
  pct() { sed -n "s/^$1: .* true S \([0-9.]*\) % RMS; S_hat - S \([0-9.]*\) % RMS on the steps.*/\\$2/p" "$out/figures.txt"; }
  rise() { sed -n "s/^$1: .* plant \([0-9.]*\) -> \([0-9.]*\) degC at the sine.*/\\1 \\2/p" "$out/figures.txt" | awk '{ printf "%.1f", $2 - $1 }'; }
  printf 'self-heating: the sine warmed the stack by %s K; on the position steps true S %s %% RMS with adaptation, %s %% without (goal 0.5 %%); S_hat - S %s %% and %s %%\n' \
    "$(rise heating-adapted)" "$(pct heating-adapted 1)" "$(pct heating-plain 1)" "$(pct heating-adapted 2)" "$(pct heating-plain 2)" |
    tee -a "$out/figures.txt"
fi
"$cli" main-job-page "$out" "$@" || faulted=1
[ "$faulted" = 0 ] || { echo "a recording has faulted samples: no figure for it" >&2; exit 1; }
