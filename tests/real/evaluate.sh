#!/usr/bin/env bash
# Evaluation on the measured data sets in ../shared/data/real (see docs/real-data.md): imports
# every set with `selfsense import`, identifies on one part, validates on another and prints
# nrmse and max per channel (docs/recording-format.md, in % of the recorded range of that part).
# The data are read where they lie and never copied into the repository (the disc set has no
# licence). Usage: evaluate.sh SELFSENSE_BINARY DATA_DIR [FIGURES_AWK]
# Exit status: 1 when an asserted figure or finding is missed, a step fails, or DATA_DIR or one
# of its data files is missing (each named); 0 otherwise. Goals that are not met yet are printed
# as NOT MET, not asserted. The data are there in CI: where they are optional (a checkout
# without ../shared), SELFSENSE_REAL_DATA_OPTIONAL=1 turns a missing file into a note and a
# missing DATA_DIR into exit 77 (CTest: skipped).
# shellcheck disable=SC2015 # "a && b || continue": skip the case when any step fails
set -Eeuo pipefail
bin=${1:?usage: evaluate.sh SELFSENSE_BINARY DATA_DIR [FIGURES_AWK]}
data=${2:?usage: evaluate.sh SELFSENSE_BINARY DATA_DIR [FIGURES_AWK]}
here=$(cd "$(dirname "$0")" && pwd)
fig_awk=${3:-$here/figures.awk}
optional=${SELFSENSE_REAL_DATA_OPTIONAL:-0}
if [ ! -d "$data" ]; then
  if [ "$optional" = 1 ]; then
    echo "SKIP: the real-data folder $data is absent (SELFSENSE_REAL_DATA_OPTIONAL=1)"
    exit 77
  fi
  echo "FAIL: the real-data folder $data is missing (set SELFSENSE_REAL_DATA_OPTIONAL=1 where" \
    "the real data is optional)" >&2
  exit 1
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
trap 'echo "real-data evaluation: FAILED (line $LINENO: $BASH_COMMAND)" >&2' ERR
failed=0
declare -a notes=()

# require FILE...: every data file is there. A missing one fails the evaluation, named; with
# SELFSENSE_REAL_DATA_OPTIONAL=1 it is a note. Returns 1 when any is missing (the set is skipped).
require() {
  local f missing=0
  for f in "$@"; do
    [ -f "$f" ] && continue
    missing=1
    if [ "$optional" = 1 ]; then
      notes+=("$f: absent, not evaluated (SELFSENSE_REAL_DATA_OPTIONAL=1)")
    else
      echo "FAIL: data file $f is missing (set SELFSENSE_REAL_DATA_OPTIONAL=1 where the real" \
        "data is optional)" >&2
      failed=1
    fi
  done
  return $missing
}

step() {  # runs a selfsense step quietly; its output is shown only when it fails
  if ! "$bin" "$@" >"$work/step.txt" 2>&1; then
    echo "FAIL: selfsense $*" >&2
    cat "$work/step.txt" >&2
    failed=1
    return 1
  fi
}

# diagnose NAME MODEL REC [VALIDATE]: runs `selfsense diagnose`, prints its findings and keeps
# the JSON and report in $SELFSENSE_REPORT_DIR when set (docs/diagnosis/ holds those of the
# licensed sets).
diagnose() {
  local name=$1 model=$2 rec=$3 val=${4:-}
  local args=(diagnose --model "$model" --recording "$rec" --json "$work/$name.json"
    --report "$work/$name.html" --out "$work/$name.improved.yaml")
  [ -n "$val" ] && args+=(--validate "$val")
  step "${args[@]}" || return 1
  sed -n 's/^  \([a-z_]* on [A-Z_a-z]* (explains [0-9]* %)\).*/\1/p' "$work/step.txt" |
    sed "s/^/diagnose $name: /"
  { grep -E '^  (fit|validation) ' "$work/step.txt" || true; } | sed "s/^ */diagnose $name: /"
  if [ -n "${SELFSENSE_REPORT_DIR:-}" ]; then
    mkdir -p "$SELFSENSE_REPORT_DIR"
    cp "$work/$name.json" "$work/$name.html" "$SELFSENSE_REPORT_DIR/"
  fi
}

# named JSON EFFECT CHANNEL: the diagnosis JSON names EFFECT on CHANNEL among its findings
# (only that it is named: its figures are the diagnosis's own business).
named() {
  python3 - "$@" <<'PY'
import json
import sys

path, effect, channel = sys.argv[1:4]
with open(path, encoding="utf-8") as f:
    findings = json.load(f).get("findings", [])
sys.exit(0 if any(x.get("effect") == effect and x.get("channel") == channel
                  for x in findings) else 1)
PY
}

