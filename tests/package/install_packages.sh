#!/usr/bin/env bash
# The selfsense package installed with apt into a minimal Debian 12 root: a throw-away overlay
# on the VM image (scripts/vm/image.sh, debootstrap minbase with the runtime libraries), entered
# with chroot. Checks that apt installs it offline (its Depends are met by Debian's packages),
# that postinst created the selfsense user and group, that the installed programs run on the
# installed configuration, that an upgrade keeps a changed /etc/selfsense/selfsensed.yaml, that
# remove keeps the configuration and purge removes it and /var/lib/selfsensed. No systemd runs in
# a chroot: starting the service is the VM's job (issue 25). Root only; skips (77) without the
# cached image.
#
#   install_packages.sh SOURCE_DIR BUILD_DIR WORK_DIR
set -euo pipefail

source_dir=$(cd "$1" && pwd)
build=$(cd "$2" && pwd)
work=$3

[ "$(id -u)" -eq 0 ] || { echo "SKIP: needs root (loop mount, overlay, chroot)"; exit 77; }
image=$(bash "$source_dir/scripts/vm/image.sh" --check 2>/dev/null) ||
  { echo "SKIP: no cached VM image; build it with scripts/vm/image.sh (as root)"; exit 77; }

# The packages of package.contents when up to date, else built here.
arch=$(dpkg --print-architecture)
version=$(sed -n 's/^set(CPACK_PACKAGE_VERSION "\(.*\)")$/\1/p' "$build/CPackConfig.cmake")
rm -rf "$work"
mkdir -p "$work"
debs=$(bash "$source_dir/tests/package/packages_dir.sh" "$build" "$work/cpack")
runtime=$debs/selfsense_${version}_${arch}.deb

# The same package as the next version: an upgrade.
dpkg-deb -R "$runtime" "$work/next"
next_version="$version.1"
sed -i "s/^Version: .*/Version: $next_version/" "$work/next/DEBIAN/control"
dpkg-deb --root-owner-group -b "$work/next" "$work/selfsense_${next_version}_${arch}.deb" >/dev/null

lower=$work/lower root=$work/root
mkdir -p "$lower" "$root" "$work/upper" "$work/overlay-work"
mounted=()
cleanup() {
  local i
  for ((i = ${#mounted[@]} - 1; i >= 0; i--)); do umount -l "${mounted[$i]}" 2>/dev/null || true; done
}
trap cleanup EXIT
mount -o ro,loop,noload "$image/root.img" "$lower" ||
  { echo "SKIP: cannot loop-mount $image/root.img"; exit 77; }
mounted+=("$lower")
mount -t overlay overlay -o "lowerdir=$lower,upperdir=$work/upper,workdir=$work/overlay-work" "$root" ||
  { echo "SKIP: cannot mount an overlay"; exit 77; }
mounted+=("$root")
mount -t proc proc "$root/proc" && mounted+=("$root/proc")
mount --bind /dev "$root/dev" && mounted+=("$root/dev")
cp "$runtime" "$work/selfsense_${next_version}_${arch}.deb" "$root/tmp/"

failures=0
fail() {
  echo "FAIL: $*"
  failures=$((failures + 1))
}
in_root() { chroot "$root" env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin DEBIAN_FRONTEND=noninteractive "$@"; }
apt_get() { in_root apt-get -q -y -o Dpkg::Use-Pty=0 "$@"; }

begin=$SECONDS
if apt_get install "/tmp/$(basename "$runtime")" >"$work/install.log" 2>&1; then
  echo "install: apt-get install ./$(basename "$runtime"): ok"
else
  tail -30 "$work/install.log"
  echo "FAIL: apt-get install"
  exit 1
fi
# Offline: nothing but the package itself is fetched.
fetched=$(grep -E '^Get:' "$work/install.log" | grep -v ' /tmp/selfsense_' || true)
[ -z "$fetched" ] || fail "apt fetched packages: $fetched"
echo "status: $(in_root dpkg-query -W -f='${Package} ${Version} ${Status}' selfsense)"
echo "user: $(in_root id selfsense 2>&1)"
in_root getent passwd selfsense | grep -q ':/usr/sbin/nologin$' || fail "no system user selfsense with nologin"
in_root id -nG selfsense | grep -qw dialout || fail "selfsense is not in dialout"
for path in /usr/bin/selfsensed /usr/bin/selfsense /lib/systemd/system/selfsensed.service \
  /etc/selfsense/selfsensed.yaml /usr/share/selfsense/models/sim.yaml; do
  [ -f "$root$path" ] || fail "$path not installed"
done
in_root dpkg-query -W -f='${Conffiles}\n' selfsense | grep -q '/etc/selfsense/selfsensed.yaml' ||
  fail "dpkg does not know /etc/selfsense/selfsensed.yaml as a conffile"
# The installed programs on the installed configuration, with Debian's libraries only.
in_root selfsense check-config /etc/selfsense/selfsensed.yaml >"$work/check.log" 2>&1 ||
  fail "check-config /etc/selfsense/selfsensed.yaml: $(head -3 "$work/check.log")"
in_root selfsensed --help >/dev/null 2>&1 || fail "selfsensed --help"

# Upgrade: the administrator's change to the configuration stays.
echo "# changed on this board" >>"$root/etc/selfsense/selfsensed.yaml"
apt_get install "/tmp/selfsense_${next_version}_${arch}.deb" >"$work/upgrade.log" 2>&1 ||
  { tail -20 "$work/upgrade.log"; fail "apt-get install (upgrade to $next_version)"; }
echo "upgrade: $(in_root dpkg-query -W -f='${Version}' selfsense)"
grep -q '^# changed on this board$' "$root/etc/selfsense/selfsensed.yaml" ||
  fail "the upgrade replaced the changed /etc/selfsense/selfsensed.yaml"

# Remove keeps the configuration; purge removes it and the daemon's state.
mkdir -p "$root/var/lib/selfsensed/recordings"
touch "$root/var/lib/selfsensed/recordings/r.csv"
apt_get remove selfsense >"$work/remove.log" 2>&1 || { tail -20 "$work/remove.log"; fail "apt-get remove"; }
[ -e "$root/usr/bin/selfsensed" ] && fail "remove left /usr/bin/selfsensed"
[ -f "$root/etc/selfsense/selfsensed.yaml" ] || fail "remove took /etc/selfsense/selfsensed.yaml"
apt_get purge selfsense >"$work/purge.log" 2>&1 || { tail -20 "$work/purge.log"; fail "apt-get purge"; }
[ -e "$root/etc/selfsense" ] && fail "purge left /etc/selfsense"
[ -e "$root/var/lib/selfsensed" ] && fail "purge left /var/lib/selfsensed"
echo "install, upgrade, remove, purge: $((SECONDS - begin)) s"

if [ "$failures" -ne 0 ]; then
  echo "$failures check(s) failed"
  exit 1
fi
echo "install: all checks passed"
