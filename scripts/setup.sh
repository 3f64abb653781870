#!/usr/bin/env bash
# selfsense set-up on Debian 12: installs what is missing, builds, then runs either the main
# job on the simulated transducer (`demo`), every check (`test`) or the Debian packages
# (`package`). Idempotent and non-interactive; run as root on a fresh machine (apt-get), as any
# user once installed.
#
#   scripts/setup.sh demo   install, build (Release), run the main job (the daemon on the
#                           simulated transducer; before it the operator demo and self-sensing)
#   scripts/setup.sh test   install, format check, build (Release, -Werror), unit tests,
#                           clang-tidy, then build (clang) and test again under ASan + UBSan
#                           and run every fuzz target for a bounded time; the Debian packages
#                           built and read back (tests/package)
#   scripts/setup.sh package  install, build the programs and libraries (Release, no tests),
#                           cpack (cmake/SelfsensePackage.cmake): build/packages/
#                           selfsense_VERSION_ARCH.deb and libselfsense-dev_VERSION_ARCH.deb
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
  clang-format clang-tidy python3  # python3: run-clang-tidy and scripts/tidy_cached.py
  clang libclang-rt-14-dev  # the sanitizer build and the fuzz targets (libFuzzer), tests/fuzz
  zlib1g-dev chromium fonts-liberation  # the reports' browser tests (tests/cli)
  mbpoll
  rt-tests  # cyclictest beside the loop in tests/bench/loop_timing_bench (docs/benchmarks.md)
)
# The Debian packages (cmake/SelfsensePackage.cmake, tests/package): dpkg-shlibdeps (dpkg-dev)
# computes Depends, lintian reads them back. Not for the demo.
if [ "$mode" = package ] || [ "$mode" = test ]; then
  packages+=(dpkg-dev lintian)
fi

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

# Units found clean before (same clang-tidy, .clang-tidy, command and preprocessed source) are
# skipped: the cache lives outside the clone (/var/cache/selfsense-tidy), like the VM image.
check_tidy() {
  say "lint: clang-tidy (warnings are errors)"
  python3 scripts/tidy_cached.py build "$root/(src|tests|drivers)/.*\\.cpp\$" "$jobs" \
    >build/clang-tidy.log 2>&1 ||
    { grep -E 'error:|warning:' build/clang-tidy.log | head -50; echo "clang-tidy failed" >&2; exit 1; }
  tail -1 build/clang-tidy.log
}

# run_tests DIR [ctest args...]
run_tests() {
  local dir=$1
  shift
  say "tests: $dir $*"
  ctest --test-dir "$dir" --output-on-failure -j "$jobs" "$@"
}

# Self-sensing on the simulated transducer: record an identification recording (the mix, then
# minor loops of many sizes and offsets) and a validation recording under excitation the fit
# never saw, identify the Preisach-class model, reconstruct T and S from E and D alone.
run_self_sensing() {
  local out=build/demo cli=build/src/cli/selfsense cfg=config/plant/reconstruction.yaml
  mkdir -p "$out"
  say "main job: plant recordings ($cfg, config/plant/reconstruction-validation.yaml)"
  "$cli" plant --config "$cfg" --excitation identification --seed 1 --out "$out/identification.csv"
  "$cli" plant --config config/plant/reconstruction-validation.yaml --excitation mix --seed 2 \
    --out "$out/validation.csv"
  say "main job: identify the preisach-creep model, validate on new excitation"
  "$cli" identify --recording "$out/identification.csv" --structure preisach-creep \
    --holdout 0 --validate "$out/validation.csv" --out "$out/model.yaml" --json "$out/fit.json"
  say "main job: self-sensing reconstruction of T and S from E and D"
  "$cli" reconstruct --model "$out/model.yaml" --recording "$out/validation.csv" \
    --out "$out/reconstructed.csv"
}

# Every fuzz target (tests/fuzz, docs/reliability.md) for FUZZ_SECONDS (default 10) with a
# fixed seed, on a scratch copy of its committed corpus (the repository's corpus is never
# written). A violated property, a sanitizer report, a timeout or a leak fails the run; the
# input is kept as DIR/fuzz-<target>-crash-... and the log's tail is printed.
run_fuzz() {
  local dir=$1 seconds=${FUZZ_SECONDS:-10} scratch name log
  scratch=$(mktemp -d)
  for corpus in tests/fuzz/corpus/*/; do
    name=$(basename "$corpus")
    log="$dir/fuzz-$name.log"
    cp -r "$corpus" "$scratch/$name"
    "$dir/tests/fuzz/fuzz_$name" -seed=1 -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
      -print_final_stats=1 -artifact_prefix="$dir/fuzz-$name-" "$scratch/$name" >"$log" 2>&1 ||
      { tail -40 "$log"; rm -rf "$scratch"; echo "fuzz: $name failed (input kept as $dir/fuzz-$name-*)" >&2; exit 1; }
    printf 'fuzz: %-16s %s\n' "$name" "$(grep -E '^#[0-9]+' "$log" | tail -1 | sed 's/  */ /g')"
  done
  rm -rf "$scratch"
}

