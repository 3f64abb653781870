#!/usr/bin/env bash
# `selfsense import`: aixACCT ASCII export and generic delimited text, on small files written
# here; values, metadata, and errors that name file, line and column. Usage: import_test.sh BIN
set -euo pipefail
bin=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
passed=0
ok() { passed=$((passed + 1)); }
# value of column NAME in data row ROW (1-based) of a recording
cell() { awk -F, -v name="$2" -v row="$3" '/^#/ { next } !h { for (i = 1; i <= NF; ++i) c[$i] = i;
  h = 1; next } ++n == row { print $c[name]; exit }' "$1"; }
near() { awk -v a="$1" -v b="$2" 'BEGIN { d = a - b; if (d < 0) d = -d; s = b < 0 ? -b : b;
  exit !(d <= 1e-12 * s + 1e-300) }' || fail "$3: $1 != $2"; }
expect_error() {  # expect_error PATTERN selfsense-args...
  local pattern=$1
  shift
  if "$bin" "$@" >"$work/out.txt" 2>"$work/err.txt"; then fail "accepted: $*"; fi
  grep -q -- "$pattern" "$work/err.txt" || fail "error for '$*' lacks '$pattern': $(cat "$work/err.txt")"
  ok
}

# --- aixACCT: summary table (its own "Table 1"), then two data blocks, trailing tabs --------
tab=$'\t'
{
  printf 'PiezoResult\n\nTable 1\nTable No [#]\tVc+ [V]\t\n1.000000e+000\t1.1e+003\t\n\n'
  printf 'Piezo\nProgram: aixPlorer Software version 3.0.44.0\n\n'
  printf 'Table 1\nSampleName: FIRST\nArea [mm2]: 60\nThickness [nm]: 800000\n'
  printf 'Time [s]\tV+ [V]\tV- [V]\tI1 [A]\tP1 [uC/cm2]\tD1 [nm]\t\n'
  printf '0.000000e+000\t1.000000e+002\t0.000000e+000\t1.0e-006\t-2.000000e+001\t0.0\t\n'
  printf '1.000000e-002\t2.000000e+002\t0.000000e+000\t1.0e-006\t-1.900000e+001\t8.0e+001\t\n\n'
  printf 'Table 2\nSampleName: SECOND\nMeasurement Topology: electrical 3, strain 3\n'
  printf 'Area [mm2]: 50\nThickness [nm]: 500000\n'
  printf 'Time [s]\tV+ [V]\tV- [V]\tI1 [A]\tP1 [uC/cm2]\tD1 [nm]\t\n'
  printf '0.000000e+000\t1.000000e+003\t1.000000e+002\t2.0e-007\t1.000000e+001\t0.0\t\n'
  printf '5.000000e-001\t-5.000000e+002\t0.000000e+000\t2.0e-007\t1.100000e+001\t-5.0e+002\t\n'
  printf '1.000000e+000\t0.000000e+000\t0.000000e+000\t2.0e-007\t1.200000e+001\t1.0e+002\t\n'
} >"$work/a.dat"
"$bin" import aixacct "$work/a.dat" --block 2 --out "$work/a2.csv" >/dev/null
grep -q '^t,E,D,S,u,I,P1,D1$' "$work/a2.csv" || fail "aixacct header: $(grep -v '^#' "$work/a2.csv" | head -1)"
grep -q '^# aixacct SampleName: SECOND$' "$work/a2.csv" || fail "aixacct metadata not in comments"
grep -q '^# h = 5e-04 m, A = 5e-05 m^2, I0 = 0 A$' "$work/a2.csv" || fail "aixacct geometry comment"
[ "$(grep -vc '^#' "$work/a2.csv")" = 4 ] || fail "aixacct: block 2 should have 3 rows"
near "$(cell "$work/a2.csv" E 1)" 1.8e6 "E = (V+ - V-) / h"
near "$(cell "$work/a2.csv" D 2)" 0.11 "D = P1 * 1e-2"
near "$(cell "$work/a2.csv" S 2)" -1e-3 "S = D1 * 1e-9 / h"
near "$(cell "$work/a2.csv" P1 3)" 12 "raw P1 carried through"
ok
# a constant leakage current is removed from D: D = P1 * 1e-2 - I0 (t - t0) / A
"$bin" import aixacct "$work/a.dat" --block 2 --current-offset-a 2e-7 --out "$work/a2c.csv" >/dev/null
near "$(cell "$work/a2c.csv" D 3)" "$(awk 'BEGIN { print 0.12 - 2e-7 * 1.0 / 5e-5 }')" "offset current"
"$bin" import aixacct "$work/a.dat" --block 2 --detrend-charge --detrend-tail 0.5 \
  --out "$work/a2d.csv" >/dev/null
grep -q 'I0 = 2e-07 A' "$work/a2d.csv" || fail "detrend-charge did not estimate I0 = 2e-7 A"
ok
# geometry from the command line wins over the metadata
"$bin" import aixacct "$work/a.dat" --block 1 --thickness-m 1e-3 --out "$work/a1.csv" >/dev/null
near "$(cell "$work/a1.csv" E 2)" 2e5 "--thickness-m"
ok

expect_error "no data block 'Table 3' (data blocks: 1, 2)" import aixacct "$work/a.dat" --block 3 --out "$work/x.csv"
sed 's/^5.000000e-001\t-5.000000e+002\t0.000000e+000\t2.0e-007\t1.100000e+001/5.000000e-001\t-5.000000e+002\t0.000000e+000\t2.0e-007\tabc/' \
  "$work/a.dat" >"$work/bad.dat"
