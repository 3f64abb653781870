# Sourced by the payload tests that run the selfsense Debian package (can_loop, daemon_systemd;
# tests/vm/boot.sh --packages brings it to /payload/files/packages and this file to
# /payload/files/lib): the programs as the package installs them, with Debian's libraries, not
# the payload's (/payload/bin, /payload/lib).
# shellcheck shell=bash

unset LD_LIBRARY_PATH
export PATH=/usr/sbin:/usr/bin:/sbin:/bin DEBIAN_FRONTEND=noninteractive

# vm_install_package: this build's selfsense package of the VM's architecture installed with apt
# from /payload/files/packages, offline (the image holds its Depends). The previous version
# (packages/previous/, VERSION~prev: the same files) when the boot brought one, so that
# package_systemd upgrades from this install instead of installing again. Installing the same
# version again changes nothing (apt: already the newest version), so every test that needs the
# package calls this, whichever runs first. Calls the test's own `fail` when apt fails.
vm_install_package() {
  local arch deb log=/tmp/apt-install-selfsense.log
  arch=$(dpkg --print-architecture)
  # shellcheck disable=SC2012 # names that cpack and boot.sh made: no odd characters
  deb=$(ls /payload/files/packages/previous/selfsense_*_"$arch".deb /payload/files/packages/selfsense_*_"$arch".deb \
    2>/dev/null | head -1 || true)
  [ -n "$deb" ] || fail "no selfsense package in /payload/files/packages (tests/vm/boot.sh --packages)"
  apt-get -q -y -o Dpkg::Use-Pty=0 install "$deb" >>"$log" 2>&1 ||
    { tail -20 "$log"; fail "apt-get install $deb"; }
}
