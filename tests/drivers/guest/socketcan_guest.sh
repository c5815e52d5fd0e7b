#!/usr/bin/env bash
# Runs a SocketCAN test binary on a real kernel CAN stack with a vcan0 interface.
#
#   socketcan_guest.sh TEST_BINARY [ARGS...]
#
# 1. On a host whose kernel has vcan (a lab PC), it creates vcan0 if needed and runs the
#    binary directly.
# 2. Otherwise it boots Debian's own kernel under qemu (TCG, no KVM) with a busybox
#    initramfs, loads can, can-raw and vcan, shares the host's / read-only over 9p,
#    chroots into it and runs the same binary there (../shared/design/SOCKETCAN-TESTING.md,
#    route A). The kernel package is downloaded once with apt-get and cached, never
#    installed: ${HAPTIC_GUEST_CACHE:-~/.cache/haptic-guest}.
# 3. When neither is possible it prints why and exits 77, which ctest reports as skipped.
#    It never reports success for tests that did not run.
#
# HAPTIC_SOCKETCAN_ROUTE=host|guest forces a route (guest: even on a host with vcan).
# Exit status: the test binary's, 77 when skipped, 1 when the guest failed.
set -uo pipefail

readonly SKIP=77
readonly GUEST_TIMEOUT_S=${HAPTIC_GUEST_TIMEOUT_S:-420}
# Module load order (Debian ships no modules.dep we could use without depmod).
readonly MODULES=(virtio virtio_ring virtio_pci_modern_dev virtio_pci_legacy_dev virtio_pci
  netfs fscache 9pnet 9pnet_virtio 9p can can-raw can-dev vcan)

skip() {
  echo "SKIPPED: the SocketCAN tests did not run: $*" >&2
  exit $SKIP
}
log() { echo "socketcan_guest: $*" >&2; }

