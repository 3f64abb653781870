#!/usr/bin/env bash
# Host side of payload/can_smoke.sh: the kernel's SocketCAN stack with vcan carried a standard,
# an extended and a CAN FD frame from cansend to candump.
#   tests/vm/can_smoke.sh OUT_DIR   (after tests/vm/boot.sh OUT_DIR)
set -euo pipefail
# shellcheck source-path=SCRIPTDIR source=lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"

vm_check_test "${1:?usage: tests/vm/can_smoke.sh OUT_DIR}" can_smoke \
  'fd_refused_at_mtu16=yes' \
  'seen_standard=yes' \
  'seen_extended=yes' \
  'seen_fd=yes' \
  'frames=3'
