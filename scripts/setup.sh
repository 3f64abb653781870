#!/usr/bin/env bash
# selfsense set-up on Debian 12: installs what is missing, builds, then runs either the main
# job on the simulated transducer (`demo`) or every check (`test`). Idempotent and
# non-interactive; run as root on a fresh machine (apt-get), as any user once installed.
#
#   scripts/setup.sh demo   install, build (Release), run the main job
#   scripts/setup.sh test   install, format check, build (Release, -Werror), unit tests,
#                           clang-tidy, then build and test again under ASan + UBSan
set -euo pipefail

mode=${1:-demo}
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
jobs=$(nproc)
cd "$root"

say() { printf '\n== %s\n' "$*"; }

packages=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev libyaml-cpp-dev libgpiod-dev libmodbus-dev libsystemd-dev libcli11-dev
  nlohmann-json3-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  clang-format clang-tidy
)

install_missing() {
  local missing=()
  for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
  done
  if [ ${#missing[@]} -eq 0 ]; then
    say "packages: all ${#packages[@]} present"
    return
  fi
  say "packages: installing ${missing[*]}"
  if [ "$(id -u)" -ne 0 ]; then
    echo "setup: missing packages and not root; run as root: apt-get install ${missing[*]}" >&2
    exit 1
  fi
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -q
  apt-get install -y -q --no-install-recommends "${missing[@]}"
}

# configure_and_build DIR [cmake args...]
configure_and_build() {
  local dir=$1
  shift
  say "build: $dir ($*)"
  cmake -S . -B "$dir" -G Ninja "$@"
  cmake --build "$dir" -j "$jobs"
}

sources() { git ls-files -- '*.cpp' '*.hpp'; }

check_format() {
  say "format: clang-format --dry-run --Werror on $(sources | wc -l) files"
  sources | xargs clang-format --dry-run --Werror
}

check_tidy() {
  say "lint: clang-tidy (warnings are errors)"
  run-clang-tidy -p build -quiet -j "$jobs" "$root/(src|tests|drivers)/.*\\.cpp\$" >build/clang-tidy.log 2>&1 ||
    { grep -E 'error:|warning:' build/clang-tidy.log | head -50; echo "clang-tidy failed" >&2; exit 1; }
}

run_tests() {
  say "tests: $1"
  ctest --test-dir "$1" --output-on-failure -j "$jobs"
}

install_missing
case "$mode" in
  demo)
    configure_and_build build -DCMAKE_BUILD_TYPE=Release
    say "main job: selfsense demo"
    build/src/cli/selfsense demo
    ;;
  test)
    check_format
    configure_and_build build -DCMAKE_BUILD_TYPE=Release -DSELFSENSE_WERROR=ON
    run_tests build
    check_tidy
    configure_and_build build-sanitize -DCMAKE_BUILD_TYPE=Debug -DSELFSENSE_WERROR=ON \
      -DSELFSENSE_SANITIZE=address,undefined -DSELFSENSE_BUILD_BENCHMARKS=OFF
    run_tests build-sanitize
    say "all checks passed"
    ;;
  *)
    echo "usage: scripts/setup.sh demo|test" >&2
    exit 2
    ;;
esac
