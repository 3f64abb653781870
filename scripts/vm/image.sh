#!/usr/bin/env bash
# Builds, as root, the Debian 12 VM image the VM tests boot under qemu: a debootstrap minbase
# root with Debian's kernel, systemd as PID 1, CAN tools and the project's runtime libraries
# (packages.txt), set up to boot fast on a serial console and to run the payload disk
# (guest/selfsense-payload.service). Cached under /var/cache/selfsense-vm/ARCH/KEY/ (KEY hashes
# the architecture, this script, packages.txt and guest/), so a second call returns at once.
#
#   scripts/vm/image.sh           build unless cached; prints the image directory on stdout
#   scripts/vm/image.sh --check   prints the directory and exits 0 if cached, exits 1 if not
#
# SELFSENSE_VM_ARCH=arm64 builds the arm64 image (booted by qemu-system-aarch64): the same root,
# made by debootstrap --arch=arm64 whose second stage and apt-get run under qemu-user
# (qemu-user-static through binfmt_misc).
#
# The directory holds root.img (ext4, label root), vmlinuz and initrd.img.
set -euo pipefail
# shellcheck source-path=SCRIPTDIR source=common.sh
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

suite=bookworm
dir=$(vm_image_dir)

if [ "${1:-}" = --check ]; then
  vm_image_ready || exit 1
  echo "$dir"
  exit 0