identify() {  # identify REC STRUCTURE MODEL [options...]
  local rec=$1 structure=$2 model=$3
  shift 3
  step identify --recording "$rec" --structure "$structure" --out "$model" "$@"
}

printf '%-26s %-16s %-28s %-4s %9s %9s  %s\n' set structure split chan "nrmse %" "max %" goal
at_most() {  # at_most VALUE LIMIT: VALUE is a number <= LIMIT
  awk -v v="$1" -v l="$2" 'BEGIN { exit !(v != "nan" && v <= l) }'
}
# row SET STRUCTURE SPLIT SIM CHANNEL FROM TO [GOAL_KIND GOAL [BOUND]]: prints the figures and
# whether the goal (nrmse or max <= GOAL %) is met. With BOUND (about 1.3x of what the figure
# measures, below the goal) the figure is asserted <= BOUND %, so a regression fails.
row() {
  local set=$1 structure=$2 split=$3 sim=$4 chan=$5 from=$6 to=$7 kind=${8:-} limit=${9:-} \
    bound=${10:-}
  local est=${chan}_model
  local figs nrmse max verdict=""
  figs=$(awk -F, -v ref="$chan" -v est="$est" -v from="$from" -v to="$to" -f "$fig_awk" "$sim")
  read -r nrmse max _ <<<"$figs"
  if [ -n "$kind" ]; then
    local value=$nrmse
    [ "$kind" = max ] && value=$max
    if at_most "$value" "$limit"; then
      verdict="$kind <= $limit %: met"
    else
      verdict="$kind <= $limit %: NOT MET"
    fi
    if [ -n "$bound" ]; then
      if at_most "$value" "$bound"; then
        verdict="$verdict (asserted <= $bound %)"
      else
        failed=1
        verdict="$verdict (asserted <= $bound %: FAIL)"
      fi
    fi
  fi
  printf '%-26s %-16s %-28s %-4s %9s %9s  %s\n' "$set" "$structure" "$split" "$chan" "$nrmse" \
    "$max" "$verdict"
}

# --- smarthysteresis: piezo actuator, 1 Hz sine, voltage and displacement only --------------
# No geometry is given: a nominal one (h = 100 um layers, L = 36 mm) makes E and S; the figures
# are relative to the range and do not depend on it.
sh=$data/smarthysteresis-piezo-1hz/hysteresis_v_150_1hz.csv
if require "$sh" && step import columns "$sh" --map "2:t:s,3:x:um,4:u:V" \
  --layer-thickness-m 1e-4 --active-length-m 0.036 --out "$work/sh.csv"; then
  # preisach-creep chooses its dead zones and hinges on the fitting part alone (t < 7.3 s);
  # the goals are judged on the held-out part alone.
  for structure in linear preisach-creep; do
    identify "$work/sh.csv" "$structure" "$work/sh.yaml" --fit-until 7.3 &&
      step simulate --model "$work/sh.yaml" --recording "$work/sh.csv" --out "$work/sh_sim.csv" ||
      continue
    name=smarthysteresis-1hz
    row $name $structure "fit: t < 7.3 s" "$work/sh_sim.csv" S 0 7.3
    if [ "$structure" = linear ]; then
      row $name $structure "held out: t >= 7.3 s" "$work/sh_sim.csv" S 7.3 ""
    else
      # Measured 0.127 % and 0.714 % (goals 0.2 % and 1 %): asserted at about 1.3x.
      row $name $structure "held out: t >= 7.3 s" "$work/sh_sim.csv" S 7.3 "" nrmse 0.2 0.165
      row $name $structure "held out: t >= 7.3 s" "$work/sh_sim.csv" S 7.3 "" max 1 0.93
    fi
  done
  # The stack rings after the step at 3.257 s: diagnose must name dynamics on S there
  # (asserted), from the preisach-creep model of the last round.
  if diagnose smarthysteresis-1hz "$work/sh.yaml" "$work/sh.csv"; then
    # JSON keys are sorted: within a finding "effect" comes before "where", "t_end" before
    # "t_start".
    if ! awk '/"effect":/ { d = /"dynamics"/ } d && /"t_end"/ { e = $2 + 0 }
              d && /"t_start"/ { if ($2 + 0 <= 3.26 && e >= 3.26) ok = 1 }
              END { exit !ok }' "$work/smarthysteresis-1hz.json"; then
      echo "diagnose smarthysteresis-1hz: dynamics at t = 3.26 s not named (asserted: FAIL)"
      failed=1
    fi
  fi
