#!/usr/bin/env bash
# Installs livod's Debian package on a fresh Debian 12 and checks the service under a real systemd
# (docs/deploy.md, "Checking the package on a fresh Debian 12"): debootstraps a minimal bookworm
# root (cached in WORK_DIR/base), installs the .deb into a copy with `apt-get install
# --no-install-recommends ./livod_*.deb` (so only the package's declared dependencies come in),
# enables livod.service and boots the root in qemu. A check unit in the guest then looks at the
# running service, writes one line per check to the serial console and powers the guest off; this
# script prints those lines and exits 1 if any check failed (or the guest never reported).
#
# Checked in the guest: boot reaches multi-user; livod is active (READY=1 came) with a STATUS=
# line naming the configured sensor, which is absent; the `livod` system user; /var/lib/livod and
# /var/log/livod owned by it, mode 0750; the process runs as livod with no capability,
# no_new_privs, a seccomp filter and RLIMIT_RTPRIO 50, and has SCHED_FIFO threads;
# net.core.rmem_max from the sysctl.d drop-in and the capture socket's 8 MiB receive buffer (ss);
# `systemd-analyze verify` prints nothing;
# `systemd-analyze security livod` (the loaded unit) rates exposure <= MAX_EXPOSURE; no restart and
# no withheld watchdog ping over LIVOD_VM_UP_S seconds without sensors; SIGUSR1 to the main
# process is answered in the journal and the daemon runs on (no sensor, no scan: the answer is the
# refusal to save an empty map); `systemctl stop` is clean (SIGTERM logged, exit 0, result
# success); with the outputs pointed at /var/lib/livod and /var/log/livod, a start and stop write
# them there (livod:livod, 0640).
#
# Run by hand as root (minutes: debootstrap once, then qemu's software emulation; needs the Debian
# mirror): too slow and privileged for every CI run.
#   scripts/check-deb-in-vm.sh build/release/livod_*_amd64.deb [WORK_DIR]
# Environment: DEBIAN_MIRROR (default http://deb.debian.org/debian), LIVOD_VM_ACCEL (tcg, the
# default, or kvm where nested virtualisation works), LIVOD_VM_TIMEOUT_S (whole guest run,
# default 1800), LIVOD_VM_UP_S (how long the service must stay up without a restart, default 60),
# MAX_EXPOSURE (default 4.0).
#
# The guest's network is qemu's user network with restrict=on: it has an interface, an address and
# a default route (as on a robot; the unit waits for network-online.target), but nothing it sends
# leaves qemu, so the example configuration's LCM multicast stays inside.
set -euo pipefail

