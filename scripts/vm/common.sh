# Sourced by the VM scripts: where the cached image lives and the key that names it.
# shellcheck shell=bash

vm_scripts=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
vm_cache_root=${SELFSENSE_VM_CACHE:-/var/cache/selfsense-vm}

vm_say() { printf '[vm] %s\n' "$*" >&2; }
vm_die() {
  printf '[vm] error: %s\n' "$*" >&2
  exit 1
}

# Everything that goes into the image is hashed, so any change to it builds a new image and a
# stale one is never used.
vm_key() {
  cat "$vm_scripts/image.sh" "$vm_scripts/packages.txt" "$vm_scripts"/guest/* | sha256sum | cut -c1-16
}

vm_image_dir() { printf '%s/%s\n' "$vm_cache_root" "$(vm_key)"; }

# The build writes "ready" last, so a half-built image is never taken for a finished one.
vm_image_ready() { [ -f "$(vm_image_dir)/ready" ]; }

# The packages of packages.txt, without comments and blank lines.
vm_packages() { sed -e 's/#.*//' -e '/^[[:space:]]*$/d' "$vm_scripts/packages.txt"; }
