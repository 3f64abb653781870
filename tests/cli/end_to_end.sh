#!/usr/bin/env bash
# End to end through the command line: plant -> identify -> simulate / reconstruct, and the
# error paths a user meets first. Usage: end_to_end.sh SELFSENSE_BINARY SOURCE_DIR
set -euo pipefail
bin=$1
src=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
# has_column FILE NAME: the header (first line that is not a comment) names the column. One awk,
# no pipe: `head | grep -q` fails under pipefail when grep exits before head (SIGPIPE).
has_column() { awk -F, -v c="$2" '!/^#/ { for (i = 1; i <= NF; ++i) if ($i == c) f = 1; exit } END { exit !f }' "$1"; }

cat >"$work/plant.yaml" <<'YAML'
plant:
  sample_rate_hz: 1000
  hysteresis: {enabled: true}
  creep: {enabled: true, tau_s: [0.05, 2.0], s_weights: [0.02, 0.02], d_weights: [0.01, 0.01]}
  mechanics: {enabled: false, load_stiffness_n_per_m: 0.0, load_force_n: -300.0}
excitation:
  decaying: {amplitude_v_per_m: 0.9e6, offset_v_per_m: 1.0e6, frequency_hz: 1.0, decay_per_cycle: 0.9, cycles: 20}
  load: {offset_n: 0.0, amplitude_n: 400.0, frequency_hz: 0.13}
YAML
"$bin" plant --config "$work/plant.yaml" --excitation decaying --out "$work/r.csv" >/dev/null
"$bin" identify --recording "$work/r.csv" --structure hysteresis-creep --out "$work/m.yaml" \
  --json "$work/m.json" --plays 12 --eigenvalues 3 >"$work/identify.txt"
grep -q '"held_out"' "$work/m.json" || fail "identify JSON has no held_out figures"
grep -q '^selfsense_model: 2' "$work/m.yaml" || fail "model file has no version"
tail -n 1 "$work/m.yaml" | grep -qx 'complete: true' || fail "model file does not end with its end marker"
# The fitted model explains S well on the held-out part (nrmse below 2 %).
held_s=$(sed -n 's/^  S  *[0-9.]* % *[0-9.]* % *\([0-9.]*\) %.*/\1/p' "$work/identify.txt")
awk -v v="$held_s" 'BEGIN { exit !(v != "" && v < 2.0) }' || fail "held-out S nrmse '$held_s' %"

# Temperature coefficients (docs/adaptation.md): the same plant warming 25 -> 55 degC (its
# permittivity +0.4 %/K) writes a temp column; identify fits the coefficients on it, stores them
# in the model and the JSON; reconstruct uses them with the recorded temperature.
{ sed '/^excitation:/,$d' "$work/plant.yaml"
  printf '  temperature: {enabled: true, reference_degc: 25.0, permittivity_coefficient_per_k: 4.0e-3}\n'
  sed -n '/^excitation:/,$p' "$work/plant.yaml"
  printf '  temperature: {start_degc: 25.0, end_degc: 55.0}\n'; } >"$work/warm.yaml"
"$bin" plant --config "$work/warm.yaml" --excitation decaying --seed 2 --out "$work/rw.csv" >/dev/null
has_column "$work/rw.csv" temp || fail "the warming plant wrote no temp column"
"$bin" identify --recording "$work/r.csv" --structure hysteresis-creep --out "$work/mt.yaml" \
  --json "$work/mt.json" --plays 12 --eigenvalues 3 --temperature-recording "$work/rw.csv" \
  >"$work/identify-temp.txt"
grep -q '^temperature:' "$work/mt.yaml" || fail "identify stored no temperature coefficients"
grep -q '"temperature"' "$work/mt.json" || fail "identify JSON has no temperature figures"
per_k=$(sed -n 's/^  sensor   permittivity \([-+0-9.e]*\) .*/\1/p' "$work/identify-temp.txt")
awk -v v="$per_k" 'BEGIN { exit !(v != "" && v + 0 > 2e-3 && v + 0 < 6e-3) }' ||
  fail "fitted permittivity per K '$per_k' (the plant's 4e-3)"
"$bin" reconstruct --model "$work/mt.yaml" --recording "$work/rw.csv" --adapt \
  --temperature-column temp --out "$work/rt.csv" >/dev/null || fail "reconstruct with coefficients"
