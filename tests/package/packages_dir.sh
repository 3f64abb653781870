#!/usr/bin/env bash
# Prints a directory holding this build's Debian packages: package.contents' when they are newer
# than the programs, else built here with cpack into OUT_DIR (13 s). For the tests that install
# them (package.install, the VM's package_systemd).
#   tests/package/packages_dir.sh BUILD_DIR OUT_DIR
set -euo pipefail

build=$(cd "$1" && pwd)
out=$2
# A cross build names its architecture (cmake/SelfsensePackage.cmake); natively, dpkg's own.
arch=$(sed -n 's/^set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE "\(.*\)")$/\1/p' "$build/CPackConfig.cmake")
arch=${arch:-$(dpkg --print-architecture)}
version=$(sed -n 's/^set(CPACK_PACKAGE_VERSION "\(.*\)")$/\1/p' "$build/CPackConfig.cmake")
[ -n "$version" ] || { echo "packages_dir: no CPACK_PACKAGE_VERSION in $build/CPackConfig.cmake" >&2; exit 1; }
name=selfsense_${version}_${arch}.deb
contents=$build/tests/package/contents/cpack/packages
if [ -f "$contents/$name" ] && [ "$contents/$name" -nt "$build/src/selfsensed/selfsensed" ] &&
  [ "$contents/$name" -nt "$build/src/cli/selfsense" ]; then
  echo "$contents"
  exit 0
fi
rm -rf "$out"
mkdir -p "$out"
(cd "$out" && cpack --config "$build/CPackConfig.cmake" -B "$out") >"$out.log" 2>&1 ||
  { tail -30 "$out.log" >&2; echo "packages_dir: cpack failed (log: $out.log)" >&2; exit 1; }
[ -f "$out/packages/$name" ] || { echo "packages_dir: cpack made no $name" >&2; exit 1; }
echo "$out/packages"