fi
[ $# -eq 0 ] || vm_die "usage: scripts/vm/image.sh [--check]"

if vm_image_ready; then
  vm_say "image: cached in $dir"
  echo "$dir"
  exit 0
fi
[ "$(id -u)" -eq 0 ] || vm_die "building the image needs root (debootstrap, chroot); run: sudo $0"

start=$SECONDS
step() { vm_say "image: $* (+$((SECONDS - start)) s)"; }

install_host_tools() {
  local missing=() tool package
  local tools=(debootstrap:debootstrap mke2fs:e2fsprogs debugfs:e2fsprogs)
  if [ "$vm_arch" = arm64 ]; then
    tools+=(qemu-system-aarch64:qemu-system-arm qemu-aarch64-static:qemu-user-static
      update-binfmts:binfmt-support)
  else
    tools+=(qemu-system-x86_64:qemu-system-x86)
  fi
  for tool in "${tools[@]}"; do
    package=${tool#*:}
    command -v "${tool%%:*}" >/dev/null || missing+=("$package")
  done
  [ ${#missing[@]} -eq 0 ] && return
  step "installing host tools ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -q
  apt-get install -y -q --no-install-recommends "${missing[@]}"
}

# The Debian mirrors the host's apt already uses (one-line and deb822 sources), so the image
# comes from the same place and has the same package versions as the host that builds the
# programs.
host_uris() {
  local f
  for f in /etc/apt/sources.list /etc/apt/sources.list.d/*.list /etc/apt/sources.list.d/*.sources; do
    [ -f "$f" ] || continue
    awk '/^[[:space:]]*deb[[:space:]]/ { for (i = 2; i <= NF; i++) if ($i !~ /^\[|\]$|=/) { print $i; break } }
         /^URIs:/ { for (i = 2; i <= NF; i++) print $i }' "$f"
  done
}
mirror=$(host_uris | grep -E '/debian/?$' | head -1 || true)
security=$(host_uris | grep -E '/debian-security/?$' | head -1 || true)
mirror=${mirror:-http://deb.debian.org/debian}
security=${security:-http://deb.debian.org/debian-security}

# The arm64 root's programs run here under qemu-user: the kernel must hand aarch64 ELF files to
# qemu-aarch64-static (binfmt_misc, registered by qemu-user-static's postinst).
enable_binfmt() {
  [ "$vm_arch" = arm64 ] || return 0
  [ -f /proc/sys/fs/binfmt_misc/status ] || mount -t binfmt_misc binfmt_misc /proc/sys/fs/binfmt_misc
  [ -f /proc/sys/fs/binfmt_misc/qemu-aarch64 ] || update-binfmts --enable qemu-aarch64 >&2 ||
    vm_die "no binfmt_misc entry for aarch64 (update-binfmts --enable qemu-aarch64)"
}

install_host_tools
enable_binfmt
mkdir -p "$vm_cache_root/$vm_arch"
# One build at a time; a second caller waits and then finds the image cached.
exec 9>"$vm_cache_root/.lock"
flock 9
if vm_image_ready; then
  vm_say "image: built meanwhile by another caller, in $dir"
  echo "$dir"
  exit 0
fi

build="$dir.build"
root="$build/root"
unmount_all() {
  local m
  for m in dev/pts dev sys proc; do
    mountpoint -q "$root/$m" 2>/dev/null && umount -l "$root/$m"
  done
  return 0
}
# shellcheck disable=SC2317 # called by the EXIT trap
cleanup() {
  unmount_all
  mountpoint -q "$root" 2>/dev/null && umount -l "$root"
  return 0
}
trap cleanup EXIT
cleanup
rm -rf --one-file-system "$build"
mkdir -p "$root"
# The root is built in memory: dpkg's many fsyncs cost minutes on a busy disk and nothing of
# the root is kept but the ext4 image made from it.
mount -t tmpfs -o size=4g,mode=0755 selfsense-vm-root "$root"

step "debootstrap --arch=$vm_arch --variant=minbase $suite from $mirror"
debootstrap --arch="$vm_arch" --variant=minbase "$suite" "$root" "$mirror" >"$build/debootstrap.log" 2>&1 ||
  { tail -20 "$build/debootstrap.log" >&2; vm_die "debootstrap failed (log: $build/debootstrap.log)"; }

cat >"$root/etc/apt/sources.list" <<EOF
deb $mirror $suite main
deb $mirror $suite-updates main
deb $security $suite-security main
EOF
# Documentation and translations are never read inside the VM; leaving them out keeps the image small.
cat >"$root/etc/dpkg/dpkg.cfg.d/01-selfsense-nodoc" <<'EOF'
path-exclude=/usr/share/doc/*
path-exclude=/usr/share/man/*
path-exclude=/usr/share/info/*
path-exclude=/usr/share/locale/*
path-include=/usr/share/locale/locale.alias
EOF
# No service may start inside the chroot.
printf '#!/bin/sh\nexit 101\n' >"$root/usr/sbin/policy-rc.d"
chmod +x "$root/usr/sbin/policy-rc.d"
# A small initramfs with only the virtio disk driver boots faster under emulation than
# Debian's default of most modules.
mkdir -p "$root/etc/initramfs-tools/conf.d"
printf 'MODULES=list\nCOMPRESS=gzip\n' >"$root/etc/initramfs-tools/conf.d/selfsense"
printf 'virtio_pci\nvirtio_mmio\nvirtio_blk\next4\ncrc32c_generic\n' >"$root/etc/initramfs-tools/modules"

mount -t proc proc "$root/proc"
mount -t sysfs sys "$root/sys"
mount --bind /dev "$root/dev"
mount --bind /dev/pts "$root/dev/pts"

mapfile -t packages < <(vm_packages)
step "apt-get install ${packages[*]}"
in_root() { chroot "$root" env DEBIAN_FRONTEND=noninteractive LC_ALL=C "$@"; }
{
  in_root apt-get update -q
  # confold keeps the initramfs module list written above.
  in_root apt-get install -y -q --no-install-recommends \
    -o Dpkg::Options::=--force-confdef -o Dpkg::Options::=--force-confold "${packages[@]}"
  in_root apt-get clean
} >"$build/apt.log" 2>&1 || { tail -20 "$build/apt.log" >&2; vm_die "apt-get in the root failed (log: $build/apt.log)"; }
unmount_all

step "configuring boot, console and the payload unit"
rm -f "$root/usr/sbin/policy-rc.d"
rm -rf "$root"/var/lib/apt/lists/* "$root"/usr/share/doc/* "$root"/usr/share/man/*
echo selfsense-vm >"$root/etc/hostname"
printf '127.0.0.1 localhost\n127.0.1.1 selfsense-vm\n' >"$root/etc/hosts"
# Pass 0: no fsck of a fresh snapshot on every boot.
printf 'LABEL=root / ext4 rw,noatime 0 0\n' >"$root/etc/fstab"
# A fixed machine id, so systemd does not treat each boot as the first (no firstboot prompts).
chroot "$root" systemd-machine-id-setup >/dev/null
# An empty root password makes emergency.target usable for debugging by hand (see docs).
chroot "$root" passwd -d root >/dev/null
mkdir -p "$root/etc/systemd/journald.conf.d"
install -m 0644 "$vm_scripts/guest/journald.conf" "$root/etc/systemd/journald.conf.d/selfsense.conf"
install -m 0755 "$vm_scripts/guest/selfsense-payload" "$root/usr/local/sbin/selfsense-payload"
sed "s|/dev/ttyS0|/dev/$(vm_console)|" "$vm_scripts/guest/selfsense-payload.service" \
  >"$root/etc/systemd/system/selfsense-payload.service"
chroot "$root" systemctl enable selfsense-payload.service >/dev/null 2>&1
# Nothing else may write to the serial console or hold up the boot: no login prompts (a getty
# hangs up the tty the payload writes to), no timers, no waiting for a network, and none of the
# kernel modules and pseudo file systems nothing here uses (each costs about a second under
# emulation).
timers=()
for timer in "$root"/lib/systemd/system/*.timer; do
  [[ $timer == *@* ]] || timers+=("$(basename "$timer")")
done
chroot "$root" systemctl mask getty@tty1.service "serial-getty@$(vm_console).service" getty.target \
  systemd-firstboot.service systemd-networkd-wait-online.service e2scrub_reap.service \
  modprobe@configfs.service modprobe@dm_mod.service modprobe@drm.service \
  modprobe@efi_pstore.service modprobe@fuse.service modprobe@loop.service \
  sys-kernel-config.mount sys-kernel-debug.mount sys-kernel-tracing.mount \
  sys-fs-fuse-connections.mount dev-hugepages.mount \
  "${timers[@]}" >/dev/null 2>&1

cp -L "$root/vmlinuz" "$build/vmlinuz"
cp -L "$root/initrd.img" "$build/initrd.img"

step "mke2fs root.img"
size_mib=$(($(du -sm "$root" | cut -f1) * 3 / 2 + 512))
# mke2fs names the file it creates on stdout, which is reserved for the image directory.
mke2fs -q -t ext4 -L root -d "$root" "$build/root.img" "${size_mib}M" >&2
umount "$root"
rmdir "$root"
vm_packages >"$build/packages"
touch "$build/ready"

rm -rf "$dir"
mv "$build" "$dir"
# Images of older keys (of this architecture) are never used again.
find "$vm_cache_root/$vm_arch" -mindepth 1 -maxdepth 1 -type d ! -path "$dir" -exec rm -rf --one-file-system {} +
step "done: $dir ($(du -sh "$dir/root.img" | cut -f1) image, $((SECONDS - start)) s)"
echo "$dir"