# Recordings of the same plant held near 25, 40 and 55 degC (each drifting by 0.5 K, too little
# to fit on alone; a constant one writes no temp column) fit the coefficients together.
for c in 25 40 55; do
  sed "s/start_degc: 25.0, end_degc: 55.0/start_degc: $c.0, end_degc: $c.5/" "$work/warm.yaml" \
    >"$work/at$c.yaml"
  "$bin" plant --config "$work/at$c.yaml" --excitation decaying --seed 2 --out "$work/at$c.csv" \
    >/dev/null
done
"$bin" identify --recording "$work/r.csv" --structure hysteresis-creep --out "$work/mf.yaml" \
  --plays 12 --eigenvalues 3 --temperature-recording "$work/at25.csv" "$work/at40.csv" \
  --temperature-recording "$work/at55.csv" >"$work/identify-fixed.txt" ||
  fail "identify on recordings at three temperatures"
per_k=$(sed -n 's/^  sensor   permittivity \([-+0-9.e]*\) .*/\1/p' "$work/identify-fixed.txt")
awk -v v="$per_k" 'BEGIN { exit !(v != "" && v + 0 > 2e-3 && v + 0 < 6e-3) }' ||
  fail "permittivity per K from three fixed temperatures '$per_k' (the plant's 4e-3)"

"$bin" simulate --model "$work/m.yaml" --recording "$work/r.csv" --out "$work/sim.csv" >/dev/null
has_column "$work/sim.csv" D_model || fail "simulate wrote no D_model"
has_column "$work/sim.csv" S_model || fail "simulate wrote no S_model"
"$bin" reconstruct --model "$work/m.yaml" --recording "$work/r.csv" --out "$work/rec.csv" >/dev/null
has_column "$work/rec.csv" T_hat || fail "reconstruct wrote no T_hat"
# --adapt (docs/adaptation.md): on a recording at the identification temperature the drift
# estimate learns from the moving field and stays near 25 degC; a missing temperature column
# is named.
"$bin" reconstruct --model "$work/m.yaml" --recording "$work/r.csv" --adapt --out "$work/ad.csv" >"$work/ad.txt"
has_column "$work/ad.csv" temp_equivalent || fail "reconstruct --adapt wrote no temp_equivalent"
has_column "$work/ad.csv" S_hat || fail "reconstruct --adapt wrote no S_hat"
eq=$(sed -n 's/^adaptation: \([0-9]*\) updates;.*equivalent temperature \([0-9.-]*\) degC.*/\1 \2/p' "$work/ad.txt")
awk -v u="${eq%% *}" -v t="${eq##* }" 'BEGIN { exit !(u > 100 && t > 24 && t < 26) }' ||
  fail "reconstruct --adapt: updates and equivalent temperature '$eq'"
if "$bin" reconstruct --model "$work/m.yaml" --recording "$work/r.csv" --adapt \
  --temperature-column nope --out "$work/x.csv" 2>"$work/err.txt"; then
  fail "a missing temperature column was accepted"
fi
grep -q "no column 'nope'" "$work/err.txt" || fail "missing temperature column not named: $(cat "$work/err.txt")"

# preisach-creep: the identification excitation (mix, then minor loops), sizes chosen on the
# fitting data and said, hinges in the model file, the model runs in reconstruct.
printf 'plant:\n  sample_rate_hz: 500\n  hysteresis: {enabled: true}\nexcitation:\n  loops: {duration_s: 20}\n' >"$work/loops.yaml"
"$bin" plant --config "$work/loops.yaml" --excitation loops --out "$work/loops.csv" >/dev/null
"$bin" identify --recording "$work/loops.csv" --structure preisach-creep --out "$work/p.yaml" \
  --plays 8 --eigenvalues 2 --dead-zones 2 >"$work/p.txt"
grep -q '^sizes chosen on the fitting data (dead zones given):' "$work/p.txt" ||
  fail "preisach-creep did not say its sizes: $(cat "$work/p.txt")"
grep -q '^structure: preisach-creep' "$work/p.yaml" || fail "model is not preisach-creep"
"$bin" identify --recording "$work/loops.csv" --structure preisach-creep --out "$work/p3.yaml" \
  --plays 8 --eigenvalues 2 --bias-levels 3 >/dev/null
