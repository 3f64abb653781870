#!/usr/bin/env bash
# selfsense set-up on Debian 12: installs what is missing, builds, then runs either the main
# job on the simulated transducer (`demo`), every check (`test`) or the Debian packages
# (`package`). Idempotent and non-interactive; run as root on a fresh machine (apt-get), as any
# user once installed.
#
#   scripts/setup.sh demo   install what the programs need, build selfsense and selfsensed only
#                           (Release, no tests), run the main job (the daemon on the simulated
#                           transducer; before it the operator demo and self-sensing)
#   scripts/setup.sh test   install, format check, build (Release, -Werror), unit tests,
#                           clang-tidy, then build (clang) and test again under ASan + UBSan
#                           and run every fuzz target for a bounded time; the Debian packages
#                           built and read back (tests/package); the arm64 cross build's unit
#                           tests (label port) under qemu-user and its packages read back
#   scripts/setup.sh package  install, build the programs and libraries (Release, no tests) for
#                           amd64 (build/) and cross for arm64 and armhf (build-arm64/,
#                           build-armhf/, cmake/toolchains/), cpack (cmake/SelfsensePackage.cmake):
#                           build/packages/selfsense_VERSION_ARCH.deb and
#                           libselfsense-dev_VERSION_ARCH.deb for the three architectures; an
#                           architecture whose libraries apt cannot install here is built in a
#                           Debian 12 root of its own (package_in_root)
#   scripts/setup.sh port   install, the arm64 port alone as `test` proves it: cross-build, the
#                           unit tests of label port under qemu-user, the arm64 packages read back
#                           and installed in the arm64 VM (qemu-system-aarch64, scripts/vm/)
set -euo pipefail

mode=${1:-demo}
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
jobs=$(nproc)
cd "$root"

# Each step's heading with the seconds since the start, so that a run's log times its steps.
setup_begin=$SECONDS
say() { printf '\n== [%d s] %s\n' $((SECONDS - setup_begin)) "$*"; }
demo_build=${SELFSENSE_DEMO_BUILD:-build}

# Release's flags as CMake sets them for GCC (the checks and the packages), and the demo's
# lighter ones (below, `demo`): one build directory may serve both, so each sets its own.
release_flags='-O3 -DNDEBUG'
demo_release_flags='-O1 -DNDEBUG'

# What the programs need to build (the demo's whole list): compiler, CMake, the libraries.
packages=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev libyaml-cpp-dev libgpiod-dev libmodbus-dev libsystemd-dev libcli11-dev
  nlohmann-json3-dev
)
# The checks: the tests, lint, sanitizers and fuzzing, the browser that renders the reports in
# their tests. The demo builds only the two programs it runs and draws its page itself
# (`selfsense main-job-page`): none of these.
if [ "$mode" != demo ]; then
  packages+=(
    libgtest-dev libgmock-dev libbenchmark-dev
    clang-format clang-tidy python3  # python3: run-clang-tidy and scripts/tidy_cached.py
    clang libclang-rt-14-dev  # the sanitizer build and the fuzz targets (libFuzzer), tests/fuzz
    zlib1g-dev chromium fonts-liberation  # the reports' browser tests (tests/cli)
    mbpoll
    rt-tests  # cyclictest beside the loop in tests/bench/loop_timing_bench (docs/benchmarks.md)
  )
fi
# The Debian packages (cmake/SelfsensePackage.cmake, tests/package): dpkg-shlibdeps (dpkg-dev)
# computes Depends, lintian reads them back. Not for the demo.
if [ "$mode" = package ] || [ "$mode" = test ] || [ "$mode" = port ]; then
  packages+=(dpkg-dev lintian file)
fi
# The VMs (scripts/vm/image.sh would install them itself, after an apt-get update of its own,
# and two image builds in the background would meet at dpkg's lock): debootstrap and e2fsprogs
# for the images, qemu-system-x86 (test), qemu-system-aarch64 and qemu-user-static with binfmt
# for the arm64 image's root.
if [ "$mode" = test ] || [ "$mode" = port ]; then
  packages+=(debootstrap e2fsprogs qemu-system-arm qemu-user-static binfmt-support)
fi
if [ "$mode" = test ]; then
  packages+=(qemu-system-x86)
fi

