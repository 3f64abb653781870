#!/usr/bin/env bash
# The Debian packages (cmake/SelfsensePackage.cmake) read back: built with cpack from the build
# tree into a scratch directory (or taken from PACKAGES_DIR), then their names, contents,
# control data (conffiles, maintainer scripts, Depends computed by dpkg-shlibdeps) checked with
# dpkg-deb, lintian run (no E: line allowed), the packaged programs run from the unpacked tree
# on the installed configurations, and a program built against the unpacked libselfsense-dev
# with find_package(selfsense).
#
# A cross build's packages (cmake/toolchains/, CPACK_DEBIAN_PACKAGE_ARCHITECTURE in the build's
# CPackConfig.cmake) are checked the same way for their architecture: the programs are ELF for
# the target, their Depends resolve among that architecture's Debian packages (apt-get -s), and
# the programs and the integrator's program run under the emulator in PACKAGE_EMULATOR (the
# build's CMAKE_CROSSCOMPILING_EMULATOR, e.g. qemu-aarch64 -L /usr/aarch64-linux-gnu ...), the
# integrator's program built with the toolchain file in PACKAGE_TOOLCHAIN.
#
#   check_packages.sh BUILD_DIR WORK_DIR [PACKAGES_DIR]
set -euo pipefail

build=$(cd "$1" && pwd)
work=$2
given=${3:-}
failures=0
fail() {
  echo "FAIL: $*"
  failures=$((failures + 1))
}

rm -rf "$work"
mkdir -p "$work"
if [ -n "$given" ]; then
  debs=$given
else
  begin=$(date +%s.%N)
  mkdir -p "$work/cpack"
  (cd "$work/cpack" && cpack --config "$build/CPackConfig.cmake" -B "$work/cpack") >"$work/cpack.log" 2>&1 ||
    { tail -30 "$work/cpack.log"; echo "FAIL: cpack"; exit 1; }
  debs=$work/cpack/packages
  echo "cpack: $(awk -v a="$begin" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }') s"
fi

arch=$(sed -n 's/^set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE "\(.*\)")$/\1/p' "$build/CPackConfig.cmake")
[ -n "$arch" ] || arch=$(dpkg --print-architecture)
# run PROGRAM ARGS...: on this machine, or under the cross build's emulator.
read -r -a emulator <<<"${PACKAGE_EMULATOR:-}"
run() { "${emulator[@]}" "$@"; }
version=$(sed -n 's/^set(CPACK_PACKAGE_VERSION "\(.*\)")$/\1/p' "$build/CPackConfig.cmake")
[ -n "$version" ] || { echo "FAIL: no CPACK_PACKAGE_VERSION in $build/CPackConfig.cmake"; exit 1; }
runtime=$debs/selfsense_${version}_${arch}.deb
dev=$debs/libselfsense-dev_${version}_${arch}.deb
echo "packages: $(cd "$debs" && ls -- *.deb | tr '\n' ' ')"
for deb in "$runtime" "$dev"; do
  [ -f "$deb" ] || { echo "FAIL: $deb not built (Debian's name: NAME_VERSION_ARCH.deb)"; exit 1; }
done
# A Debian-valid version that grows with the history: VERSION+gitN.
dpkg --validate-version "$version" || fail "version $version is not a valid Debian version"

# contents DEB: the paths in the data archive, without the leading '.'.
contents() { dpkg-deb -c "$1" | awk '{ print $6 }' | sed -e 's|^\./|/|' -e 's|/$||'; }
contents "$runtime" >"$work/runtime.list"
contents "$dev" >"$work/dev.list"

require() {  # require LIST PATH...
  local list=$1
  shift
  for path in "$@"; do
    grep -qxF "$path" "$list" || fail "$(basename "$list" .list): $path missing"
  done
}
examples=(sim damping-sim can-sim modbus-sim spi-ads131m04)
require "$work/runtime.list" /usr/bin/selfsensed /usr/bin/selfsense \
  /lib/systemd/system/selfsensed.service /usr/lib/sysusers.d/selfsense.conf \
  /lib/udev/rules.d/60-selfsense.rules /etc/selfsense/selfsensed.yaml \
  /usr/share/selfsense/models/sim.yaml /usr/share/selfsense/plant/daemon.yaml \
  /usr/share/selfsense/plant/damping.yaml \
  /usr/share/doc/selfsense/copyright /usr/share/doc/selfsense/changelog.gz \
  /usr/share/man/man1/selfsense.1.gz /usr/share/man/man8/selfsensed.8.gz
for example in "${examples[@]}"; do
  require "$work/runtime.list" "/etc/selfsense/examples/$example.yaml"
