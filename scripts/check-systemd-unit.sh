#!/usr/bin/env bash
# Checks systemd/livod.service as systemd reads it, without systemd running (ctest
# systemd_unit_test): `systemd-analyze verify` prints nothing (it exits 0 even on errors, so its
# output is what counts), `systemd-analyze security --offline` rates the unit's exposure at most
# MAX_EXPOSURE, and the sysusers.d file creates the `livod` system user (in a scratch root).
# Exits 77 (skipped) when systemd-analyze is not installed.
#
# Usage: check-systemd-unit.sh SYSTEMD_DIR LIVOD_BINARY [MAX_EXPOSURE]
set -euo pipefail

src=$1
binary=$2
max_exposure=${3:-4.0}

if ! command -v systemd-analyze >/dev/null; then
  echo "systemd-analyze is not installed (Debian package systemd): skipped"
  exit 77
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# verify checks that ExecStart's program exists and is executable: point it at the built binary.
unit=$work/livod.service
sed "s#^ExecStart=/usr/bin/livod #ExecStart=${binary} #" "$src/livod.service" >"$unit"
if ! grep -q "^ExecStart=${binary} run --config /etc/livod/livod.yaml$" "$unit"; then
  echo "FAIL: ExecStart= is not '/usr/bin/livod run --config /etc/livod/livod.yaml'" >&2
  exit 1
fi

verify=$(systemd-analyze verify "$unit" 2>&1 || true)
if [[ -n $verify ]]; then
  echo "FAIL: systemd-analyze verify livod.service:" >&2
  echo "$verify" >&2
  exit 1
fi
echo "systemd-analyze verify: no finding"

if systemd-analyze security --help 2>&1 | grep -q -- '--offline'; then
  security=$(systemd-analyze security --offline=true --no-pager "$unit" 2>&1 || true)
  exposure=$(sed -n 's/.*Overall exposure level for livod\.service: \([0-9.]*\).*/\1/p' <<<"$security")
  if [[ -z $exposure ]]; then
    echo "FAIL: no exposure level in systemd-analyze security's output:" >&2
    echo "$security" >&2
    exit 1
  fi
  echo "systemd-analyze security --offline=true: exposure $exposure (limit $max_exposure)"
  if ! awk -v e="$exposure" -v m="$max_exposure" 'BEGIN { exit !(e <= m) }'; then
    grep '✗' <<<"$security" >&2 || true
    echo "FAIL: exposure $exposure > $max_exposure" >&2
    exit 1
  fi
else
  echo "systemd-analyze security has no --offline (systemd < 252): exposure not rated"
fi

if command -v systemd-sysusers >/dev/null; then
  root=$work/root
  mkdir -p "$root/etc"
  systemd-sysusers --root="$root" "$src/livod.sysusers.conf"
  if ! grep -q '^livod:x:[0-9]*:[0-9]*:livod odometry daemon:/var/lib/livod:' "$root/etc/passwd"; then
    echo "FAIL: livod.sysusers.conf did not create the livod system user:" >&2
    cat "$root/etc/passwd" >&2
    exit 1
  fi
  uid=$(awk -F: '$1 == "livod" { print $3 }' "$root/etc/passwd")
  if ((uid >= 1000)); then
    echo "FAIL: livod's uid $uid is not a system uid" >&2
    exit 1
  fi
  echo "systemd-sysusers: system user livod (uid $uid)"
fi
