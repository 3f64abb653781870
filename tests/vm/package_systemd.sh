#!/usr/bin/env bash
# Host side of payload/package_systemd.sh: the selfsense Debian package installed with apt in the
# VM (the previous version first, its configuration changed, then upgraded: the change kept, the
# service restarted), enabled and run by systemd, armed through the installed tool, stopped,
# removed, purged. --no-upgrade: the boot brought no previous version (the arm64 VM), the
# package was installed at once.
#   tests/vm/package_systemd.sh OUT_DIR [--no-upgrade]   (after tests/vm/boot.sh OUT_DIR ... --packages BUILD)
set -euo pipefail
# shellcheck source-path=SCRIPTDIR source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"

out=${1:?usage: tests/vm/package_systemd.sh OUT_DIR [--no-upgrade]}
upgrade=(
  'previous=[^ ]*~prev install ok installed'
  'is-active_before_upgrade=active'
  'upgraded=yes'
  'config_after_upgrade=kept'
  'is-active_after_upgrade=active'
  'restarted_by_upgrade=yes'
)
[ "${2:-}" != --no-upgrade ] || upgrade=()
vm_check_test "$out" package_systemd \
  "${upgrade[@]}" \
  'installed=install ok installed' \
  'unit_path=/lib/systemd/system/selfsensed.service' \
  'user=selfsense,dialout' \
  'cpu_dma_latency_group=selfsense' \
  'is-enabled=enabled' \
  'is-active=active' \
  'exec_start=/usr/bin/selfsensed' \
  'cpu_latency_request=held' \
  'state_after_arm=armed' \
  'recording=selfsense:selfsense' \
  'is-active_after_stop=inactive' \
  'exit_status=0' \
  'running_after_remove=no' \
  'enabled_after_remove=no' \
  'config_after_remove=kept' \
  'after_purge='
