#!/usr/bin/env bash
# The build's layering, as a check that fails (docs/architecture.md): every header and source of a
# library, a driver (drivers/) and the programs (src/cli, src/selfsensed) may include project
# headers only from the libraries it is allowed to depend on, and the pure-math libraries include
# nothing that does files, threads, sockets or formats.
#
#   check_layering.sh SOURCE_DIR
# Prints one line per violation (FILE:LINE: what) and exits 1 if there is any.
set -euo pipefail
root=${1:?usage: check_layering.sh SOURCE_DIR}
cd "$root"

# library folder -> the include folders it may use (itself first). A library's headers are in
# include/selfsense/LIB and its sources in src/LIB; a driver's in include/selfsense/drivers/NAME
# and drivers/NAME (key drivers/NAME); the programs (cli, selfsensed) have sources only. "*": every
# library known here. The tests may use everything.
declare -A allowed=(
  [base]="base"
  [operators]="operators base"
  [models]="models operators base"
  [adaptation]="adaptation models operators base"
  [control]="control base"
  [plant]="plant base"
  [identification]="identification models operators base"
  [diagnosis]="diagnosis identification models operators base"
  [io]="io base"
  [model_io]="model_io models operators io base"
  [plant_io]="plant_io plant io base"
  [report]="report base"
  [importers]="importers io base"
  [evaluation]="evaluation diagnosis identification adaptation models operators io report runtime base"
  [runtime]="runtime adaptation models operators control base"
  [daemon]="daemon runtime adaptation models operators control io model_io base"
  [drivers/sim]="drivers/sim runtime models operators control plant base"
  [drivers/can]="drivers/can runtime models operators control io base"
  [drivers/modbus]="drivers/modbus runtime models operators control io base"
  [drivers/spi]="drivers/spi runtime models operators control io base"
  [drivers/can_sim]="drivers/can_sim drivers/can plant runtime base"
  [drivers/modbus_sim]="drivers/modbus_sim drivers/modbus drivers/sim runtime plant_io base"
  [drivers/registry]="drivers/registry drivers/sim drivers/can drivers/modbus drivers/spi daemon runtime adaptation models operators control io model_io plant plant_io base"
  [cli]="*"
  [selfsensed]="selfsensed daemon drivers/registry runtime adaptation models operators control io model_io base"
)
folders_of() {
  case "$1" in
    drivers/*) echo "include/selfsense/$1 $1" ;;
    cli | selfsensed) echo "src/$1" ;;
    *) echo "include/selfsense/$1 src/$1" ;;
  esac
}
# The math and its ground floor: no files, streams, threads, clocks, sockets or file formats.
math="base operators models adaptation control plant identification diagnosis"
forbidden_system='fstream|iostream|filesystem|thread|mutex|condition_variable|future|chrono|cstdio|yaml-cpp/.*|nlohmann/.*|sys/.*|unistd\.h|fcntl\.h|pthread\.h'

violations=0
report() {
  echo "$1"
  violations=$((violations + 1))
}

for lib in "${!allowed[@]}"; do
  for dir in $(folders_of "$lib"); do
    [ -d "$dir" ] || continue
    while IFS= read -r hit; do
      file=${hit%%:*}
      rest=${hit#*:}
      line=${rest%%:*}
      # selfsense/drivers/NAME/... -> drivers/NAME; selfsense/LIB/... -> LIB
      target=$(sed -E 's/.*#include "selfsense\/((drivers\/)?[a-z_]+)\/.*/\1/' <<<"$rest")
      ok=0
      if [ "${allowed[$lib]}" = "*" ]; then
        [ -n "${allowed[$target]+x}" ] && ok=1
      else
        for a in ${allowed[$lib]}; do
          [ "$a" = "$target" ] && ok=1
        done
      fi
      [ $ok -eq 1 ] || report "$file:$line: $lib must not include selfsense/$target (allowed: ${allowed[$lib]})"
    done < <(grep -rnE '^#include "selfsense/[a-z_]+/' "$dir" || true)
    if [[ " $math " == *" $lib "* ]]; then
      while IFS= read -r hit; do
        report "${hit%%:#*}: pure math ($lib) must not include ${hit#*#include }"
      done < <(grep -rnE "^#include <($forbidden_system)>" "$dir" || true)
    fi
  done
done

# Every library folder must be known here, so a new one cannot slip past the check.
for dir in src/*/ drivers/*/ include/selfsense/*/ include/selfsense/drivers/*/; do
  [ -d "$dir" ] || continue
  lib=${dir%/}
  lib=${lib#src/}
  lib=${lib#include/selfsense/}
  [ "$lib" = drivers ] && continue
  [ -n "${allowed[$lib]+x}" ] || report "${dir%/}: library folder not in tests/layering/check_layering.sh"
done

if [ "$violations" -gt 0 ]; then
  echo "layering: $violations violation(s)" >&2
  exit 1
fi
echo "layering: ok (${#allowed[@]} libraries)"
