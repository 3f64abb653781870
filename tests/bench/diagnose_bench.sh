#!/usr/bin/env bash
# Speed of `selfsense diagnose` on a 1e6-sample recording (issue 23: under 30 s on one core).
# Generates the diagnosis bench at 10 kHz (tests/diagnosis/data, 101.2 s: 1.012e6 samples),
# identifies the base model on the effect-free recording, then times the diagnosis of the one
# with charge leakage and creep on CPU 1. With `clean`, the diagnosed recording is another of the
# effect-free plant (another excitation seed): nothing is named, so every judgement by
# re-identification that runs where nothing is named does (the leak's on D, the lag's on both
# channels), the slowest case (docs/diagnose.md, "Speed"). Prints the wall time; not part of the
# test run.
#   tests/bench/diagnose_bench.sh build/src/cli/selfsense [clean]
set -euo pipefail
bin=${1:?usage: diagnose_bench.sh SELFSENSE_BINARY [clean]}
case=${2:-leakage_creep}
[ "$case" = leakage_creep ] || [ "$case" = clean ] || { echo "unknown case: $case" >&2; exit 2; }
root=$(cd "$(dirname "$0")/../.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for name in bench_base bench_leakage_creep; do
  sed 's/sample_rate_hz: 1000$/sample_rate_hz: 10000/' "$root/tests/diagnosis/data/$name.yaml" \
    >"$work/$name.yaml"
done
"$bin" plant --config "$work/bench_base.yaml" --excitation mix --seed 11 --out "$work/base.csv" >/dev/null
if [ "$case" = clean ]; then
  "$bin" plant --config "$work/bench_base.yaml" --excitation mix --seed 21 --out "$work/fit.csv" \
    >/dev/null
else
  "$bin" plant --config "$work/bench_leakage_creep.yaml" --excitation mix --seed 21 \
    --out "$work/fit.csv" >/dev/null
fi
"$bin" identify --recording "$work/base.csv" --structure hysteresis-creep \
  --out "$work/base.yaml" >/dev/null
rows=$(grep -vc '^#' "$work/fit.csv")
start=$(date +%s.%N)
taskset -c 1 "$bin" diagnose --model "$work/base.yaml" --recording "$work/fit.csv" \
  --json "$work/d.json" --report "$work/d.html" --out "$work/m.yaml" |
  { grep -E '^  [a-z_]+ on ' || echo "  nothing named"; }
end=$(date +%s.%N)
awk -v s="$start" -v e="$end" -v n="$((rows - 1))" \
  'BEGIN { printf "diagnose: %d samples in %.1f s on one core\n", n, e - s }'
