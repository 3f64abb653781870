#!/usr/bin/env bash
# Host side of payload/daemon_systemd.sh: this build's selfsense package installed with apt and
# its selfsensed under systemd as PID 1 (Type=notify, watchdog restart of a frozen daemon,
# restart faulted after kill -9, clean stop, the model's memory written at the stop).
#   tests/vm/daemon_systemd.sh OUT_DIR   (after tests/vm/boot.sh OUT_DIR ...)
set -euo pipefail
# shellcheck source-path=SCRIPTDIR source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"

vm_check_test "${1:?usage: tests/vm/daemon_systemd.sh OUT_DIR}" daemon_systemd \
  'installed=[^ ]+ install ok installed' \
  'unit_path=/lib/systemd/system/selfsensed.service' \
  'exec_start=/usr/bin/selfsensed' \
  'is-active_after_install=inactive' \
  'verify=ok' \
  'is-active=active' \
  'nrestarts_while_running=0' \
  'socket_mode=660 selfsense' \
  'ctl_state=(faulted|ready|armed)' \
  'telemetry=yes' \
  'nrestarts_after_freeze=[1-9][0-9]*' \
  'watchdog_timeout_logged=yes' \
  'is-active_after_restart=active' \
  'state_before_kill9=armed' \
  'restarted_after_kill9=yes' \
  'state_after_kill9=faulted' \
  'is-active_after_stop=inactive' \
  'exit_status=0' \
  'clean_stop_logged=yes' \
  'model_state_written=yes'