deb=$(realpath "${1:?usage: check-deb-in-vm.sh LIVOD_DEB [WORK_DIR]}")
work=${2:-/var/tmp/livod-debvm}
mirror=${DEBIAN_MIRROR:-http://deb.debian.org/debian}
timeout_s=${LIVOD_VM_TIMEOUT_S:-1800}
up_s=${LIVOD_VM_UP_S:-60}
max_exposure=${MAX_EXPOSURE:-4.0}
here=$(dirname "$(realpath "$0")")

fail() {
  echo "FAIL: $*" >&2
  exit 1
}
((EUID == 0)) || fail "run as root (debootstrap, chroot)"
for tool in debootstrap qemu-system-x86_64 mke2fs chroot dpkg-deb; do
  command -v "$tool" >/dev/null ||
    fail "$tool not found (apt-get install debootstrap qemu-system-x86 e2fsprogs)"
done
[[ -f $deb ]] || fail "$deb: no such package"
dpkg-deb --field "$deb" Package | grep -qx livod || fail "$deb is not the livod package"
mkdir -p "$work"

# The base root: what a minimal Debian 12 install has (systemd as init, udev, a kernel), nothing of
# livod's. Made once; every run starts from a fresh copy of it.
base=$work/base
if [[ ! -e $work/base.done ]]; then
  rm -rf "$base"
  echo "debootstrap bookworm from $mirror into $base"
  debootstrap --variant=minbase \
    --include=systemd,systemd-sysv,udev,kmod,initramfs-tools,zstd,linux-image-amd64 \
    bookworm "$base" "$mirror" >"$work/debootstrap.log" 2>&1 ||
    fail "debootstrap failed: $work/debootstrap.log"
  # A fresh install gets its security and stable updates too; the package was built against them.
  security=${mirror%/debian}/debian-security
  cat >"$base/etc/apt/sources.list" <<EOF
deb $mirror bookworm main
deb $mirror bookworm-updates main
deb $security bookworm-security main
EOF
  rm -f "$base"/boot/*.dpkg-bak "$base"/boot/*.new
  touch "$work/base.done"
fi

root=$work/root
rm -rf "$root"
cp -a "$base" "$root"

# The package, with apt resolving its Depends: only (no Recommends), in a chroot without /proc:
# the postinst must not need a running systemd (image builders install packages this way too).
cp /etc/resolv.conf "$root/etc/resolv.conf"
cp "$deb" "$root/tmp/livod.deb"
chroot "$root" dpkg-query -W -f '${Package}\n' | sort >"$work/packages-before.txt"
{
  chroot "$root" apt-get update &&
    DEBIAN_FRONTEND=noninteractive chroot "$root" apt-get install -y --no-install-recommends \
      /tmp/livod.deb
} >"$work/apt-install.log" 2>&1 || fail "apt-get install ./livod.deb: $work/apt-install.log"
chroot "$root" dpkg-query -W -f '${Package}\n' | sort >"$work/packages-after.txt"
rm "$root/tmp/livod.deb"
# ss(8) for the guest's socket check: a test tool, installed after the package list was taken.
DEBIAN_FRONTEND=noninteractive chroot "$root" apt-get install -y --no-install-recommends iproute2 \
  >>"$work/apt-install.log" 2>&1 || fail "apt-get install iproute2: $work/apt-install.log"
chroot "$root" apt-get clean
added=$(comm -13 "$work/packages-before.txt" "$work/packages-after.txt" | wc -l)
echo "apt-get install ./$(basename "$deb"): $added packages added (list: $work/packages-after.txt)"
grep -q '^livod:' "$root/etc/passwd" || fail "the package's postinst did not create user livod"

# Enabled the way the administrator does it; the guest's network as on a robot (networkd, a
# static address, so network-online.target means something).
chroot "$root" systemctl enable livod.service systemd-networkd.service >/dev/null 2>&1 ||
  fail "systemctl enable livod.service systemd-networkd.service"
cat >"$root/etc/systemd/network/10-vm.network" <<'EOF'
[Match]
Name=en* eth*
[Network]
Address=10.0.2.15/24
Gateway=10.0.2.2
EOF
echo livod-vm >"$root/etc/hostname"
echo '/dev/vda / ext4 rw 0 1' >"$root/etc/fstab"
: >"$root/etc/machine-id" # first boot: systemd makes one, as on a freshly imaged robot

# The check, run once the boot is done; it reports on the console and powers the guest off.
install -m 0755 "$here/check-deb-in-vm-guest.sh" "$root/usr/local/sbin/livod-vmcheck"
cat >"$root/etc/systemd/system/livod-vmcheck.service" <<EOF
[Unit]
Description=livod package check (scripts/check-deb-in-vm.sh)
After=livod.service
[Service]
Type=simple
Environment=UP_S=$up_s MAX_EXPOSURE=$max_exposure
ExecStart=/usr/local/sbin/livod-vmcheck
StandardOutput=tty
StandardError=tty
TTYPath=/dev/ttyS0
ExecStopPost=/usr/bin/systemctl --no-block poweroff
[Install]
WantedBy=multi-user.target
EOF
# No login prompt on the serial console: agetty's hangup of ttyS0 would cut the check's output.
chroot "$root" systemctl enable livod-vmcheck.service >/dev/null 2>&1 &&
  chroot "$root" systemctl mask serial-getty@ttyS0.service >/dev/null 2>&1 ||
  fail "systemctl enable livod-vmcheck.service"

kernel=$(find "$root/boot" -name 'vmlinuz-*' | sort | tail -n 1)
initrd=$(find "$root/boot" -name 'initrd.img-*' | sort | tail -n 1)
[[ -n $kernel && -n $initrd ]] || fail "no kernel or initrd in the guest's /boot"
cp "$kernel" "$work/vmlinuz"
cp "$initrd" "$work/initrd.img"
image=$work/root.img
rm -f "$image"
mke2fs -q -t ext4 -L livod-vm -d "$root" "$image" 4G >/dev/null || fail "mke2fs -d $root"

# Software emulation by default: /dev/kvm being there does not mean it works (in a VM without
# nested virtualisation the guest hangs before its first kernel message).
accel=${LIVOD_VM_ACCEL:-tcg}
cpu=max
[[ $accel == kvm ]] && cpu=host
# no_timer_check: on a busy host, emulated time runs so unevenly that the kernel's IO-APIC timer
# check fails and it panics at boot.
log=$work/serial.log
rm -f "$log"
echo "booting the guest (qemu, accel=$accel; serial console: $log)"
start=$(date +%s)
set +e
timeout "$timeout_s" qemu-system-x86_64 -accel "$accel" -cpu "$cpu" -smp 2 -m 2048 \
  -display none -monitor none -serial "file:$log" -no-reboot \
  -kernel "$work/vmlinuz" -initrd "$work/initrd.img" \
  -append "root=/dev/vda rw console=ttyS0 panic=-1 loglevel=4 no_timer_check" \
  -drive "file=$image,format=raw,if=virtio" \
  -netdev user,id=n0,restrict=on -device virtio-net-pci,netdev=n0
qemu_rc=$?
set -e
echo "guest ran $(($(date +%s) - start)) s (qemu exit $qemu_rc)"
((qemu_rc != 124)) || echo "FAIL: the guest did not power off within $timeout_s s" >&2

# The check's lines are "livod-vm: ..." on the console (the kernel and systemd write there too).
tr -d '\r' <"$log" | sed -n 's/^.*\(livod-vm: \)/\1/p' | tee "$work/report.txt"
if ((qemu_rc == 0)) && grep -qx 'livod-vm: RESULT PASS' "$work/report.txt"; then
  echo "all checks passed ($work/report.txt)"
  exit 0
fi
echo "FAIL: see $work/report.txt and $log" >&2
exit 1
