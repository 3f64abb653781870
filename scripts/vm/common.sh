# Sourced by the VM scripts: the architecture, where the cached image lives and the key that names it.
# shellcheck shell=bash

vm_scripts=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
vm_cache_root=${SELFSENSE_VM_CACHE:-/var/cache/selfsense-vm}
# The guest's Debian architecture: amd64 (qemu-system-x86_64) or arm64 (qemu-system-aarch64).
vm_arch=${SELFSENSE_VM_ARCH:-amd64}

vm_say() { printf '[vm] %s\n' "$*" >&2; }
vm_die() {
  printf '[vm] error: %s\n' "$*" >&2
  exit 1
}
case "$vm_arch" in
  amd64 | arm64) ;;
  *) vm_die "SELFSENSE_VM_ARCH: amd64 or arm64, not '$vm_arch'" ;;
esac

# Everything that goes into the image is hashed, so any change to it builds a new image and a
# stale one is never used.
vm_key() {
  { echo "$vm_arch"; cat "$vm_scripts/image.sh" "$vm_scripts/packages.txt" "$vm_scripts"/guest/*; } |
    sha256sum | cut -c1-16
}

# One directory per architecture, one image (KEY) in each.
vm_image_dir() { printf '%s/%s/%s\n' "$vm_cache_root" "$vm_arch" "$(vm_key)"; }

# The build writes "ready" last, so a half-built image is never taken for a finished one.
vm_image_ready() { [ -f "$(vm_image_dir)/ready" ]; }

# The packages of packages.txt for this architecture (ARCH in a name), without comments and
# blank lines.
vm_packages() { sed -e 's/#.*//' -e '/^[[:space:]]*$/d' -e "s/ARCH/$vm_arch/g" "$vm_scripts/packages.txt"; }

# The serial console's device in the guest: the PC's 16550 or the virt board's PL011.
vm_console() { if [ "$vm_arch" = arm64 ]; then echo ttyAMA0; else echo ttyS0; fi; }