# The tests under a real kernel and systemd (tests/vm, docs/vm-testing.md): builds the cached
# VM image unless present (as root; a few minutes once, then instant), then boots it once for
# every VM test. Needs a configured build directory (the tests are CTest tests).
run_vm_tests() {
  local dir=${1:-build}
  say "vm: image (cached under /var/cache/selfsense-vm)"
  scripts/vm/image.sh >build/vm-image.log 2>&1 || { tail -40 build/vm-image.log; exit 1; }
  tail -3 build/vm-image.log
  run_tests "$dir" -L vm
}

# The lock-free hand-over and the threads around the loop (rings, status seqlock, control
# socket server and clients) under ThreadSanitizer: only those test programs are built.
run_thread_sanitizer() {
  local dir=build-tsan
  say "tests: ThreadSanitizer on the rings and the control socket"
  cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=Debug -DSELFSENSE_WERROR=ON \
    -DSELFSENSE_SANITIZE=thread -DSELFSENSE_BUILD_BENCHMARKS=OFF >/dev/null
  cmake --build "$dir" -j "$jobs" --target runtime_tests daemon_control_tests
  "$dir/tests/runtime/runtime_tests" --gtest_brief=1
  "$dir/tests/daemon/daemon_control_tests" --gtest_brief=1
}

install_missing
case "$mode" in
  demo)
    configure_and_build build -DCMAKE_BUILD_TYPE=Release
    say "main job: selfsense demo"
    build/src/cli/selfsense demo
    run_self_sensing
    say "main job: selfsensed on config/sim.yaml, driven through selfsense ctl"
    bash scripts/main_job.sh build build/main-job
    ;;
  test)
    check_format
    configure_and_build build -DCMAKE_BUILD_TYPE=Release -DSELFSENSE_WERROR=ON
    run_tests build -LE vm
    run_vm_tests build
    check_tidy
    # clang, so that the same build also links the fuzz targets with libFuzzer; a directory
    # configured with another compiler is started afresh (CMake keeps the compiler it found).
    if [ -f build-sanitize/CMakeCache.txt ] &&
      ! grep -q '^CMAKE_CXX_COMPILER:[A-Z]*=.*clang++' build-sanitize/CMakeCache.txt; then
      rm -rf build-sanitize
    fi
    CXX=clang++ configure_and_build build-sanitize -DCMAKE_BUILD_TYPE=Debug -DSELFSENSE_WERROR=ON \
      -DSELFSENSE_SANITIZE=address,undefined -DSELFSENSE_BUILD_BENCHMARKS=OFF -DSELFSENSE_FUZZ=ON
    # The accuracy figures are checked in the Release run; under the sanitizers they only cost time.
    # The soak test (label soak) runs in the Release run only: under ASan + UBSan the daemon held
    # 10 kHz in a manual run (docs/reliability.md), but its uncounted-gap check sat at its
    # tolerance on this 2-core machine, and the CI budget is spent. The daemon runs under the
    # sanitizers in the process tests (kill -9, reloads) and the socket tests.
    # The packages (label package) are built and read back from the Release build only.
    # The speed tests (label perf) too: under the sanitizers a timing says nothing.
    run_tests build-sanitize -LE 'accuracy|vm|soak|package|perf'
    say "fuzz: every target for ${FUZZ_SECONDS:-10} s on a copy of its corpus"
    run_fuzz build-sanitize
    run_thread_sanitizer
    say "all checks passed"
    ;;
  package)
    # The packaged programs and libraries only (target selfsense_packaged), in the same build
    # directory as demo and test: no test is built for it, and what they built is reused.
    say "build: build (Release): the packaged programs and libraries"
    cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
    cmake --build build -j "$jobs" --target selfsense_packaged
    say "package: cpack (DEB) into build/packages/"
    rm -f build/packages/*.deb
    (cd build && cpack --config CPackConfig.cmake)
    ls -l build/packages/
    ;;
  *)
    echo "usage: scripts/setup.sh demo|test|package" >&2
    exit 2
    ;;
esac
