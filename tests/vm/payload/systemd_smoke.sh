#!/usr/bin/env bash
# Inside the VM, under systemd as PID 1: a Type=notify service with a watchdog, written in
# shell with systemd-notify. Checks that it is active once it sends READY=1, that its pings
# keep it alive past WatchdogSec, that systemd restarts it once the pings stop, and that
# `systemctl stop` returns. Prints "name=value" lines that tests/vm/systemd_smoke.sh checks.
set -euo pipefail

unit=selfsense-smoke-notify.service
watchdog_s=2
fail() {
  echo "FAILED: $*"
  systemctl status --no-pager "$unit" 2>&1 | head -20 || true
  exit 1
}
now() { cut -d' ' -f1 /proc/uptime; }
since() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.2f", b - a }'; }
prop() { systemctl show -p "$1" --value "$unit"; }

# The service: READY=1, pings for twice WatchdogSec, then hangs like a stalled loop. Not under
# /run: the initramfs mounts it noexec.
service=/usr/local/sbin/selfsense-smoke-notify
cat >"$service" <<EOF
#!/bin/bash
set -euo pipefail
systemd-notify --ready --status=pinging
for _ in \$(seq $((4 * watchdog_s))); do
  systemd-notify WATCHDOG=1
  sleep 0.5
done
systemd-notify --status=stalled
exec sleep infinity
EOF
chmod +x "$service"

# NotifyAccess=all: the notifications come from systemd-notify, a child of the main process.
cat >"/run/systemd/system/$unit" <<EOF
[Unit]
Description=selfsense VM smoke test: notify and watchdog

[Service]
Type=notify
NotifyAccess=all
ExecStart=$service
WatchdogSec=$watchdog_s
Restart=on-watchdog
RestartSec=1
LimitCORE=0
TimeoutStartSec=30
TimeoutStopSec=10
EOF
systemctl daemon-reload

begin=$(now)
# For Type=notify, start returns once READY=1 has arrived.
systemctl start "$unit" || fail "systemctl start failed"
echo "ready_after_s=$(since "$begin")"
state=$(systemctl is-active "$unit" || true)
echo "is-active=$state"
[ "$state" = active ] || fail "not active after READY=1"
echo "sub-state=$(prop SubState)"
restarts=$(prop NRestarts)
echo "nrestarts_at_start=$restarts"

# Still pinging: alive for longer than WatchdogSec, with no restart.
sleep $((watchdog_s + 1))
restarts_pinging=$(prop NRestarts)
echo "nrestarts_while_pinging=$restarts_pinging"
[ "$restarts_pinging" = "$restarts" ] || fail "restarted although it was pinging the watchdog"

# Pings stopped: the watchdog fires and systemd restarts the service.
for _ in $(seq 60); do
  [ "$(prop NRestarts)" -gt "$restarts" ] && break
  sleep 0.5
done
restarts_after=$(prop NRestarts)
echo "nrestarts_after_stall=$restarts_after"
echo "watchdog_restart_after_s=$(since "$begin")"
[ "$restarts_after" -gt "$restarts" ] || fail "no restart within 30 s of the pings stopping"
if journalctl -b -u "$unit" --no-pager | grep -q 'Watchdog timeout'; then
  echo "watchdog_timeout_logged=yes"
else
  fail "the journal has no 'Watchdog timeout' for $unit"
fi

# Back up after the restart, then stopped on request.
for _ in $(seq 40); do
  [ "$(systemctl is-active "$unit" || true)" = active ] && break
  sleep 0.5
done
echo "is-active_after_restart=$(systemctl is-active "$unit" || true)"
begin=$(now)
stop_rc=0
timeout 30 systemctl stop "$unit" || stop_rc=$?
echo "stop_rc=$stop_rc stop_s=$(since "$begin")"
[ "$stop_rc" -eq 0 ] || fail "systemctl stop returned $stop_rc"
state=$(systemctl is-active "$unit" || true)
echo "is-active_after_stop=$state"
[ "$state" = inactive ] || fail "state after stop is $state, not inactive"
