#!/usr/bin/env bash
# Plays an LCM log with the real lcm-logplayer and records it with the real lcm-logger, both inside
# a private network namespace whose only interface is a multicast-enabled loopback, so that no
# packet can leave the machine. Used by io/tests/lcm_log_test.cpp.
#
#   lcm_interop.sh INPUT_LOG OUTPUT_LOG
#
# Needs root (CAP_SYS_ADMIN) for `ip netns`; exits 2 with a message when that is not possible.
set -euo pipefail

if (($# != 2)); then
  echo "usage: $0 INPUT_LOG OUTPUT_LOG" >&2
  exit 64
fi
input=$1
output=$2
# Port and group are LCM's defaults; ttl=0 keeps the datagrams on the host even if the namespace
# had other interfaces.
port=7667
url="udpm://239.255.76.67:${port}?ttl=0"
ns="livod-lcm-test-$$"
logger_pid=""

for tool in ip lcm-logger lcm-logplayer ss timeout; do
  if ! command -v "$tool" >/dev/null; then
    echo "lcm_interop: '$tool' not found (install iproute2 and liblcm-bin)" >&2
    exit 2
  fi
done

cleanup() {
  if [[ -n $logger_pid ]] && kill -0 "$logger_pid" 2>/dev/null; then
    kill -KILL "$logger_pid" 2>/dev/null || true
    wait "$logger_pid" 2>/dev/null || true
  fi
  ip netns del "$ns" 2>/dev/null || true
}
trap cleanup EXIT

if ! ip netns add "$ns" 2>/dev/null; then
  echo "lcm_interop: cannot create network namespace '$ns' (uid $(id -u)); this test needs root" \
    "or CAP_SYS_ADMIN so that LCM multicast stays on a private loopback" >&2
  exit 2
fi
ip netns exec "$ns" ip link set lo up
ip netns exec "$ns" ip link set lo multicast on
ip netns exec "$ns" ip route add 224.0.0.0/4 dev lo

rm -f "$output"
# `lcm-logger -l URL` is broken in LCM 1.3.1; the long form works. `ip netns exec` execs the
# logger, so $! is the logger's own pid.
ip netns exec "$ns" lcm-logger --quiet --force --flush-interval=50 --lcm-url="$url" "$output" &
logger_pid=$!

# Ready once the logger has bound its multicast socket (LCM sets up the receive side when it
# subscribes), polled for at most 5 s.
ready=0
for _ in $(seq 100); do
  if ip netns exec "$ns" ss -Hlun "sport = :${port}" | grep -q .; then
    ready=1
    break
  fi
  if ! kill -0 "$logger_pid" 2>/dev/null; then break; fi
  sleep 0.05
done
if ((ready == 0)); then
  echo "lcm_interop: lcm-logger did not bind udp port ${port} within 5 s" >&2
  exit 1
fi
# Binding comes just before the multicast join; leave it a moment.
sleep 0.2

timeout 10 ip netns exec "$ns" lcm-logplayer --lcm-url="$url" "$input" >/dev/null

# Let the logger receive the last datagrams and flush (flush interval 50 ms), then stop it the way
# an operator would.
sleep 0.5
kill -INT "$logger_pid"
for _ in $(seq 60); do
  kill -0 "$logger_pid" 2>/dev/null || break
  sleep 0.05
done
if kill -0 "$logger_pid" 2>/dev/null; then
  echo "lcm_interop: lcm-logger did not exit on SIGINT within 3 s" >&2
  exit 1
fi
wait "$logger_pid" || true
logger_pid=""
if [[ ! -f $output ]]; then
  echo "lcm_interop: lcm-logger wrote no file" >&2
  exit 1
fi
