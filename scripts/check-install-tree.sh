#!/usr/bin/env bash
# Installs the build into a scratch DESTDIR (`cmake --install`) and checks what a robot gets
# (ctest install_tree_test): the binary, the unit whose ExecStart= names that binary and the
# installed configuration, the sysusers.d/sysctl.d drop-ins, the docs, and that the installed
# livod accepts the installed configuration (`livod check-config`).
#
# Usage: check-install-tree.sh BUILD_DIR PREFIX SYSCONFDIR
set -euo pipefail

build=$1
prefix=$2
sysconfdir=$3

root=$(mktemp -d)
trap 'rm -rf "$root"' EXIT
DESTDIR=$root cmake --install "$build" >/dev/null

fail() {
  echo "FAIL: $*" >&2
  exit 1
}
for f in "$prefix/bin/livod" "$prefix/lib/systemd/system/livod.service" \
  "$prefix/lib/sysusers.d/livod.conf" "$prefix/lib/sysctl.d/60-livod.conf" \
  "$sysconfdir/livod/livod.yaml" "$prefix/share/doc/livod/daemon.md"; do
  [[ -e $root$f ]] || fail "$f is not installed"
done

exec_start=$(sed -n 's/^ExecStart=//p' "$root$prefix/lib/systemd/system/livod.service")
read -r binary verb flag config <<<"$exec_start"
[[ $binary == "$prefix/bin/livod" ]] || fail "ExecStart= runs $binary, installed is $prefix/bin/livod"
[[ $verb == run && $flag == --config ]] || fail "ExecStart=$exec_start"
[[ $config == "$sysconfdir/livod/livod.yaml" ]] || fail "ExecStart= reads $config"

"$root$binary" check-config "$root$config" >/dev/null || fail "livod check-config $config"
echo "installed: $binary, its unit and drop-ins; $config passes check-config"
