#!/usr/bin/env bash
# Host side of payload/systemd_smoke.sh: systemd as PID 1 ran a Type=notify service, restarted
# it on a watchdog timeout and stopped it.
#   tests/vm/systemd_smoke.sh OUT_DIR   (after tests/vm/boot.sh OUT_DIR)
set -euo pipefail
# shellcheck source-path=SCRIPTDIR source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"

vm_check_test "${1:?usage: tests/vm/systemd_smoke.sh OUT_DIR}" systemd_smoke \
  'is-active=active' \
  'nrestarts_at_start=0' \
  'nrestarts_while_pinging=0' \
  'nrestarts_after_stall=[1-9][0-9]*' \
  'watchdog_timeout_logged=yes' \
  'is-active_after_restart=active' \
  'stop_rc=0 stop_s=[0-9.]+' \
  'is-active_after_stop=inactive'
