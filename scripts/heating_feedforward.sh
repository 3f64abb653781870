#!/usr/bin/env bash
# The main job's self-heating run (scripts/main_job.sh; config/heating-sim.yaml: a 200 Hz sine in
# open loop warms the stack, then position steps) twice on fresh daemons with adaptation on:
# `adaptation.feedforward_estimate: false` (as shipped: the feedforward's inverse as identified)
# and `true` (its inverse at the drift estimated from E and D; docs/adaptation.md, "The
# feedforward with the adapted parameters"). Per run, from the daemon's recording (armed rows),
# one line: the stack's rise over the sine; true S against the setpoint over the sine in open
# loop (RMS and mean, % of the setpoint's range there, which includes the rest before the sine);
# true S on the settled position steps (main_job_report.sh's rule: 0.2 s after each step, % of
# the setpoint's range).
#   scripts/heating_feedforward.sh BUILD_DIR OUT_DIR [RUNS]   (RUNS pairs, default 1)
set -euo pipefail
build=${1:?usage: scripts/heating_feedforward.sh BUILD_DIR OUT_DIR [RUNS]}
out=${2:?usage: scripts/heating_feedforward.sh BUILD_DIR OUT_DIR [RUNS]}
runs=${3:-1}
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cli=$build/src/cli/selfsense
daemon=$build/src/selfsensed/selfsensed
mkdir -p "$out"
out=$(cd "$out" && pwd)
run_dir=$out
# shellcheck source=scripts/daemon_runs.sh
source "$root/scripts/daemon_runs.sh"
config=$out/config/heating-feedforward.yaml
# shellcheck source=scripts/daemon_process.sh
source "$root/scripts/daemon_process.sh"
# figures NAME FILE: the run's line (header comment).
figures() {
  awk -F, -v name="$1" '
    /^#/ { next }
    !header { header = 1; for (i = 1; i <= NF; i++) col[$i] = i; next }
    $col["state"] != 2 { next }
    {
      n++; t[n] = $col["t"]; r[n] = $col["setpoint"]; x[n] = $col["S"]; mode[n] = $col["mode"]
      temp[n] = $col["temp"]
    }
    END {
      lo = hi = r[1]; last_jump = t[1]
      for (i = 1; i <= n; i++) { if (r[i] < lo) lo = r[i]; if (r[i] > hi) hi = r[i] }
      range = hi - lo
      for (i = 1; i <= n; i++) {
        if (mode[i] != 2) continue
        sine_end = i; so++; e = x[i] - r[i]; ss += e * e; sm += e
        if (!so_lo_set || r[i] < so_lo) so_lo = r[i]; if (!so_lo_set || r[i] > so_hi) so_hi = r[i]
        so_lo_set = 1
      }
      for (i = 2; i <= n; i++) {
        if ((r[i] - r[i - 1]) > 0.01 * range || (r[i - 1] - r[i]) > 0.01 * range) last_jump = t[i]
        if (t[i] - last_jump < 0.2 || mode[i] != 0) continue
        m++; ex += (x[i] - r[i]) ^ 2
      }
      printf "%s: rise %.1f K; sine in open loop: true S - setpoint %.3f %% RMS (mean %.3f %%) of %.4g; steps: true S %.3f %% RMS\n",
             name, temp[sine_end] - temp[1], 100 * sqrt(ss / so) / (so_hi - so_lo),
             100 * sm / so / (so_hi - so_lo), so_hi - so_lo, 100 * sqrt(ex / m) / range
    }' "$2"
}
for i in $(seq "$runs"); do
  for value in false true; do
    start_daemon "$root/config/heating-sim.yaml" \
      "s|^  feedforward_estimate: false|  feedforward_estimate: $value|" >/dev/null
    # A shipped file without the key would run both halves of the pair alike: fail instead.
    grep -q "^  feedforward_estimate: $value" "$config" || {
      echo "FAILED: config/heating-sim.yaml has no feedforward_estimate to set" >&2
      exit 1
    }
    watched_run "ff-$value-$i" open-loop heating_run >/dev/null
    # A daemon that exited with a fault must not leave its figures standing as a result.
    stop_daemon >"$out/ff-$value-$i.stop"
    grep -q "status 0$" "$out/ff-$value-$i.stop" || {
      echo "FAILED: $(cat "$out/ff-$value-$i.stop") (pair $i, feedforward_estimate $value)" >&2
      exit 1
    }
    figures "feedforward_estimate $value (pair $i)" "$(cat "$out/ff-$value-$i.path")"
  done
done
