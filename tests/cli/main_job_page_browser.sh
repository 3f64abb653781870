#!/usr/bin/env bash
# The main job's page in a real browser: recordings in the daemon's format (written here at
# 1 kHz: a position staircase, force steps, an undamped and a damped ring-down, and a position
# run that faulted) go through scripts/main_job_report.sh (the figures) and `selfsense
# main-job-page` (the page) as the main job's would; headless Chromium opens the page without
# console messages, parses every inline SVG, and the rendered DOM holds the axes' text (time in
# s, strain in 1e-6, stress in MPa, field in kV/mm), the legend, the tracking error panels and
# the fault's mark. The checks are run on the page without its axes' text too, which must fail
# them. (One browser start, a few seconds: the pixels of plots are the diagnosis report's test.)
# Usage: main_job_page_browser.sh SELFSENSE SOURCE_DIR. Fails (not skips) without chromium.
set -euo pipefail
cli=$1
root=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
command -v chromium >/dev/null || fail "chromium is not installed (scripts/setup.sh installs it)"

browser() {
  timeout 25 chromium --headless=new --no-sandbox --disable-gpu --no-first-run \
    --user-data-dir="$work/profile" --window-size=1200,3000 --hide-scrollbars \
    --enable-logging=stderr --v=0 "$@"
}

# recording FILE KIND [FAULT_AT]: the daemon's columns (src/daemon/csv_row.cpp) with the
# references; KIND position, force or ring (0.7 s, an impulse at 0.1 s; TAU its decay).
recording() {
  awk -v kind="$2" -v fault_at="${3:-0}" -v tau="${4:-0.15}" 'BEGIN {
    print "# selfsensed recording (test)"
    print "t,E,D,T_hat,S_hat,setpoint,command,state,S,T,mode,faults,estimate_status,driver_status,nonfinite,cycle"
    pi = 3.141592653589793
    if (kind == "position") { split("1.5e-4 6.0e-4 1.05e-3 3.5e-4 8.0e-4", level, " "); steps = 5; mode = 0 }
    if (kind == "force") { split("-5.0e6 -8.0e6 -6.0e6", level, " "); steps = 3; mode = 1 }
    n = kind == "ring" ? 700 : 800 * steps
    y = kind == "ring" ? 6e-4 : level[1]
    for (i = 0; i < n; i++) {
      t = 20 + i / 1000
      if (kind == "ring") {
        sp = 6e-4; dt = t - 20.1
        s = dt < 0 ? sp : sp + 5e-5 * exp(-dt / tau) * sin(2 * pi * 300 * dt)
        sh = s + 1e-7; th = 0; tt = 0
      } else {
        sp = level[int(i / 800) + 1]
        y += (sp - y) * 0.05  # a first-order lag of 20 ms
        if (kind == "position") { sh = y + 2e-7 * sin(i); s = y * 1.002; th = 0; tt = 0 }
        else { th = y + 2e3 * sin(i); tt = y * 1.01; sh = 3e-4; s = 3e-4 }
      }
      state = (fault_at > 0 && t >= fault_at) ? 0 : 2
      faults = state == 0 ? 256 : 0  # overrun
      e = kind == "force" ? 1e6 : 2e9 * sh
      printf "%.9g,%.9g,0.01,%.9g,%.9g,%.9g,%.9g,%d,%.9g,%.9g,%d,%d,0,0,0,%d\n",
             t, e, th, sh, kind == "force" ? sp : (kind == "ring" ? 6e-4 : sp), e, state, s, tt, mode, faults, 200000 + i
    }
  }' >"$1"
}

out=$work/job
mkdir -p "$out" "$work/rec"
recording "$work/rec/position-1.csv" position 21.5
recording "$work/rec/position-2.csv" position
recording "$work/rec/force.csv" force
recording "$work/rec/undamped.csv" ring 0 0.15
recording "$work/rec/damped.csv" ring 0 0.01
echo "$work/rec/position-2.csv" >"$out/position.path"
echo "$work/rec/force.csv" >"$out/force.path"
echo "$work/rec/undamped.csv" >"$out/undamped.path"
echo "$work/rec/damped.csv" >"$out/damped.path"
{
  echo "FAULT: position: run 1 of 2: overrun at cycle 201500 (t = 21.5 s): the loop missed its deadlines beyond safety.overrun; recording: $work/rec/position-1.csv"
  echo "position: run 2 of 2 clean"
} >"$out/faults.txt"

SELFSENSE_CLI=$cli bash "$root/scripts/main_job_report.sh" "$out" position force undamped damped \
  >"$work/report.txt" 2>&1 || { cat "$work/report.txt" >&2; fail "the report failed"; }
cat "$work/report.txt"
grep -Eq '^position: 4000 armed samples \([0-9]+ settled; 0 outside the armed state excluded\), setpoint range 0.00015 to 0.00105 \(strain\): S_hat [0-9.]+ % RMS, true S [0-9.]+ % RMS$' \
  "$out/figures.txt" || fail "position figure: $(cat "$out/figures.txt")"
grep -Eq '^force: .*, setpoint range -8e\+06 to -5e\+06 Pa: T_hat [0-9.]+ % RMS, true T [0-9.]+ % RMS$' \
  "$out/figures.txt" || fail "force figure: $(cat "$out/figures.txt")"
grep -q '^damping: ring-down shortened' "$out/figures.txt" || fail "no damping figure"
page=$out/main_job.html
[ -s "$page" ] || fail "no page written"

browser --dump-dom "file://$page" >"$work/dom.html" 2>"$work/dom.log" ||
  { tail -20 "$work/dom.log" >&2; fail "chromium could not load the page"; }
if grep -a ':CONSOLE' "$work/dom.log" >&2; then fail "the page logged console messages"; fi

# check DOM FILE: the page's plots parsed, with their axes' text; prints what is missing.
check() {
  local dom=$1 file=$2 svg_file svg_dom text missing=0
  svg_file=$(grep -o '<svg' "$file" | wc -l)
  svg_dom=$(grep -o '<svg' "$dom" | wc -l)
  # position, force: setpoint, error, field; the faulted run too; undamped, damped: 2 each.
  [ "$svg_file" -eq 13 ] || { echo "the page has $svg_file plots, not 13"; missing=1; }
  [ "$svg_dom" -eq "$svg_file" ] || { echo "the browser parsed $svg_dom of $svg_file plots"; missing=1; }
  while IFS= read -r text; do
    grep -qF ">$text</text>" "$dom" || { echo "no '$text' in the rendered page"; missing=1; }
  done <<'EOF'
time t [s]
strain S [1e-6]
stress T [MPa]
field E [kV/mm]
error [1e-6]
error [MPa]
strain S - rest [1e-6]
S_hat - S [1e-6]
position: tracking error
force: tracking error
setpoint
S_hat (self-sensed)
S (plant, true)
T_hat (self-sensed)
fault latched
faulted
1000
21.5
EOF
  return "$missing"
}
check "$work/dom.html" "$page" >&2 || fail "the rendered page lacks plots or axes"
# Control: the same page without its axis labels and ticks must fail the check.
sed -e 's|<text[^>]*>[^<]*</text>||g' "$work/dom.html" >"$work/bare.html"
if check "$work/bare.html" "$page" >/dev/null; then fail "a page without axes' text passes the check"; fi

echo "browser: the main job's page renders with its axes"