fi

# --- rug PNZT disc (aixACCT): E, D and S; bipolar drive past the coercive field ------------
rug=$data/rug-pnzt-aixacct-eds
# rug_case NAME FILE FIT_BLOCK VALIDATION_BLOCK STRUCTURE [import options...]
rug_case() {
  local name=$1 file=$2 fit=$3 val=$4 structure=$5
  shift 5
  step import aixacct "$file" --block "$fit" --out "$work/rug_fit.csv" "$@" &&
    step import aixacct "$file" --block "$val" --out "$work/rug_val.csv" "$@" &&
    identify "$work/rug_fit.csv" "$structure" "$work/rug.yaml" --holdout 0 &&
    step simulate --model "$work/rug.yaml" --recording "$work/rug_fit.csv" \
      --out "$work/rug_fit_sim.csv" &&
    step simulate --model "$work/rug.yaml" --recording "$work/rug_val.csv" \
      --out "$work/rug_val_sim.csv" || return 0
  local sensed=D
  [ "$structure" = charge-drive ] && sensed=E
  row "$name" "$structure" "fit: block $fit" "$work/rug_fit_sim.csv" $sensed "" ""
  row "$name" "$structure" "held out: block $val" "$work/rug_val_sim.csv" $sensed "" ""
  row "$name" "$structure" "fit: block $fit" "$work/rug_fit_sim.csv" S "" ""
  row "$name" "$structure" "held out: block $val" "$work/rug_val_sim.csv" S "" "" nrmse 2
  # Asserted: the disc's strain past the coercive field (butterfly) under charge drive, named
  # `electrostriction` on S on the 800 V repeats (only that it is named: its figures are
  # measured-only); its polarization creeps during the holds, named on D from the field-drive
  # model without creep operators. The other charge-drive cases name nothing (measured-only;
  # a failed diagnose step is counted by step()).
  local report="${name//\//-}-$structure" after
  # The disc set has no licence: its reports are made here and never kept.
  local SELFSENSE_REPORT_DIR=
  case "$structure:$name" in
    charge-drive:rug-disc-800V-repeats)
      diagnose "$report" "$work/rug.yaml" "$work/rug_fit.csv" "$work/rug_val.csv" &&
        if ! named "$work/$report.json" electrostriction S; then
          echo "diagnose $report: electrostriction on S not named (asserted: FAIL)"
          failed=1
        fi
      ;;
    charge-drive:*)
      diagnose "$report" "$work/rug.yaml" "$work/rug_fit.csv" "$work/rug_val.csv" || true
      ;;
    hysteresis:rug-disc-holds)
      # ... and the structure with creep operators carries to the other block: validation D
      # 25.35 % -> 6.06 % (measured), asserted at 1.3x.
      diagnose "$report" "$work/rug.yaml" "$work/rug_fit.csv" "$work/rug_val.csv" &&
        if ! grep -q '^  creep on D ' "$work/step.txt"; then
          echo "diagnose $report: creep on D not named (asserted: FAIL)"
          failed=1
        elif ! after=$(sed -n 's/^  validation D .* -> \([0-9.]*\) %$/\1/p' "$work/step.txt") ||
          [ -z "$after" ] || ! at_most "$after" 7.9; then
          echo "diagnose $report: validation D after the creep ${after:-missing} %, above 7.9 % (asserted: FAIL)"
          failed=1
        fi
      ;;
  esac
}
if require "$rug/RMN_TRAP_SLOW.dat"; then
  for structure in hysteresis charge-drive; do
    rug_case rug-disc-800V-repeats "$rug/RMN_TRAP_SLOW.dat" 7 8 $structure
  done
  for structure in hysteresis charge-drive; do
    rug_case rug-disc-1Hz-1400V/1200V "$rug/RMN_TRAP_SLOW.dat" 6 5 $structure
  done
fi
if require "$rug/RMN_TRAP_1400V_1000V_CREEP.dat"; then
  for structure in hysteresis hysteresis-creep charge-drive; do
    rug_case rug-disc-holds "$rug/RMN_TRAP_1400V_1000V_CREEP.dat" 2 1 $structure --detrend-charge
  done
fi