if (($# < 1)); then
  echo "usage: $0 TEST_BINARY [ARGS...]" >&2
  exit 2
fi
test_binary=$(realpath "$1")
shift
[[ -x $test_binary ]] || { echo "socketcan_guest: $test_binary is not executable" >&2; exit 2; }
route=${HAPTIC_SOCKETCAN_ROUTE:-auto}

host_has_vcan() {
  [[ -e /sys/class/net/vcan0 ]] && return 0
  [[ $(id -u) -eq 0 ]] || return 1
  modprobe vcan 2>/dev/null || true
  ip link add dev vcan0 type vcan 2>/dev/null || return 1
  ip link set vcan0 mtu 72 && ip link set vcan0 up
}

if [[ $route != guest ]] && host_has_vcan; then
  log "host kernel has vcan0: running directly"
  exec "$test_binary" "$@"
fi
[[ $route == host ]] && skip "HAPTIC_SOCKETCAN_ROUTE=host, but this kernel has no vcan0 (and it cannot be created)"

# --- guest route --------------------------------------------------------------------------
command -v qemu-system-x86_64 >/dev/null || skip "no vcan in this kernel and no qemu-system-x86_64 (Debian package qemu-system-x86)"
is_static() { [[ -x $1 ]] && [[ $(LC_ALL=C ldd "$1" 2>&1) == *"not a dynamic executable"* ]]; }
busybox=$(command -v busybox || echo /bin/busybox)
is_static "$busybox" ||
  skip "no vcan in this kernel and no static busybox for the guest (Debian package busybox-static)"
command -v ip >/dev/null || skip "no 'ip' (iproute2) to create vcan0 in the guest"

cache=${HAPTIC_GUEST_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/haptic-guest}
mkdir -p "$cache" || skip "cannot create the guest cache $cache"
kernel_package=$(apt-cache depends linux-image-amd64 2>/dev/null | awk '/Depends: linux-image-[0-9]/ {print $2; exit}')
if [[ -z $kernel_package ]]; then
  kernel_package=$(cd "$cache" && ls -d linux-image-*-amd64 2>/dev/null | tail -1)
fi
[[ -n $kernel_package ]] || skip "cannot tell which Debian kernel to use (apt-cache depends linux-image-amd64 gave nothing; run apt-get update)"
kdir=$cache/$kernel_package

prepare_kernel() {
  local work=$kdir.tmp
  rm -rf "$work" && mkdir -p "$work" || return 1
  log "downloading $kernel_package (once; cached in $cache)"
  (cd "$work" && apt-get download "$kernel_package" >/dev/null 2>&1) || { log "apt-get download $kernel_package failed"; return 1; }
  dpkg-deb -x "$work"/*.deb "$work/root" || return 1
  local vmlinuz offset
  vmlinuz=$(ls "$work"/root/boot/vmlinuz-* | head -1)
  # The bzImage holds an xz stream; booting it decompressed saves ~3.5 s per run under TCG.
  offset=$(LC_ALL=C grep -abo $'\xfd7zXZ\x00' "$vmlinuz" | head -1 | cut -d: -f1)
  [[ -n $offset ]] || { log "no xz stream in $vmlinuz"; return 1; }
  tail -c +$((offset + 1)) "$vmlinuz" | xz -dc >"$work/vmlinux" 2>/dev/null
  [[ $(head -c 4 "$work/vmlinux" | od -An -c | tr -d ' ') == 177ELF ]] || { log "could not extract vmlinux"; return 1; }
  mkdir -p "$work/modules"
  local module path
  for module in "${MODULES[@]}"; do
    path=$(find "$work"/root/lib/modules -name "$module.ko" | head -1)
    [[ -n $path ]] || { log "module $module.ko missing from $kernel_package"; return 1; }
    cp "$path" "$work/modules/"
  done
  rm -rf "$work/root" "$work"/*.deb
  rm -rf "$kdir" && mv "$work" "$kdir"
}
if [[ ! -f $kdir/vmlinux ]]; then
  prepare_kernel || skip "no vcan in this kernel and the guest kernel $kernel_package could not be prepared (see above)"
fi

out=$(mktemp -d "${TMPDIR:-/tmp}/haptic-guest.XXXXXX")
# The guest sees the host's / read-only and the host's /tmp writable (a tmpfs there would hide
# a checkout or build under /tmp); the test binary's folder is shared writable so that
# results (--gtest_output) come back. Paths must not contain spaces (kernel command line).
results=$(dirname "$test_binary")
[[ $out != *" "* && $results != *" "* ]] || skip "paths with spaces cannot be passed to the guest: $out $results"
trap 'rm -rf "$out"' EXIT
# The initramfs: static busybox, the modules and an init that mounts the host and runs job.sh.
initrd_dir=$out/initrd
mkdir -p "$initrd_dir"/{bin,proc,sys,dev,host,modules}
cp "$busybox" "$initrd_dir/bin/busybox"
cp "$kdir"/modules/*.ko "$initrd_dir/modules/"
printf '%s\n' "${MODULES[@]}" >"$initrd_dir/modules/order"
cat >"$initrd_dir/init" <<'INIT'
#!/bin/busybox sh
/bin/busybox --install -s /bin
export PATH=/bin
mount -t proc proc /proc
mount -t sysfs sysfs /sys
mount -t devtmpfs devtmpfs /dev
for pass in 1 2 3; do
  for m in $(cat /modules/order); do
    name=$(echo "$m" | tr - _)
    grep -q "^$name " /proc/modules || insmod /modules/$m.ko 2>/dev/null
  done
done
out=$(sed -n 's/.*haptic\.out=\([^ ]*\).*/\1/p' /proc/cmdline)
results=$(sed -n 's/.*haptic\.results=\([^ ]*\).*/\1/p' /proc/cmdline)
if mount -t 9p -o trans=virtio,version=9p2000.L,ro,msize=512000,cache=loose hostroot /host &&
   mount -t proc proc /host/proc && mount -t sysfs sysfs /host/sys &&
   mount -t devtmpfs devtmpfs /host/dev &&
   mount -t 9p -o trans=virtio,version=9p2000.L,msize=512000 hosttmp /host/tmp &&
   mount -t tmpfs tmpfs /host/run && mkdir -p "/host$out" &&
   mount -t 9p -o trans=virtio,version=9p2000.L,msize=512000 results "/host$results" &&
   mount -t 9p -o trans=virtio,version=9p2000.L,msize=512000 out "/host$out"; then
  chroot /host /bin/sh "$out/job.sh"
else
  echo "guest: mounting the host over 9p failed"
fi
poweroff -f
INIT
chmod +x "$initrd_dir/init"
(cd "$initrd_dir" && find . | "$busybox" cpio -o -H newc 2>/dev/null | gzip -1 >"$out/initrd.gz")

{
  echo 'set -u'
  for var in ASAN_OPTIONS LSAN_OPTIONS UBSAN_OPTIONS TSAN_OPTIONS GTEST_FILTER GTEST_COLOR; do
    [[ -n ${!var:-} ]] && printf 'export %s=%q\n' "$var" "${!var}"
  done
  echo 'export HOME=/tmp PATH=/usr/sbin:/usr/bin:/sbin:/bin'
  echo 'if ! { ip link add dev vcan0 type vcan && ip link set vcan0 mtu 72 && ip link set vcan0 up; }; then'
  echo "  echo 'guest: could not create vcan0'; echo 98 >$(printf %q "$out/rc"); exit 0"
  echo 'fi'
  printf 'cd %q\n' "$PWD"
  printf '%q ' "$test_binary" "$@"
  echo
  printf 'echo $? >%q\n' "$out/rc"
} >"$out/job.sh"

log "booting $kernel_package under qemu (TCG) to run $(basename "$test_binary")"
start=$SECONDS
timeout --kill-after=10 "$GUEST_TIMEOUT_S" qemu-system-x86_64 \
  -accel tcg -cpu max -m 1024 -smp ${HAPTIC_GUEST_CPUS:-1} \
  -kernel "$kdir/vmlinux" -initrd "$out/initrd.gz" \
  -append "console=ttyS0 quiet loglevel=3 panic=-1 haptic.out=$out haptic.results=$results" \
  -display none -nodefaults -no-user-config -no-reboot -serial stdio -monitor none \
  -virtfs "local,path=/,mount_tag=hostroot,security_model=none,readonly=on,multidevs=remap" \
  -virtfs "local,path=/tmp,mount_tag=hosttmp,security_model=none,multidevs=remap" \
  -virtfs "local,path=$out,mount_tag=out,security_model=none" \
  -virtfs "local,path=$results,mount_tag=results,security_model=none" </dev/null
qemu_status=$?
log "guest finished in $((SECONDS - start)) s (qemu exit $qemu_status)"
if [[ ! -f $out/rc ]]; then
  echo "socketcan_guest: the guest did not report a result (timeout ${GUEST_TIMEOUT_S}s or boot failure)" >&2
  exit 1
fi
rc=$(cat "$out/rc")
if [[ $rc == 98 ]]; then
  echo "socketcan_guest: vcan0 could not be created in the guest" >&2
  exit 1
fi
exit "$rc"
