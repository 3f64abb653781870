#!/usr/bin/env bash
# Inside the VM, under systemd as PID 1: the selfsense Debian package (cmake/SelfsensePackage.cmake)
# of the VM's architecture installed with apt from /payload/files/packages, offline (the image
# holds its Depends): first the previous version (/payload/files/packages/previous, the same
# package as VERSION~prev), its /etc/selfsense/selfsensed.yaml changed and the service running,
# then upgraded to this build's package (the change kept, the service restarted and active).
# Without a previous package (the arm64 VM: fewer steps under emulation) this build's package is
# installed at once and its configuration changed the same way. Run as the package ships it: the
# unit from /lib/systemd/system, the user from sysusers.d, the devices' group from the udev rule,
# /etc/selfsense/selfsensed.yaml on the simulated transducer.
# Enabled and started, reset and armed through the installed `selfsense ctl`, a recording under
# /var/lib/selfsensed, a clean `systemctl stop`; `apt-get remove` stops the running service,
# `apt-get purge` removes the configuration and the state. Runs after daemon_systemd, whose
# install of the previous version (its configuration changed the same way) it upgrades.
# Prints "name=value" lines that tests/vm/package_systemd.sh checks.
set -euo pipefail

# The installed programs with Debian's libraries, not the payload's.
unset LD_LIBRARY_PATH
export PATH=/usr/sbin:/usr/bin:/sbin:/bin DEBIAN_FRONTEND=noninteractive
unit=selfsensed.service
fail() {
  echo "FAILED: $*"
  systemctl status --no-pager "$unit" 2>&1 | head -30 || true
  journalctl -b -u "$unit" --no-pager 2>&1 | tail -30 || true
  exit 1
}
prop() { systemctl show -p "$1" --value "$unit"; }
ctl() { /usr/bin/selfsense ctl "$@"; }
field() { sed -n "s/.*\"$1\":\"\\([a-z]*\\)\".*/\\1/p"; }

systemctl reset-failed "$unit" 2>/dev/null || true

arch=$(dpkg --print-architecture)
deb=$(ls /payload/files/packages/selfsense_*_"$arch".deb 2>/dev/null | head -1)
previous=$(ls /payload/files/packages/previous/selfsense_*_"$arch".deb 2>/dev/null | head -1 || true)
[ -n "$deb" ] || fail "no selfsense package in /payload/files/packages"
echo "package=$(dpkg-deb -f "$deb" Package Version | paste -sd' ')"
apt_get() { apt-get -q -y -o Dpkg::Use-Pty=0 "$@"; }
now() { cut -d' ' -f1 /proc/uptime; }
since() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.1f", b - a }'; }
begin=$(now)

# The administrator's change to the conffile. Software emulation is far from real time: the
# same tolerances as daemon_systemd (which may have put them in already), and a line of its own.
cfg=/etc/selfsense/selfsensed.yaml
change_config() {
  sed -i -e 's/rate_hz: 10000/rate_hz: 1000/' -e 's/frequency_hz: 2000.0/frequency_hz: 300.0/' \
    -e 's/allow_degraded_timing: false/allow_degraded_timing: true/' \
    -e 's/^  overrun: {consecutive: 3, within_count: 10, window_cycles: 10000}$/  overrun: {consecutive: 1000000, within_count: 0}/' \
    "$cfg"
  grep -q '^# changed on this board$' "$cfg" || echo "# changed on this board" >>"$cfg"
  grep -q '^  overrun: {consecutive: 1000000' "$cfg" || fail "the packaged selfsensed.yaml's overrun policy changed"
  selfsense check-config "$cfg" || fail "check-config rejected the changed configuration"
}