# --- dbo micromanipulator: DAQ voltage -> capacitive sensor, 200 Hz, no time column ---------
# No geometry: nominal h = L = 1 m, so E and S are numerically u [V] and x [m].
dbo=$data/dbo-piezo-micromanipulator
if require "$dbo/Model_Vi_Do.dat" "$dbo/Test_Vi_Do_Di.dat" &&
  step import columns "$dbo/Model_Vi_Do.dat" --delimiter tab --sample-rate-hz 200 \
    --map "1:u:V,5:x:um" --layer-thickness-m 1 --active-length-m 1 --out "$work/dbo.csv" &&
  step import columns "$dbo/Test_Vi_Do_Di.dat" --delimiter tab --sample-rate-hz 200 \
    --map "1:u:V,5:x:um" --layer-thickness-m 1 --active-length-m 1 --out "$work/dbo_test.csv"; then
  for structure in linear hysteresis; do
    identify "$work/dbo.csv" $structure "$work/dbo.yaml" --fit-until 30 &&
      step simulate --model "$work/dbo.yaml" --recording "$work/dbo.csv" --out "$work/dbo_sim.csv" &&
      step simulate --model "$work/dbo.yaml" --recording "$work/dbo_test.csv" \
        --out "$work/dbo_test_sim.csv" || continue
    row dbo-micromanipulator $structure "fit: t < 30 s" "$work/dbo_sim.csv" S 0 30
    if [ $structure = hysteresis ]; then
      diagnose dbo-micromanipulator "$work/dbo.yaml" "$work/dbo.csv" "$work/dbo_test.csv" || true
      # Measured 0.562 % (goal 1 %): asserted at about 1.3x.
      row dbo-micromanipulator $structure "held out: t >= 30 s" "$work/dbo_sim.csv" S 30 "" \
        nrmse 1 0.73
      row dbo-micromanipulator $structure "Test_Vi_Do_Di (compens.)" "$work/dbo_test_sim.csv" S \
        "" "" nrmse 2
    else
      row dbo-micromanipulator $structure "held out: t >= 30 s" "$work/dbo_sim.csv" S 30 ""
      row dbo-micromanipulator $structure "Test_Vi_Do_Di (compens.)" "$work/dbo_test_sim.csv" S \
        "" ""
    fi
  done
fi

# --- kuleuven fine steering mirror: multisine 0.8 Hz - 3 kHz, u1 -> y1 only ----------------
# The 6 training and 3 test realizations (one steady-state period each) are joined; t is made
# from the 6400 Hz rate. Nominal h = L = 1 m as for dbo.
ku=$data/kuleuven-fsm-piezo-multisine/csv
if require "$ku/300mV_train.csv" "$ku/300mV_test.csv" &&
  step import columns "$ku/300mV_train.csv" --skip-rows 1 --sample-rate-hz 6400 \
    --map "3:u:V,6:x:m" --layer-thickness-m 1 --active-length-m 1 --out "$work/ku.csv" &&
  step import columns "$ku/300mV_test.csv" --skip-rows 1 --sample-rate-hz 6400 \
    --map "3:u:V,6:x:m" --layer-thickness-m 1 --active-length-m 1 --out "$work/ku_test.csv"; then
  for structure in linear hysteresis; do
    identify "$work/ku.csv" $structure "$work/ku.yaml" --holdout 0 &&
      step simulate --model "$work/ku.yaml" --recording "$work/ku.csv" --out "$work/ku_sim.csv" &&
      step simulate --model "$work/ku.yaml" --recording "$work/ku_test.csv" \
        --out "$work/ku_test_sim.csv" || continue
    row kuleuven-fsm-300mV-u1y1 $structure "fit: train (6 periods)" "$work/ku_sim.csv" S "" ""
    row kuleuven-fsm-300mV-u1y1 $structure "held out: test (3 periods)" "$work/ku_test_sim.csv" S \
      "" "" nrmse 2
    if [ $structure = hysteresis ]; then
      diagnose kuleuven-fsm-300mV "$work/ku.yaml" "$work/ku.csv" "$work/ku_test.csv" || true
    fi
  done
fi

for n in "${notes[@]}"; do echo "note: $n"; done
if [ $failed -ne 0 ]; then
  echo "real-data evaluation: FAILED (an asserted figure or finding was missed, a step failed or" \
    "a data file is missing)"
  exit 1
fi
if [ ${#notes[@]} -gt 0 ]; then
  echo "real-data evaluation: asserted figures and findings met on the data present" \
    "(${#notes[@]} data file(s) absent, optional)"
else
  echo "real-data evaluation: asserted figures and findings met"
fi