done
require "$work/dev.list" /usr/include/selfsense/operators/hysteresis_creep.hpp \
  /usr/include/selfsense/control/pid.hpp /usr/include/selfsense/runtime/loop.hpp \
  /usr/lib/cmake/selfsense/selfsenseConfig.cmake /usr/lib/cmake/selfsense/selfsenseConfigVersion.cmake \
  /usr/lib/cmake/selfsense/selfsenseTargets.cmake \
  /usr/lib/libselfsense_operators.a /usr/lib/libselfsense_models.a /usr/lib/libselfsense_control.a \
  /usr/share/doc/libselfsense-dev/copyright /usr/share/doc/libselfsense-dev/changelog.gz
grep -q '^/usr/bin/' "$work/dev.list" && fail "libselfsense-dev: ships programs"
grep -qE '^/usr/(include|lib/cmake)/|\.a$' "$work/runtime.list" && fail "selfsense: ships development files"
grep -q '^/usr/local' "$work/runtime.list" "$work/dev.list" && fail "a file under /usr/local"

# Control data.
for part in runtime dev; do
  deb=$runtime
  [ $part = dev ] && deb=$dev
  dpkg-deb -e "$deb" "$work/$part.control"
  printf '%s: ' "$part"
  dpkg-deb -f "$deb" Package Version Architecture Depends | tr '\n' ' '
  echo
  [ "$(dpkg-deb -f "$deb" Architecture)" = "$arch" ] ||
    fail "$part: Architecture is $(dpkg-deb -f "$deb" Architecture), not $arch"
done
for script in postinst prerm postrm; do
  file=$work/runtime.control/$script
  if [ -x "$file" ]; then
    sh -n "$file" || fail "selfsense: $script is not valid sh"
  else
    fail "selfsense: maintainer script $script missing or not executable"
  fi
done
grep -q 'systemd-sysusers' "$work/runtime.control/postinst" || fail "postinst: no systemd-sysusers"
grep -q 'stop selfsensed.service' "$work/runtime.control/prerm" || fail "prerm: does not stop the service"
grep -q 'rm -rf /etc/selfsense /var/lib/selfsensed' "$work/runtime.control/postrm" ||
  fail "postrm: purge does not remove /etc/selfsense and /var/lib/selfsensed"
# Every file under /etc is a conffile, and every conffile is in the package.
conffiles=$work/runtime.control/conffiles
[ -f "$conffiles" ] || fail "selfsense: no conffiles"
while read -r path; do
  [ -n "$path" ] && { grep -qxF "$path" "$conffiles" 2>/dev/null || fail "$path is not a conffile"; }
done < <(dpkg-deb -c "$runtime" | awk '$1 !~ /^d/ { print $6 }' | sed 's|^\./|/|' | grep '^/etc/' || true)
[ -f "$conffiles" ] && while read -r path; do
  grep -qxF "$path" "$work/runtime.list" || fail "conffile $path is not in the package"
done <"$conffiles"
# Depends computed by dpkg-shlibdeps from the programs' libraries.
depends=$(dpkg-deb -f "$runtime" Depends)
for lib in libc6 libstdc++6 libyaml-cpp0.7 libsystemd0 libmodbus5 libgpiod2; do
  grep -qE "(^|, )${lib//+/\\+}( |,|$)" <<<"$depends" || fail "selfsense: Depends has no $lib ($depends)"
done
grep -q 'libyaml-cpp-dev' <<<"$(dpkg-deb -f "$dev" Depends)" || fail "libselfsense-dev: Depends has no libyaml-cpp-dev"
# The Depends resolve among this architecture's packages (multiarch: libc6:arm64, ...): apt
# plans the installation without doing it.
if apt-get install -s -q -o Debug::NoLocking=1 --no-install-recommends "$runtime" >"$work/apt-simulate.log" 2>&1 &&
  grep -qE "^Inst selfsense(:$arch)? " "$work/apt-simulate.log"; then
  echo "apt-get -s install: Depends resolve for $arch"
else
  tail -15 "$work/apt-simulate.log"
  fail "apt-get -s install $(basename "$runtime"): Depends do not resolve for $arch"
fi

# The unpacked tree: the unit starts /usr/bin/selfsensed as selfsense; the installed
# configurations name files that the package installs and pass check-config.
root=$work/root
dpkg-deb -x "$runtime" "$root"
dpkg-deb -x "$dev" "$root"
# The programs and static libraries are built for the package's architecture.
case $arch in
  amd64) machine='x86-64' ;;
  arm64) machine='ARM aarch64' ;;
  armhf) machine='ARM, EABI5' ;;
  *) machine='' ;;
esac
for program in "$root/usr/bin/selfsensed" "$root/usr/bin/selfsense"; do
  description=$(file -b "$program")
  grep -q "^ELF .*$machine" <<<"$description" || fail "$(basename "$program") is not $arch ELF: $description"