# The previous version first: the upgrade's starting point, configured and running. Then the
# upgrade, as an administrator runs it: the changed conffile stays (dpkg keeps it without a
# question when the package's own copy did not change), the running service is restarted on the
# new programs (postinst: try-restart).
install_and_upgrade() {
  local installed
  installed=$(dpkg-query -W -f='${Version} ${Status}' selfsense 2>/dev/null || true)
  if [ "$installed" = "$(dpkg-deb -f "$previous" Version) install ok installed" ]; then
    echo "previous_installed_by=daemon_systemd"  # the same package, its test run on it
  else
    [ -z "$installed" ] || [[ $installed == *" not-installed" ]] || [[ $installed == *" config-files" ]] ||
      fail "selfsense $installed is installed, not the previous version"
    apt_get install "$previous" >/tmp/apt-install-previous.log 2>&1 ||
      { tail -20 /tmp/apt-install-previous.log; fail "apt-get install $previous"; }
  fi
  echo "previous=$(dpkg-query -W -f='${Version} ${Status}' selfsense)"
  change_config
  systemctl enable --now "$unit" >/dev/null 2>&1 || fail "systemctl enable --now (previous version) failed"
  echo "is-active_before_upgrade=$(systemctl is-active "$unit" || true)"
  local pid_before pid_after
  pid_before=$(prop MainPID)

  apt_get install "$deb" >/tmp/apt-upgrade.log 2>&1 || { tail -20 /tmp/apt-upgrade.log; fail "apt-get install (upgrade) $deb"; }
  echo "upgraded=$([ "$(dpkg-query -W -f='${Version}' selfsense)" = "$(dpkg-deb -f "$deb" Version)" ] && echo yes || echo no)"
  echo "config_after_upgrade=$(grep -q '^# changed on this board$' "$cfg" && grep -q '^  overrun: {consecutive: 1000000' "$cfg" && echo kept || echo replaced)"
  for _ in $(seq 20); do [ "$(systemctl is-active "$unit" || true)" = active ] && break; sleep 0.5; done
  echo "is-active_after_upgrade=$(systemctl is-active "$unit" || true)"
  pid_after=$(prop MainPID)
  echo "restarted_by_upgrade=$([ "$pid_after" != 0 ] && [ "$pid_after" != "$pid_before" ] && echo yes || echo no)"
  # Measured only: what the upgrade's part of this test costs (docs/vm-testing.md).
  echo "seconds_previous_to_upgraded=$(since "$begin")"
}

if [ -n "$previous" ]; then
  install_and_upgrade
else
  apt_get install "$deb" >/tmp/apt-install.log 2>&1 || { tail -20 /tmp/apt-install.log; fail "apt-get install $deb"; }
  change_config
  echo "seconds_to_installed=$(since "$begin")"
fi
echo "installed=$(dpkg-query -W -f='${Status}' selfsense)"
echo "unit_path=$(prop FragmentPath)"
echo "user=$(id -nG selfsense | tr ' ' ',')"
udevadm settle --timeout=10 || true
# postinst's udevadm trigger applied the rule to the device that was there before the group.
echo "cpu_dma_latency_group=$(stat -c %G /dev/cpu_dma_latency)"

# The installed (upgraded) service, enabled and running (since the upgrade's restart).
systemctl enable --now "$unit" >/dev/null 2>&1 || fail "systemctl enable --now failed"
echo "is-enabled=$(systemctl is-enabled "$unit" || true)"
echo "is-active=$(systemctl is-active "$unit" || true)"
echo "exec_start=$(prop ExecStart | sed -n 's/.*path=\([^ ;]*\).*/\1/p')"
for _ in $(seq 40); do ctl status >/dev/null 2>&1 && break; sleep 0.5; done
status=$(ctl status 2>&1) || true
if grep -q 'CPU wake-up latency' <<<"$status"; then
  echo "cpu_latency_request=refused"
  grep -o 'CPU wake-up latency[^"]*' <<<"$status" | head -1
else
  echo "cpu_latency_request=held"
fi
for _ in $(seq 20); do ctl reset >/dev/null 2>&1 && break; sleep 0.2; done
echo "state_after_arm=$(ctl arm 2>&1 | field state)"
ctl record start >/dev/null || fail "record start"
sleep 2
ctl record stop >/dev/null || fail "record stop"
recording=$(find /var/lib/selfsensed/recordings -type f -size +0 2>/dev/null | head -1)
echo "recording=$([ -n "$recording" ] && stat -c '%U:%G' "$recording" || echo none)"

systemctl stop "$unit" || fail "systemctl stop failed"
echo "is-active_after_stop=$(systemctl is-active "$unit" || true)"
echo "exit_status=$(prop ExecMainStatus)"

# Remove stops the running service and disables it; the configuration stays until purge.
systemctl start "$unit" || fail "systemctl start (before remove) failed"
apt_get remove selfsense >/tmp/apt-remove.log 2>&1 ||
  { tail -20 /tmp/apt-remove.log; fail "apt-get remove"; }
running=$(grep -lx selfsensed /proc/[0-9]*/comm 2>/dev/null || true)
echo "running_after_remove=$([ -n "$running" ] && echo yes || echo no)"
echo "enabled_after_remove=$([ -e "/etc/systemd/system/multi-user.target.wants/$unit" ] && echo yes || echo no)"
echo "config_after_remove=$([ -f "$cfg" ] && echo kept || echo gone)"
apt_get purge selfsense >/tmp/apt-purge.log 2>&1 ||
  { tail -20 /tmp/apt-purge.log; fail "apt-get purge"; }
echo "after_purge=$(ls -d /etc/selfsense /var/lib/selfsensed 2>/dev/null | paste -sd, || true)"
