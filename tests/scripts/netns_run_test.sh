#!/usr/bin/env bash
# Checks scripts/netns-run.sh, the wrapper behind livod_add_netns_test: the command runs in a
# namespace with only a multicast-routed loopback, its exit status comes back, and a host where no
# namespace can be created fails with a message (exit 2) unless LIVOD_NETNS_ALLOW_SKIP=1 (exit 77).
set -euo pipefail
run=$(dirname "$0")/../../scripts/netns-run.sh
fail() {
  echo "FAIL: $*" >&2
  exit 1
}

inside=$(bash "$run" bash -c 'ip -o link show | awk -F": " "{print \$2}"; ip route show 224.0.0.0/4;
  ip -o link show lo | grep -q MULTICAST && echo multicast; echo "netns=$LIVOD_NETNS"')
grep -qx lo <<<"$inside" || fail "no lo: $inside"
grep -q '^224.0.0.0/4 dev lo' <<<"$inside" || fail "no multicast route: $inside"
grep -qx multicast <<<"$inside" || fail "lo without multicast: $inside"
grep -qx netns=1 <<<"$inside" || fail "LIVOD_NETNS not set: $inside"
# The host's interfaces are not visible inside (a fresh namespace each time).
[[ $(bash "$run" ip -o link show | wc -l) == 1 ]] || fail "interfaces other than lo inside"

set +e
bash "$run" bash -c 'exit 7'
status=$?
set -e
[[ $status == 7 ]] || fail "exit status $status, expected 7"

# No namespace possible: an unshare that always fails.
fake=$(mktemp -d)
trap 'rm -rf "$fake"' EXIT
printf '#!/bin/sh\nexit 1\n' >"$fake/unshare"
chmod +x "$fake/unshare"
set +e
message=$(PATH="$fake:$PATH" bash "$run" true 2>&1)
status=$?
skipped=$(PATH="$fake:$PATH" LIVOD_NETNS_ALLOW_SKIP=1 bash "$run" true 2>&1)
skip_status=$?
set -e
[[ $status == 2 ]] || fail "exit status $status without a namespace, expected 2"
grep -q "cannot create a network namespace" <<<"$message" || fail "no message: $message"
[[ $skip_status == 77 ]] || fail "exit status $skip_status with LIVOD_NETNS_ALLOW_SKIP=1"
grep -q "skipped" <<<"$skipped" || fail "no skip message: $skipped"
echo "netns-run: ok"
