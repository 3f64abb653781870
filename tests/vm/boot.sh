#!/usr/bin/env bash
# CTest fixture vm.boot: one VM boot that runs every tests/vm/payload/*.sh. It fails only when
# the VM itself did not report (timeout, panic, no payload); each test's own result is checked
# by its CTest test (systemd_smoke.sh, can_smoke.sh, ...), so one failure does not hide the
# others. The PROGRAMs (host-built, e.g. the selfsense tool) go in with their libraries;
# --packages BUILD_DIR: the build's selfsense package (tests/package/packages_dir.sh) as
# /payload/files/packages/, and the same as a lower version in /payload/files/packages/previous/
# (the upgrade's starting point), unless --no-previous; with it payload/lib/ as
# /payload/files/lib/ (the tests' code to install it). --only NAME (repeated): only those
# tests/vm/payload/NAME.sh. SELFSENSE_VM_ARCH (amd64 or arm64) chooses the VM (scripts/vm/).
#   tests/vm/boot.sh OUT_DIR [PROGRAM... | --file PATH... | --packages BUILD_DIR | --no-previous | --only NAME...]
set -euo pipefail
# shellcheck source-path=SCRIPTDIR source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"

# vm_previous_package BUILT DIR: DIR/ holds this build's selfsense package and the same package
# as a lower version (VERSION~prev, repacked with dpkg-deb), the one the VM upgrades from.
vm_previous_package() {
  local built=$1 dir=$2 deb version previous
  rm -rf "$dir" "$dir.tree"
  mkdir -p "$dir"
  deb=$(ls "$built"/selfsense_*_"$vm_arch".deb) || return 1
  cp "$deb" "$dir/"
  version=$(dpkg-deb -f "$deb" Version)
  previous="$version~prev"
  dpkg --compare-versions "$previous" lt "$version" || return 1
  dpkg-deb -R "$deb" "$dir.tree"
  sed -i "s/^Version: .*/Version: $previous/" "$dir.tree/DEBIAN/control"
  mkdir -p "$dir/previous"
  dpkg-deb --root-owner-group -b "$dir.tree" "$dir/previous/selfsense_${previous}_$vm_arch.deb" >/dev/null
  rm -rf "$dir.tree"
}

[ $# -ge 1 ] || { echo "usage: tests/vm/boot.sh OUT_DIR [PROGRAM...]" >&2; exit 2; }
out=$1
shift
vm_require_image
args=(--timeout 540)
packages=
previous=yes
tests=()
while [ $# -gt 0 ]; do
  if [ "$1" = --file ]; then
    args+=(--file "${2:?--file needs a path}")
    shift 2
  elif [ "$1" = --packages ]; then
    packages=${2:?--packages needs a build directory}
    shift 2
  elif [ "$1" = --no-previous ]; then
    previous=no
    shift
  elif [ "$1" = --only ]; then
    tests+=("$vm_repo/tests/vm/payload/${2:?--only needs a test name}.sh")
    shift 2
  else
    args+=(--program "$1")
    shift
  fi
done
if [ -n "$packages" ]; then
  built=$(bash "$vm_repo/tests/package/packages_dir.sh" "$packages" "$out-cpack") ||
    { echo "FAIL: no packages to install in the VM"; exit 1; }
  if [ "$previous" = yes ]; then
    vm_previous_package "$built" "$out-vm/packages" || { echo "FAIL: no previous package for the upgrade"; exit 1; }
  else
    rm -rf "$out-vm/packages"
    mkdir -p "$out-vm/packages"
    cp "$built"/selfsense_*_"$vm_arch".deb "$out-vm/packages/" || { echo "FAIL: no $vm_arch package"; exit 1; }
  fi
  # With the code the tests that install it share (payload/lib/package.sh).
  args+=(--file "$out-vm/packages" --file "$vm_repo/tests/vm/payload/lib")
fi
[ ${#tests[@]} -gt 0 ] || tests=("$vm_repo"/tests/vm/payload/*.sh)
status=0
"$vm_repo/scripts/vm/run_tests.sh" "$out" "${args[@]}" "${tests[@]}" || status=$?
case "$status" in
  77) echo "SKIP: no cached VM image"; exit "$vm_skip" ;;
  124 | 125) echo "FAIL: the VM did not report (status $status); console: $out/console.log"; exit 1 ;;
  0) echo "vm.boot: every payload test passed" ;;
  *) echo "vm.boot: the VM ran; $status payload test(s) failed (see their own results)" ;;
esac