grep -q '^  hinges:' "$work/p3.yaml" || fail "--bias-levels 3 wrote no hinges"
"$bin" reconstruct --model "$work/p3.yaml" --recording "$work/loops.csv" --out "$work/prec.csv" >/dev/null
has_column "$work/prec.csv" S_hat || fail "preisach-creep reconstruct wrote no S_hat"

# Without a T column: the free actuator (T = 0), actuator and sensor sides still fitted.
cut -d, -f1-4 "$work/r.csv" | grep -v '^#' >"$work/free.csv"
[ "$(sed -n 1p "$work/free.csv")" = "t,E,D,S" ] || fail "unexpected plant columns: $(head -n 1 "$work/free.csv")"
"$bin" identify --recording "$work/free.csv" --structure hysteresis --out "$work/free.yaml" \
  --json "$work/free.json" >"$work/free.txt" || fail "identify without T failed"
grep -q 'no T: free actuator' "$work/free.txt" || fail "identify did not say T is absent"

# The stress-dependent (vectorial) model: identified, saved, loaded, reconstructed numerically.
"$bin" identify --recording "$work/r.csv" --structure stress-hysteresis --out "$work/v.yaml" \
  --plays 8 >/dev/null
grep -q '^vectorial:' "$work/v.yaml" || fail "stress-hysteresis model has no vectorial section"
"$bin" reconstruct --model "$work/v.yaml" --recording "$work/r.csv" --out "$work/vrec.csv" 2>/dev/null
has_column "$work/vrec.csv" T_hat || fail "vectorial reconstruct wrote no T_hat"
if "$bin" reconstruct --model "$work/v.yaml" --recording "$work/r.csv" --adapt --out "$work/x.csv" 2>"$work/err.txt"; then
  fail "reconstruct --adapt accepted the stress-dependent model"
fi
grep -q "stress-dependent" "$work/err.txt" || fail "--adapt refusal not explained: $(cat "$work/err.txt")"

# The paced plant (the daemon's simulated backend): real time at 1 kHz, overruns reported.
printf 'plant:\n  sample_rate_hz: 1000\nexcitation:\n  steps: {levels_v_per_m: [1.0e6, 0.0], hold_s: 0.1}\n' >"$work/paced.yaml"
start=$(date +%s%N)
"$bin" plant --config "$work/paced.yaml" --excitation steps --out "$work/paced.csv" --realtime >"$work/paced.txt"
elapsed_ms=$(( ($(date +%s%N) - start) / 1000000 ))
grep -q 'paced in real time' "$work/paced.txt" || fail "no pacing report"
[ "$elapsed_ms" -ge 150 ] || fail "paced run of about 0.2 s took only $elapsed_ms ms"

# Bad input: a clear one-line error naming file, line and column, and a non-zero status.
printf 't,E,D\n0,1,2\n0.001,abc,3\n' >"$work/bad.csv"
if "$bin" reconstruct --model "$work/m.yaml" --recording "$work/bad.csv" --out "$work/x.csv" 2>"$work/err.txt"; then
  fail "a non-numeric cell was accepted"
fi
grep -q "bad.csv:3: column 'E'" "$work/err.txt" || fail "error does not name line and column: $(cat "$work/err.txt")"
[ ! -e "$work/x.csv" ] || fail "an output was written despite the error"
if "$bin" identify --recording "$work/r.csv" --structure preisach --out "$work/y.yaml" 2>"$work/err.txt"; then
  fail "an unknown structure was accepted"
fi
grep -q "not one of linear" "$work/err.txt" || fail "unknown structure message: $(cat "$work/err.txt")"
sed 's/^structure: hysteresis-creep/structure: hysteresis-creep\nbogus: 1/' "$work/m.yaml" >"$work/bad.yaml"
if "$bin" simulate --model "$work/bad.yaml" --recording "$work/r.csv" --out "$work/x.csv" 2>"$work/err.txt"; then
  fail "an unknown model key was accepted"
fi
grep -q "bad.yaml:3: bogus" "$work/err.txt" || fail "model error: $(cat "$work/err.txt")"
echo "end-to-end: 1 passed, 0 failed"