expect_error "bad.dat:25: column 'P1 \[uC/cm2\]': not a number: 'abc'" import aixacct "$work/bad.dat" --block 2 --out "$work/x.csv"
sed "s/^1.000000e+000${tab}0.000000e+000/4.000000e-001${tab}0.000000e+000/" "$work/a.dat" >"$work/bad.dat"
expect_error "bad.dat:26: column 'Time \[s\]': 0.4 does not increase" import aixacct "$work/bad.dat" --block 2 --out "$work/x.csv"
sed 's/D1 \[nm\]/X1 [nm]/' "$work/a.dat" >"$work/bad.dat"
expect_error "bad.dat:14: header has no column 'D1 \[nm\]'" import aixacct "$work/bad.dat" --block 1 --out "$work/x.csv"
sed 's/^Thickness \[nm\]: 500000/Thickness [nm]: thin/' "$work/a.dat" >"$work/bad.dat"
expect_error "bad.dat:22: 'Thickness \[nm\]': not a positive number: 'thin'" import aixacct "$work/bad.dat" --block 2 --out "$work/x.csv"
[ ! -e "$work/x.csv" ] || fail "an output was written despite an error"

# --- generic columns: header row, empty first column, units and geometry -------------------
printf 'index,time_ms,x_um,u_kV,F_N\n,0,1.5,0.1,-10\n,2,3.0,0.2,-20\n,4,4.5,0.15,-30\n' >"$work/c.csv"
"$bin" import columns "$work/c.csv" --skip-rows 1 --map "2:t:ms,3:x:um,4:u:kV,5:F:N" \
  --layer-thickness-m 1e-4 --active-length-m 0.03 --cross-section-m2 1e-4 --out "$work/c_out.csv" >/dev/null
grep -q '^t,x,u,F,E,S,T$' "$work/c_out.csv" || fail "columns header: $(grep -v '^#' "$work/c_out.csv" | head -1)"
near "$(cell "$work/c_out.csv" t 3)" 0.004 "t in ms"
near "$(cell "$work/c_out.csv" x 2)" 3e-6 "x in um"
near "$(cell "$work/c_out.csv" E 2)" 2e6 "E = u / h"
near "$(cell "$work/c_out.csv" S 3)" 1.5e-4 "S = x / L"
near "$(cell "$work/c_out.csv" T 1)" -1e5 "T = F / A_mech"
ok
# tab separated, no time column: t from the sample rate; row range; uC/cm2 to C/m^2
printf '1\t10\n2\t20\n3\t30\n4\t40\n' >"$work/c.tsv"
"$bin" import columns "$work/c.tsv" --delimiter tab --sample-rate-hz 100 --first-row 2 --last-row 3 \
  --map "1:u:V,2:D:uC/cm2" --out "$work/c_tsv.csv" >/dev/null
[ "$(grep -vc '^#' "$work/c_tsv.csv")" = 3 ] || fail "--first-row/--last-row"
near "$(cell "$work/c_tsv.csv" t 2)" 0.01 "t from --sample-rate-hz"
near "$(cell "$work/c_tsv.csv" D 1)" 0.2 "uC/cm2"
ok

printf 't,x\n0,1\n1,abc\n' >"$work/bad.csv"
expect_error "bad.csv:3: column 2 ('x'): not a number: 'abc'" import columns "$work/bad.csv" --skip-rows 1 --map "1:t:s,2:x:um" --out "$work/x.csv"
printf '0,1\n1\n' >"$work/bad.csv"
expect_error "bad.csv:2: column 2 ('x'): missing: the line has 1 cells" import columns "$work/bad.csv" --map "1:t:s,2:x:um" --out "$work/x.csv"
printf '0,1\n0,2\n' >"$work/bad.csv"
expect_error "bad.csv:2: column 1 ('t'): 0 does not increase" import columns "$work/bad.csv" --map "1:t:s,2:x:um" --out "$work/x.csv"
expect_error "unknown unit 'furlong'" import columns "$work/c.csv" --map "1:t:furlong" --out "$work/x.csv"
expect_error "name 'x' given twice" import columns "$work/c.csv" --map "1:x,2:x" --out "$work/x.csv"
expect_error "no column is named t; give --sample-rate-hz" import columns "$work/c.csv" --skip-rows 1 --map "3:x:um" --out "$work/x.csv"
# finite cells whose SI value is beyond the range of a double (found by the fuzz targets'
# round-trip property: the recording could not be written)
printf '0,1e307\n1,2\n' >"$work/big.csv"
expect_error "big.csv:1: column 2 ('u'): 1e+307 kV is beyond the range of a double" import columns "$work/big.csv" --map "1:t:s,2:u:kV" --out "$work/x.csv"
printf '0,1\n1,1e300\n' >"$work/big.csv"
expect_error "big.csv:2: E = u / 1e-10 = 1e+300 / 1e-10 is beyond the range of a double" import columns "$work/big.csv" --map "1:t:s,2:u:V" --layer-thickness-m 1e-10 --out "$work/x.csv"
sed 's/^Thickness \[nm\]: 800000/Thickness [nm]: 1e-300/' "$work/a.dat" >"$work/big.dat"
expect_error "big.dat:15: column 'E': inf after conversion" import aixacct "$work/big.dat" --block 1 --out "$work/x.csv"
[ ! -e "$work/x.csv" ] || fail "an output was written despite an error"
echo "import: $passed passed, 0 failed"