done
echo "selfsensed: $(file -b "$root/usr/bin/selfsensed" | cut -d, -f1-3)"
mkdir -p "$work/objects"
object=$(ar t "$root/usr/lib/libselfsense_control.a" | head -1)
(cd "$work/objects" && ar x "$root/usr/lib/libselfsense_control.a" "$object")
file -b "$work/objects/$object" | grep -q "$machine" ||
  fail "libselfsense_control.a is not $arch: $(file -b "$work/objects/$object")"
unit=$root/lib/systemd/system/selfsensed.service
grep -qx 'ExecStart=/usr/bin/selfsensed --config /etc/selfsense/selfsensed.yaml' "$unit" ||
  fail "unit: ExecStart is $(grep '^ExecStart=' "$unit")"
grep -qx 'User=selfsense' "$unit" || fail "unit: not User=selfsense"
grep -q '^u selfsense ' "$root/usr/lib/sysusers.d/selfsense.conf" || fail "sysusers: no user selfsense"
for device in cpu_dma_latency spidev gpiochip; do
  grep -v '^#' "$root/lib/udev/rules.d/60-selfsense.rules" | grep "$device" | grep -q 'GROUP="selfsense"' ||
    fail "udev rule: $device not given to group selfsense"
done
grep -q 'type: simulated' "$root/etc/selfsense/selfsensed.yaml" ||
  fail "selfsensed.yaml: not the simulated transducer"
for config in "$root/etc/selfsense/selfsensed.yaml" "$root"/etc/selfsense/examples/*.yaml; do
  while read -r path; do
    [ -f "$root$path" ] || fail "$(basename "$config"): $path is not in the package"
  done < <(grep -oE '/usr/share/selfsense/[^ ]+\.yaml' "$config")
  # The configuration as it reads once installed: its shared files taken from the unpacked tree.
  sed "s|/usr/share/selfsense/|$root/usr/share/selfsense/|" "$config" >"$work/check-$(basename "$config")"
  run "$root/usr/bin/selfsense" check-config "$work/check-$(basename "$config")" >"$work/check.log" 2>&1 ||
    fail "check-config $(basename "$config"): $(head -3 "$work/check.log")"
done
run "$root/usr/bin/selfsensed" --help >/dev/null || fail "the packaged selfsensed --help failed"

# lintian: errors fail, the rest is listed.
if command -v lintian >/dev/null; then
  lintian --tag-display-limit 0 "$runtime" "$dev" >"$work/lintian.log" 2>&1 || true
  echo "lintian: $(grep -c '^E:' "$work/lintian.log") errors, $(grep -c '^W:' "$work/lintian.log") warnings"
  sed 's/^/  /' "$work/lintian.log"
  grep -q '^E:' "$work/lintian.log" && fail "lintian reports errors"
else
  fail "lintian is not installed (apt-get install lintian; scripts/setup.sh test installs it)"
fi

# An integrator's program: find_package(selfsense) from the unpacked libselfsense-dev.
mkdir -p "$work/consumer"
cat >"$work/consumer/CMakeLists.txt" <<'CMAKE'
cmake_minimum_required(VERSION 3.25)
project(consumer LANGUAGES CXX)
find_package(selfsense REQUIRED)
add_executable(consumer main.cpp)
target_link_libraries(consumer PRIVATE selfsense::control)
target_compile_features(consumer PRIVATE cxx_std_20)
CMAKE
cat >"$work/consumer/main.cpp" <<'CPP'
#include <selfsense/control/pid.hpp>
int main() {
  selfsense::control::Pid::Params p;
  p.gains.kp = 2.0;
  selfsense::control::Pid pid(p, 1e-3);
  return pid.step(1.0, 0.0) == 2.0 ? 0 : 1;
}
CPP
toolchain=()
[ -n "${PACKAGE_TOOLCHAIN:-}" ] && toolchain=(--toolchain "$PACKAGE_TOOLCHAIN")
if cmake -S "$work/consumer" -B "$work/consumer/build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  "${toolchain[@]}" -DCMAKE_PREFIX_PATH="$root/usr" >"$work/consumer.log" 2>&1 &&
  cmake --build "$work/consumer/build" >>"$work/consumer.log" 2>&1 &&
  run "$work/consumer/build/consumer"; then
  echo "find_package(selfsense): a program linked selfsense::control and ran"
else
  tail -20 "$work/consumer.log"
  fail "find_package(selfsense) from libselfsense-dev"
fi

if [ "$failures" -ne 0 ]; then
  echo "$failures check(s) failed"
  exit 1
fi
echo "packages: all checks passed"
