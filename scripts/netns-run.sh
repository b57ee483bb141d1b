#!/usr/bin/env bash
# Runs a command inside a fresh private network namespace whose only interface is a loopback with
# multicast routed onto it, so that LCM udpm traffic (and any UDP a test sends) cannot leave the
# machine, and concurrent tests cannot hear each other. The namespace disappears with the last
# process in it. Used by the CMake helpers livod_add_netns_test / livod_add_netns_gtest.
#
#   scripts/netns-run.sh COMMAND [ARGS...]
#
# Inside: lo up, multicast on, 224.0.0.0/4 routed to lo, LIVOD_NETNS=1 in the environment. The
# command's exit status is returned.
# Needs root (CAP_SYS_ADMIN) or unprivileged user namespaces (then `unshare -r -n`, the command
# runs as a mapped root). When neither works it exits 2 with a message, or 77 (ctest's skip code
# for these tests) when LIVOD_NETNS_ALLOW_SKIP=1 explicitly allows skipping.
set -euo pipefail

if [[ ${1:-} == --inside ]]; then
  shift
  ip link set lo up
  ip link set lo multicast on
  ip route add 224.0.0.0/4 dev lo
  # Refuse to run if the namespace is not the empty one we asked for.
  links=$(ip -o link show | awk -F': ' '{print $2}' | tr '\n' ' ')
  if [[ $links != "lo " ]]; then
    echo "netns-run: the namespace has interfaces other than lo ($links); refusing to run" >&2
    exit 2
  fi
  # Tests that send multicast check this before they do (they refuse to run outside).
  export LIVOD_NETNS=1
  exec "$@"
fi

if (($# == 0)); then
  echo "usage: $0 COMMAND [ARGS...]" >&2
  exit 64
fi
for tool in unshare ip; do
  if ! command -v "$tool" >/dev/null; then
    echo "netns-run: '$tool' not found (util-linux, iproute2)" >&2
    exit 2
  fi
done

self=$(readlink -f "$0")
if unshare -n true 2>/dev/null; then
  exec unshare -n -- bash "$self" --inside "$@"
elif unshare -r -n true 2>/dev/null; then
  exec unshare -r -n -- bash "$self" --inside "$@"
fi

message="netns-run: cannot create a network namespace (uid $(id -u)): 'unshare -n' needs root or
CAP_SYS_ADMIN, 'unshare -r -n' needs unprivileged user namespaces. These tests run LCM multicast
on a private loopback only; run them as root (CI does)"
if [[ ${LIVOD_NETNS_ALLOW_SKIP:-0} == 1 ]]; then
  echo "$message; skipped (LIVOD_NETNS_ALLOW_SKIP=1)" >&2
  exit 77
fi
echo "$message, or set LIVOD_NETNS_ALLOW_SKIP=1 to skip them." >&2
exit 2
