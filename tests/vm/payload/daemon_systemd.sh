#!/usr/bin/env bash
# Inside the VM, under systemd as PID 1: the selfsense Debian package installed with apt
# (lib/package.sh: this build's, as the previous version when the boot brought one, which
# package_systemd upgrades), run as it ships: the unit from /lib/systemd/system (ExecStart
# /usr/bin/selfsensed), the user from sysusers.d, the packaged /etc/selfsense/selfsensed.yaml on
# the simulated transducer with the emulation's tolerances put in (the administrator's change).
# Checks that `systemd-analyze verify` accepts the unit, that the service is active once it
# sent READY=1, that it keeps itself alive through the watchdog, that a frozen daemon gets
# restarted by the watchdog, that a kill -9 of an armed daemon restarts it faulted, and that
# `systemctl stop` ends it with status 0 after its safe-output shutdown.
# Prints "name=value" lines that tests/vm/daemon_systemd.sh checks.
set -euo pipefail

# shellcheck source-path=SCRIPTDIR source=lib/package.sh
source /payload/files/lib/package.sh
unit=selfsensed.service
fail() {
  echo "FAILED: $*"
  systemctl status --no-pager "$unit" 2>&1 | head -30 || true
  journalctl -b -u "$unit" --no-pager 2>&1 | tail -30 || true
  exit 1
}
prop() { systemctl show -p "$1" --value "$unit"; }

vm_install_package
echo "installed=$(dpkg-query -W -f='${Version} ${Status}' selfsense)"
echo "unit_path=$(prop FragmentPath)"
echo "exec_start=$(prop ExecStart | sed -n 's/.*path=\([^ ;]*\).*/\1/p')"
# An install starts nothing (postinst only restarts a running service on an upgrade), nor does
# can_loop, which may have installed it first.
echo "is-active_after_install=$(systemctl is-active "$unit" || true)"

# Software emulation is far from real time: a 1 kHz loop, degraded timing allowed, overruns
# tolerated, also as faults, so that the loop can be armed (this test is about systemd, not
# timing). The administrator's edit of the conffile.
cfg=/etc/selfsense/selfsensed.yaml
sed -i -e 's/rate_hz: 10000/rate_hz: 1000/' -e 's/frequency_hz: 2000.0/frequency_hz: 300.0/' \
  -e 's/allow_degraded_timing: false/allow_degraded_timing: true/' \
  -e 's/^  overrun: {consecutive: 3, within_count: 10, window_cycles: 10000}$/  overrun: {consecutive: 1000000, within_count: 0}/' \
  "$cfg"
grep -q '^  overrun: {consecutive: 1000000' "$cfg" ||
  fail "the packaged selfsensed.yaml's overrun policy changed: this test's tolerance was not put in"
selfsense check-config "$cfg" || fail "check-config rejected the configuration"

if verify=$(systemd-analyze verify "/lib/systemd/system/$unit" 2>&1); then
  echo "verify=ok"
else
  echo "verify=failed"
  awk '{ print "verify: " $0 }' <<<"$verify"
fi
systemd-analyze security --no-pager "$unit" 2>/dev/null | tail -1 | sed 's/^/security: /' || true
systemctl start "$unit" || fail "systemctl start failed"
state=$(systemctl is-active "$unit" || true)
echo "is-active=$state"
[ "$state" = active ] || fail "not active after READY=1"
sleep 8  # longer than WatchdogSec: the daemon's own pings keep it alive
echo "nrestarts_while_running=$(prop NRestarts)"
# The control socket under the unit's RuntimeDirectory, mode 0660, group selfsense.
sock=/run/selfsensed/control.sock
echo "socket_mode=$(stat -c '%a %G' "$sock" 2>/dev/null || echo missing)"
reply=$(selfsense ctl --socket "$sock" status 2>&1) || true
echo "ctl_state=$(sed -n 's/.*"state":"\([a-z]*\)".*/\1/p' <<<"$reply")"
echo "status_text=$(prop StatusText)"
[ -s /var/lib/selfsensed/selfsensed.prom ] && echo "telemetry=yes" || echo "telemetry=no"

# A frozen daemon (every thread stopped) sends no WATCHDOG=1: systemd restarts it.
pid=$(prop MainPID)
kill -STOP "$pid"
for _ in $(seq 60); do
  [ "$(prop NRestarts)" -ge 1 ] && break
  sleep 0.5
done
echo "nrestarts_after_freeze=$(prop NRestarts)"
for _ in $(seq 40); do
  [ "$(systemctl is-active "$unit" || true)" = active ] && break
  sleep 0.5
done
echo "is-active_after_restart=$(systemctl is-active "$unit" || true)"
if journalctl -b -u "$unit" --no-pager | grep -q 'Watchdog timeout'; then
  echo "watchdog_timeout_logged=yes"
fi

# kill -9 of an armed daemon: systemd restarts it (Restart=on-failure) and it comes up faulted,
# never armed, whatever it was doing before.
ctl() { selfsense ctl --socket "$sock" "$@"; }
for _ in $(seq 40); do ctl status >/dev/null 2>&1 && break; sleep 0.5; done
for _ in $(seq 20); do ctl reset >/dev/null 2>&1 && break; sleep 0.2; done
echo "state_before_kill9=$(ctl arm 2>&1 | sed -n 's/.*"state":"\([a-z]*\)".*/\1/p')"
restarts=$(prop NRestarts)
systemctl kill --signal=KILL "$unit"
for _ in $(seq 60); do
  [ "$(prop NRestarts)" -gt "$restarts" ] && [ "$(systemctl is-active "$unit" || true)" = active ] && break
  sleep 0.5
done
echo "restarted_after_kill9=$([ "$(prop NRestarts)" -gt "$restarts" ] && echo yes || echo no)"
for _ in $(seq 40); do ctl status >/dev/null 2>&1 && break; sleep 0.5; done
echo "state_after_kill9=$(ctl status 2>&1 | sed -n 's/.*"state":"\([a-z]*\)".*/\1/p')"

systemctl stop "$unit" || fail "systemctl stop failed"
echo "is-active_after_stop=$(systemctl is-active "$unit" || true)"
echo "exit_status=$(prop ExecMainStatus)"
if journalctl -b -u "$unit" --no-pager | grep -q 'selfsensed: stopped at cycle'; then
  echo "clean_stop_logged=yes"
fi
# The model's memory, written at the clean stop into the StateDirectory (ProtectSystem=strict).
if [ -s /var/lib/selfsensed/model-state.yaml ] &&
  tail -n 1 /var/lib/selfsensed/model-state.yaml | grep -q '^complete: true$'; then
  echo "model_state_written=yes"
fi