# Cross builds (cmake/toolchains/): Debian's cross compilers and the target's libraries as
# multiarch packages (dpkg --add-architecture; libc6:ARCH is the runtime the target's programs
# run on under qemu-user), qemu-user to run the target's programs, ccache
# (its cache outside the clone, ~/.cache/ccache). The package build needs the libraries the
# programs link; the port's tests (test) also GoogleTest and zlib for the configuration.
# libyaml-cpp-dev is not Multi-Arch: same in Debian 12: the target's libyaml-cpp0.7 with the
# build machine's headers (cmake/toolchains/yaml-cpp/).
cross_arches=()
case $mode in
  package) cross_arches=(arm64 armhf) ;;
  test | port) cross_arches=(arm64) ;;
esac
# Inside a build root (package_in_root, below): that one architecture's packages only.
root_arch=${SELFSENSE_ROOT_ARCH:-}
[ -z "$root_arch" ] || { [ "$mode" = package ] && cross_arches=("$root_arch"); }
declare -A cross_triplet=([arm64]=aarch64-linux-gnu [armhf]=arm-linux-gnueabihf)
cross_packages() {  # cross_packages ARCH: the packages a cross build for ARCH needs
  local arch=$1
  echo "crossbuild-essential-$arch"
  printf '%s\n' libc6 libyaml-cpp0.7 libmodbus-dev libgpiod-dev libsystemd-dev | sed "s/\$/:$arch/"
  [ "$mode" = package ] || printf '%s\n' libgtest-dev zlib1g-dev | sed "s/\$/:$arch/"
  return 0
}
if [ ${#cross_arches[@]} -gt 0 ]; then
  packages+=(qemu-user ccache)
fi

missing_of() {  # missing_of PACKAGE...: those not installed
  local p
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || echo "$p"
  done
}

as_root() {  # as_root WHAT: exit unless root
  if [ "$(id -u)" -ne 0 ]; then
    echo "setup: $1 and not root; run as root" >&2
    exit 1
  fi
}

apt_updated=0
apt_update() {
  [ "$apt_updated" -eq 1 ] && return
  # An index that a mirror serves inconsistently (one architecture's list mid-sync) fails the
  # update but not the lists it fetched: go on, apt-get install says what it cannot find.
  apt-get update -q || echo "setup: apt-get update reported errors (above); going on with the lists it has" >&2
  apt_updated=1
}

install_missing() {
  local missing
  mapfile -t missing < <(missing_of "${packages[@]}")
  if [ ${#missing[@]} -eq 0 ]; then
    say "packages: all ${#packages[@]} present"
    return
  fi
  say "packages: installing ${missing[*]}"
  as_root "missing packages (${missing[*]})"
  export DEBIAN_FRONTEND=noninteractive
  apt_update
  apt-get install -y -q --no-install-recommends "${missing[@]}"
}

add_architecture() {  # add_architecture ARCH: dpkg's foreign architecture, for apt's next update
  if ! dpkg --print-foreign-architectures | grep -qx "$1"; then
    dpkg --add-architecture "$1"
    apt_updated=0
  fi
}

# install_cross ARCH: the cross compiler and the target's libraries (multiarch); returns non-zero
# when apt cannot install them (`package` then builds ARCH in a root of its own, package_in_root;
# `test` and `port` stop).
install_cross() {
  local arch=$1 wanted missing
  mapfile -t wanted < <(cross_packages "$arch")
  mapfile -t missing < <(missing_of "${wanted[@]}")
  if [ ${#missing[@]} -eq 0 ]; then
    say "packages ($arch): all present"
    return 0
  fi
  say "packages ($arch): installing ${missing[*]}"
  as_root "missing packages for $arch (${missing[*]})"
  export DEBIAN_FRONTEND=noninteractive
  add_architecture "$arch"
  apt_update
  apt-get install -y -q --no-install-recommends "${missing[@]}"
}

# The compiler cache for every build once ccache is installed (`test`, `package` and `port`
# install it): its cache lives outside the clone (~/.cache/ccache), like the VM images and the
# clang-tidy cache, so a run after one that compiled the same sources takes their objects from
# it (the five builds of `test`: Release, ASan + UBSan, TSan, arm64; not shared between them,
# their flags differ). CCACHE_BASEDIR: paths under the clone are hashed relative to it.
# Prints the CMake argument, or nothing without ccache.
compiler_launcher() {
  if command -v ccache >/dev/null; then
    echo "-DCMAKE_CXX_COMPILER_LAUNCHER=ccache"
  fi
}
export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$root}

# configure_and_build DIR [cmake args...]
configure_and_build() {
  local dir=$1 launcher
  shift
  launcher=$(compiler_launcher)
  say "build: $dir ($*${launcher:+, $launcher})"
  cmake -S . -B "$dir" -G Ninja ${launcher:+"$launcher"} "$@"
  cmake --build "$dir" -j "$jobs"
}

sources() { git ls-files -- '*.cpp' '*.hpp'; }

check_format() {
  say "format: clang-format --dry-run --Werror on $(sources | wc -l) files"
  sources | xargs clang-format --dry-run --Werror
}

# Units found clean before (same clang-tidy, .clang-tidy, command and preprocessed source) are
# skipped: the cache lives outside the clone (/var/cache/selfsense-tidy), like the VM image.
# Only the units changed since .ci/tidy-baseline (a commit at which every unit was clean) are
# checked, as a pull request's lint checks what it changes: on a fresh machine (no cache) every
# unit took 1614 s of a 5500 s run (2026-12-07). SELFSENSE_TIDY_ALL=1 checks every unit.
check_tidy() {
  local baseline=(--baseline .ci/tidy-baseline)
  [ "${SELFSENSE_TIDY_ALL:-0}" = 0 ] || baseline=()
  say "lint: clang-tidy (warnings are errors)${baseline[*]:+, the units changed since .ci/tidy-baseline}"
  python3 scripts/tidy_cached.py build "$root/(src|tests|drivers)/.*\\.cpp\$" "$jobs" "${baseline[@]}" \
    >build/clang-tidy.log 2>&1 ||
    { grep -E 'error:|warning:' build/clang-tidy.log | head -50; echo "clang-tidy failed" >&2; exit 1; }
  grep -E "^(tidy_cached|clang-tidy):" build/clang-tidy.log
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
  local out=$demo_build/demo cli=$demo_build/src/cli/selfsense cfg=config/plant/reconstruction.yaml
  mkdir -p "$out"
  say "main job: plant recordings ($cfg, config/plant/reconstruction-validation.yaml)"
  "$cli" plant --config "$cfg" --excitation identification --seed 1 --out "$out/identification.csv"
  "$cli" plant --config config/plant/reconstruction-validation.yaml --excitation mix --seed 2 \
    --out "$out/validation.csv"
  # The sizes given are those identify chooses on this recording (8 dead zones per side, 7
  # hinges per play, both sides; asserted by PlantAccuracy.PreisachClassImprovesSelfSensing-
  # OnNewExcitation): the same model byte for byte, fitted once per side instead of once per
  # candidate as well (28 s of CPU instead of 67 s, 2026-11-28). `selfsense identify` without
  # them chooses (docs/results.md).
  say "main job: identify the preisach-creep model (8 dead zones, 7 hinges per play), validate on new excitation"
  "$cli" identify --recording "$out/identification.csv" --structure preisach-creep \
    --dead-zones 8 --bias-levels 7 \
    --holdout 0 --validate "$out/validation.csv" --out "$out/model.yaml" --json "$out/fit.json"
  say "main job: self-sensing reconstruction of T and S from E and D"
  "$cli" reconstruct --model "$out/model.yaml" --recording "$out/validation.csv" \
    --out "$out/reconstructed.csv"
}

# Every fuzz target (tests/fuzz, docs/reliability.md) for FUZZ_SECONDS (default 10) with a
# fixed seed, on a scratch copy of its committed corpus (the repository's corpus is never
# written). A violated property, a sanitizer report, a timeout or a leak fails the run; the
# input is kept as DIR/fuzz-<target>-crash-... and the log's tail is printed. A libFuzzer run is
# one process on one core: `jobs` targets at a time, each still for its full FUZZ_SECONDS.
fuzz_one() {  # fuzz_one DIR SCRATCH NAME: one target; its log DIR/fuzz-NAME.log
  local dir=$1 scratch=$2 name=$3
  "$dir/tests/fuzz/fuzz_$name" -seed=1 -max_total_time="${FUZZ_SECONDS:-10}" -timeout=10 \
    -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$dir/fuzz-$name-" "$scratch/$name" \
    >"$dir/fuzz-$name.log" 2>&1
}
run_fuzz() {
  local dir=$1 scratch name names=() pids=() i failed=()
  scratch=$(mktemp -d)
  for corpus in tests/fuzz/corpus/*/; do
    name=$(basename "$corpus")
    cp -r "$corpus" "$scratch/$name"
    names+=("$name")
  done
  for i in "${!names[@]}"; do
    # At most `jobs` running: wait for the oldest before starting the next.
    if [ "$i" -ge "$jobs" ]; then
      wait "${pids[$((i - jobs))]}" || failed+=("${names[$((i - jobs))]}")
    fi
    fuzz_one "$dir" "$scratch" "${names[$i]}" &
    pids+=($!)
  done
  for ((i = ${#names[@]} - jobs < 0 ? 0 : ${#names[@]} - jobs; i < ${#names[@]}; i++)); do
    wait "${pids[$i]}" || failed+=("${names[$i]}")
  done
  rm -rf "$scratch"
  for name in "${names[@]}"; do
    printf 'fuzz: %-16s %s\n' "$name" "$(grep -E '^#[0-9]+' "$dir/fuzz-$name.log" | tail -1 | sed 's/  */ /g')"
  done
  if [ ${#failed[@]} -ne 0 ]; then
    for name in "${failed[@]}"; do
      tail -40 "$dir/fuzz-$name.log"
      echo "fuzz: $name failed (input kept as $dir/fuzz-$name-*)" >&2
    done
    exit 1
  fi
}

# The tests under a real kernel and systemd (tests/vm, docs/vm-testing.md): builds the cached
# VM image of ARCH (amd64, or arm64 for the cross build) unless present (as root; a few minutes
# once, then instant), then boots it once for every VM test of BUILD_DIR. Needs a configured
# build directory (the tests are CTest tests).
run_vm_tests() {  # run_vm_tests BUILD_DIR [ARCH]
  local dir=${1:-build} arch=${2:-amd64}
  say "vm: $arch image (cached under /var/cache/selfsense-vm/$arch)"
  if [ -n "${vm_image_job[$arch]:-}" ]; then
    wait "${vm_image_job[$arch]}" || { tail -40 "${vm_image_log[$arch]}"; echo "setup: the $arch VM image failed" >&2; exit 1; }
    tail -3 "${vm_image_log[$arch]}"
  else
    SELFSENSE_VM_ARCH=$arch scripts/vm/image.sh >"$dir/vm-image.log" 2>&1 || { tail -40 "$dir/vm-image.log"; exit 1; }
    tail -3 "$dir/vm-image.log"
  fi
  run_tests "$dir" -L vm
}

# A VM image built in the background (run_vm_tests waits for it): cold, the amd64 image takes
# about 5 minutes and the arm64 one about 20, mostly waiting for the mirror, the disk and dpkg
# under emulation (7 minutes of CPU), so `test` starts both before its builds; image.sh builds
# one at a time (a lock), and returns at once when the image is cached.
declare -A vm_image_job=() vm_image_log=()
start_vm_image() {  # start_vm_image ARCH
  local arch=$1
  mkdir -p build-vm
  vm_image_log[$arch]=build-vm/image-$arch.log
  SELFSENSE_VM_ARCH=$arch scripts/vm/image.sh >"${vm_image_log[$arch]}" 2>&1 &
  vm_image_job[$arch]=$!
}

# The lock-free hand-over and the threads around the loop (rings, status seqlock, control
# socket server and clients) under ThreadSanitizer: only those test programs are built.
run_thread_sanitizer() {
  local dir=build-tsan
  say "tests: ThreadSanitizer on the rings and the control socket"
  local launcher
  launcher=$(compiler_launcher)
  cmake -S . -B "$dir" -G Ninja ${launcher:+"$launcher"} -DCMAKE_BUILD_TYPE=Debug -DSELFSENSE_WERROR=ON \
    -DSELFSENSE_SANITIZE=thread -DSELFSENSE_BUILD_BENCHMARKS=OFF >/dev/null
  cmake --build "$dir" -j "$jobs" --target runtime_tests daemon_control_tests
  "$dir/tests/runtime/runtime_tests" --gtest_brief=1
  "$dir/tests/daemon/daemon_control_tests" --gtest_brief=1
}

# cross_configure ARCH [cmake args...]: build-ARCH with ARCH's toolchain file, Release, through
# the compiler cache (outside the clone) when there is one.
cross_configure() {
  local arch=$1 launcher
  shift
  launcher=$(compiler_launcher)
  say "build: build-$arch (cmake/toolchains/${cross_triplet[$arch]}.cmake $*)"
  cmake -S . -B "build-$arch" -G Ninja --toolchain "$root/cmake/toolchains/${cross_triplet[$arch]}.cmake" \
    -DCMAKE_BUILD_TYPE=Release -DSELFSENSE_BUILD_BENCHMARKS=OFF ${launcher:+"$launcher"} "$@" >/dev/null
}

# The arm64 port proven (test): the programs and the unit tests of label port (tests/
# CMakeLists.txt) cross-built, the tests run under qemu-user (the toolchain's
# CMAKE_CROSSCOMPILING_EMULATOR), the arm64 packages built and read back (package.contents:
# architecture, aarch64 ELF, Depends resolved for arm64, lintian, the programs under qemu-user).
# Three long identifications (30 to 75 s each under emulation) are left
# to the native run: their figures say nothing about the port that the other tests do not.
# Then the arm64 package that package.contents built is installed and run by systemd in the
# arm64 VM (vm_arm64.*, tests/vm/CMakeLists.txt): no second cpack.
port_long='RuntimeModel.ModelIdentifiedAt1kHzRunsAt20kHz|Reconstruction.IdentifiedHysteresisCreepBeatsLinearOnHeldOutData|StressHysteresis.ReconstructsStressWhereTheAffineModelCannot'
run_port() {
  local begin=$SECONDS
  # The arm64 VM image beside the cross build and the port's tests (`test` started it earlier).
  [ -n "${vm_image_job[arm64]:-}" ] || start_vm_image arm64
  cross_configure arm64 -DSELFSENSE_BUILD_TESTS=ON -DSELFSENSE_WERROR=ON
  cmake --build build-arm64 -j "$jobs" --target selfsense_packaged selfsense_port_tests
  run_tests build-arm64 -L 'port|package' -LE vm -E "$port_long"
  run_vm_tests build-arm64 arm64
  say "port: arm64 built, tested under qemu-user, packaged and run in the arm64 VM in $((SECONDS - begin)) s"
}

# package_in_root ARCH: the ARCH packages built in a Debian 12 root of their own, where apt
# cannot install ARCH's libraries beside this machine's. A Multi-Arch: same library (libc6,
# liblzma5, ...) must have one version on every architecture; a machine that took a security
# update whose ARCH build its mirror does not serve (bookworm-security's armhf index failing to
# update, 2026-11-27/28) cannot install them. The root takes bookworm and bookworm-updates only
# (every library at the archive's version on both architectures); it is made once by
# debootstrap and kept outside the clone like the VM images (/var/cache/selfsense-roots, or
# SELFSENSE_ROOTS). The clone is bound into it at its own path, so the build directory
# (build-ARCH) and the packages (build/packages/) are the clone's; setup.sh runs there as
# `package` for ARCH alone (SELFSENSE_ROOT_ARCH) and installs what it needs in the root.
# Cold, measured on 2 cores (2026-11-28): debootstrap 47 s, apt 131 s, the armhf build 309 s.
package_in_root() {
  local arch=$1 base=${SELFSENSE_ROOTS:-/var/cache/selfsense-roots} mirror
  local dir=$base/bookworm
  as_root "the $arch packages need a build root"
  command -v debootstrap >/dev/null || { export DEBIAN_FRONTEND=noninteractive; apt_update; apt-get install -y -q --no-install-recommends debootstrap; }
  mirror=$(apt-get indextargets --format '$(REPO_URI)' 2>/dev/null | grep -E '/debian/$' | head -1 || true)
  mirror=${mirror:-http://deb.debian.org/debian/}
  if [ ! -x "$dir/usr/bin/apt-get" ]; then
    say "package ($arch): a Debian 12 build root ($dir, debootstrap from $mirror)"
    rm -rf "$dir.new"
    mkdir -p "$base"
    debootstrap --variant=minbase bookworm "$dir.new" "$mirror" >"$base/debootstrap.log" 2>&1 ||
      { tail -20 "$base/debootstrap.log" >&2; echo "setup: debootstrap failed (log: $base/debootstrap.log)" >&2; exit 1; }
    printf 'deb %s bookworm main\ndeb %s bookworm-updates main\n' "$mirror" "$mirror" >"$dir.new/etc/apt/sources.list"
    mv "$dir.new" "$dir"
  fi
  say "package ($arch): built in the build root $dir"
  cp /etc/resolv.conf "$dir/etc/resolv.conf"
  mkdir -p "$dir$root"
  (
    mounted=()
    trap 'for ((i = ${#mounted[@]} - 1; i >= 0; i--)); do umount "${mounted[$i]}"; done' EXIT
    for m in /proc /sys /dev /dev/pts "$root"; do
      mount --bind "$m" "$dir$m"
      mounted+=("$dir$m")
    done
    # git (the version) runs as root on a clone another user may own.
    chroot "$dir" /usr/bin/env SELFSENSE_ROOT_ARCH="$arch" GIT_CONFIG_COUNT=1 \
      GIT_CONFIG_KEY_0=safe.directory GIT_CONFIG_VALUE_0="$root" bash "$root/scripts/setup.sh" package
  )
}

# The cross architectures added before the first apt-get update, so that one update serves all.
for arch in "${cross_arches[@]}"; do
  mapfile -t wanted < <(cross_packages "$arch")
  mapfile -t missing < <(missing_of "${wanted[@]}")
  [ ${#missing[@]} -eq 0 ] || { as_root "missing packages for $arch (${missing[*]})"; add_architecture "$arch"; }
done
install_missing
# The cross builds' packages, one architecture at a time: an architecture whose libraries apt
# cannot install (a mirror's index mid-sync) goes to cross_failed (see install_cross).
cross_ready=()
cross_failed=()
for arch in "${cross_arches[@]}"; do
  if install_cross "$arch"; then
    cross_ready+=("$arch")
  else
    echo "setup: the $arch cross build's packages cannot be installed (apt above)" >&2
    cross_failed+=("$arch")
  fi
done
case "$mode" in
  demo)
    # The two programs the demo runs, nothing else: no test, no benchmark (SELFSENSE_DEMO_BUILD:
    # another build directory, e.g. to time a fresh build beside build/). A unity build (CMake
    # compiles each target's sources in batches of 16): the headers every file parses (CLI11,
    # which compiles its whole parser in every file that uses it, nlohmann/json, yaml-cpp, Eigen)
    # are compiled once a batch instead of once a file, in less than half the compiler's time
    # (README). Batches of 16 rather than CMake's 8: 26 compiles instead of 33 and 19 % less
    # compiler CPU (237 s against 291 s), while the longest batch stays well under half the
    # whole, so two cores stay busy.
    # At -O1, not Release's -O3: the build's steps sum to 540 s instead of 870 s (-O2: 690 s),
    # the identification writes the same model byte for byte in the same time (Eigen's kernels
    # carry it), and the daemon's cycle stays at 2 us median, 4 us p99 of its 100 us period,
    # the main job's figures within run-to-run scatter of -O3's (README, 2026-11-28).
    # Only here: the checks (`test`) and the packages build file by file at -O3 (set again
    # there, since they may share this build directory).
    say "build: $demo_build (unity, -O1): selfsense and selfsensed"
    cmake -S . -B "$demo_build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DSELFSENSE_BUILD_TESTS=OFF \
      -DSELFSENSE_BUILD_BENCHMARKS=OFF -DCMAKE_UNITY_BUILD=ON -DCMAKE_UNITY_BUILD_BATCH_SIZE=16 \
      "-DCMAKE_CXX_FLAGS_RELEASE=$demo_release_flags"
    cmake --build "$demo_build" -j "$jobs" --target selfsense selfsensed
    say "main job: selfsense demo"
    "$demo_build/src/cli/selfsense" demo
    run_self_sensing
    say "main job: selfsensed on config/sim.yaml, driven through selfsense ctl"
    bash scripts/main_job.sh "$demo_build" "$demo_build/main-job"
    say "demo: done in $((SECONDS - setup_begin)) s; the page: $demo_build/main-job/main_job.html"
    ;;
  test)
    start_vm_image amd64
    [ ${#cross_failed[@]} -ne 0 ] || start_vm_image arm64
    check_format
    # Tests and benchmarks on, file by file: a build directory the demo configured has them off
    # and builds in batches (clang-tidy reads compile_commands.json, which then names the
    # batches, not the files).
    configure_and_build build -DCMAKE_BUILD_TYPE=Release -DSELFSENSE_WERROR=ON \
      -DSELFSENSE_BUILD_TESTS=ON -DSELFSENSE_BUILD_BENCHMARKS=ON -DCMAKE_UNITY_BUILD=OFF \
      "-DCMAKE_CXX_FLAGS_RELEASE=$release_flags"
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
      -DSELFSENSE_SANITIZE=address,undefined -DSELFSENSE_BUILD_BENCHMARKS=OFF -DSELFSENSE_FUZZ=ON \
      -DSELFSENSE_BUILD_ACCURACY_TESTS=OFF
    # The accuracy figures are checked in the Release run; under the sanitizers they only cost
    # time, so their programs are not built here (SELFSENSE_BUILD_ACCURACY_TESTS).
    # The soak test (label soak) runs in the Release run only: under ASan + UBSan the daemon held
    # 10 kHz in a manual run (docs/reliability.md), but its uncounted-gap check sat at its
    # tolerance on this 2-core machine, and the CI budget is spent. The daemon runs under the
    # sanitizers in the process tests (kill -9, reloads) and the socket tests.
    # The packages (label package) are built and read back from the Release build only.
    # The speed tests (label perf) too: under the sanitizers a timing says nothing.
    # The checks of the source tree alone (label sources: the layering) build nothing to sanitize.
    # Two statistical verdict tests (tests/diagnosis/verdict_test.cpp: the whole diagnosis on a
    # long recording, the noise floor and a disturbance's place) take about 205 s each under ASan;
    # their code runs under the sanitizers in the shorter diagnosis tests, their figures are checked
    # in the Release run. Left out here to pay for the arm64 VM in run_port.
    sanitize_long='Verdict\.(ADisturbanceNoCandidateModelsIsUnexplainedWithItsPlace|ARecordingTheModelExplainsToItsNoiseIsConsistent)'
    run_tests build-sanitize -LE 'accuracy|vm|soak|package|perf|sources' -E "$sanitize_long"
    say "fuzz: every target for ${FUZZ_SECONDS:-10} s on a copy of its corpus"
    run_fuzz build-sanitize
    run_thread_sanitizer
    [ ${#cross_failed[@]} -eq 0 ] || { echo "setup: cannot cross-build for arm64" >&2; exit 1; }
    run_port
    say "all checks passed"
    ;;
  package)
    # The packaged programs and libraries only (target selfsense_packaged), in the same build
    # directory as demo and test: no test is built for it, and what they built is reused.
    # Inside a build root only the cross architecture it was started for.
    if [ -z "$root_arch" ]; then
      say "build: build (Release): the packaged programs and libraries"
      launcher=$(compiler_launcher)
      cmake -S . -B build -G Ninja ${launcher:+"$launcher"} -DCMAKE_BUILD_TYPE=Release -DCMAKE_UNITY_BUILD=OFF \
        "-DCMAKE_CXX_FLAGS_RELEASE=$release_flags"
      cmake --build build -j "$jobs" --target selfsense_packaged
      say "package: cpack (DEB) into build/packages/"
      rm -f build/packages/*.deb
      (cd build && cpack --config CPackConfig.cmake)
    fi
    mkdir -p build/packages
    # The same for each cross architecture, in its own build directory (no test is configured),
    # its packages beside amd64's.
    for arch in "${cross_ready[@]}"; do
      cross_configure "$arch" -DSELFSENSE_BUILD_TESTS=OFF
      cmake --build "build-$arch" -j "$jobs" --target selfsense_packaged
      say "package: cpack (DEB, $arch) into build/packages/"
      rm -f "build-$arch"/packages/*.deb
      (cd "build-$arch" && cpack --config CPackConfig.cmake)
      cp "build-$arch"/packages/*_"$arch".deb build/packages/
    done
    # An architecture whose libraries apt could not install here is built in a Debian 12 root
    # of its own (package_in_root); inside one, a failure is final.
    if [ -z "$root_arch" ]; then
      for arch in "${cross_failed[@]}"; do
        package_in_root "$arch"
      done
    elif [ ${#cross_failed[@]} -ne 0 ]; then
      echo "setup: the $root_arch libraries could not be installed in the build root either (apt above)" >&2
      exit 1
    fi
    ls -l build/packages/
    ;;
  port)
    [ ${#cross_failed[@]} -eq 0 ] || { echo "setup: cannot cross-build for arm64" >&2; exit 1; }
    run_port
    ;;
  *)
    echo "usage: scripts/setup.sh demo|test|package|port" >&2
    exit 2
    ;;
esac
