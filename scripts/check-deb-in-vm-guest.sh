#!/bin/bash
# The guest half of scripts/check-deb-in-vm.sh: run once at boot by livod-vmcheck.service in the
# Debian 12 guest where the livod package is installed and livod.service enabled. Prints one line
# per check ("livod-vm: PASS ..." / "livod-vm: FAIL ...", then "livod-vm: RESULT PASS|FAIL") on
# the serial console; the unit powers the guest off when this exits.
# Environment (from the unit): UP_S, seconds the service must stay up without a restart;
# MAX_EXPOSURE, the highest acceptable `systemd-analyze security` exposure.
set -u  # no pipefail: grep -m1 may close a pipe early

up_s=${UP_S:-60}
max_exposure=${MAX_EXPOSURE:-4.0}
failed=0

say() { echo "livod-vm: $*"; }
pass() { say "PASS $*"; }
check_fail() {
  say "FAIL $*"
  failed=$((failed + 1))
}
prop() { systemctl show livod.service -p "$1" --value; }
# Every line of the livod unit's journal in this boot, message only.
journal() { journalctl -b -u livod.service -o cat --no-pager; }

# Not `is-system-running --wait`: that needs D-Bus, which a minimal Debian 12 does not have.
for _ in $(seq 600); do
  state=$(systemctl is-system-running)
  [[ $state == initializing || $state == starting ]] || break
  sleep 1
done
if [[ $state == running ]]; then
  pass "boot: system $state; $(systemd-analyze time | head -n 1)"
else
  check_fail "boot: system $state (failed units: $(systemctl --failed --plain --no-legend | tr '\n' ' '))"
fi

# Type=notify: active means READY=1 came (systemd logs "Started" only then).
for _ in $(seq 60); do
  [[ $(prop ActiveState) == active ]] && break
  sleep 1
done
if [[ $(prop ActiveState) == active && $(prop SubState) == running ]]; then
  pass "livod active (READY=1): $(systemctl show livod.service -p MainPID,NRestarts,WatchdogUSec | tr '\n' ' ')"
else
  check_fail "livod not active: $(systemctl show livod.service -p ActiveState,SubState,Result,NRestarts | tr '\n' ' ')"
fi
pid=$(prop MainPID)
started=$(prop ExecMainStartTimestampMonotonic)

if journal | grep -q '^Started livod'; then
  pass "journal: $(journal | grep -m1 '^Started livod')"
else
  check_fail "journal has no 'Started livod' (READY=1 never came?)"
fi
# The configured sensor (the example's Avia) is absent: reported WAITING or STALE, not a failure.
sleep 3
status=$(prop StatusText)
if [[ $status =~ avia\ (WAITING|STALE) ]] && [[ $status == *filter* ]]; then
  pass "STATUS=$status"
else
  check_fail "STATUS='$status' does not report the absent sensor avia"
fi

if entry=$(getent passwd livod); then
  uid=$(cut -d: -f3 <<<"$entry")
  if ((uid < 1000)); then pass "system user: $entry"; else check_fail "livod uid $uid >= 1000"; fi
else
  check_fail "no user livod"
fi
# What the package installs besides the unit: the configuration livod accepts, the guide the
# unit's Documentation= names, the LCM types for lcm-spy and Python.
if out=$(livod check-config /etc/livod/livod.yaml 2>&1); then
  pass "livod check-config /etc/livod/livod.yaml: $(head -n 1 <<<"$out")"
else
  check_fail "livod check-config /etc/livod/livod.yaml: $(tr '\n' ' ' <<<"$out")"
fi
for f in /usr/share/doc/livod/deploy.md /usr/share/java/livod_lcmtypes.jar \
  /usr/share/livod/lcmtypes/livod/pose_t.lcm /usr/share/livod/python/livod/pose_t.py \
  /usr/lib/sysusers.d/livod.conf /usr/lib/sysctl.d/60-livod.conf; do
  if [[ -s $f ]]; then pass "installed: $f"; else check_fail "not installed: $f"; fi
done

# expect_owner_mode PATH "USER:GROUP MODE" WHAT
expect_owner_mode() {
  local got
  got=$(stat -c '%U:%G %a' "$1" 2>/dev/null)
  if [[ $got == "$2" ]]; then
    pass "$3$1 $got"
  else
    check_fail "$3$1: '${got:-missing}', expected $2"
  fi
}

for dir in /var/lib/livod /var/log/livod; do
  expect_owner_mode "$dir" "livod:livod 750" ""
done

# The process as the unit made it: user livod, no capability, no_new_privs, seccomp filter.
if [[ -r /proc/$pid/status ]]; then
  st=/proc/$pid/status
  uid=$(awk '/^Uid:/ { print $2 }' "$st")
  capeff=$(awk '/^CapEff:/ { print $2 }' "$st")
  capbnd=$(awk '/^CapBnd:/ { print $2 }' "$st")
  nnp=$(awk '/^NoNewPrivs:/ { print $2 }' "$st")
  seccomp=$(awk '/^Seccomp:/ { print $2 }' "$st")
  rtprio=$(awk '/^Max realtime priority/ { print $4 }' "/proc/$pid/limits")
  threads=$(ls "/proc/$pid/task" | wc -l)
  summary="uid=$uid CapEff=$capeff CapBnd=$capbnd NoNewPrivs=$nnp Seccomp=$seccomp RLIMIT_RTPRIO=$rtprio threads=$threads"
  if [[ $uid == "$(id -u livod)" && $capeff == 0000000000000000 && $capbnd == 0000000000000000 &&
    $nnp == 1 && $seccomp == 2 && $rtprio == 50 ]]; then
    pass "process $pid: $summary"
  else
    check_fail "process $pid: $summary"
  fi
  # SCHED_FIFO threads (realtime.*_priority 50/40): the policy column of /proc/PID/task/*/stat.
  fifo=0
  for t in /proc/"$pid"/task/*; do
    policy=$(sed 's/^.*) //' "$t/stat" | awk '{ print $39 }')
    [[ $policy == 1 ]] && fifo=$((fifo + 1))
  done
  if ((fifo > 0)); then
    pass "$fifo thread(s) SCHED_FIFO under LimitRTPRIO=50 with no capability"
  else
    check_fail "no SCHED_FIFO thread: $(journal | grep -i -m3 'sched\|priority' | tr '\n' ' ')"
  fi
else
  check_fail "no /proc/$pid/status"
fi

rmem=$(cat /proc/sys/net/core/rmem_max)
if ((rmem >= 16777216)); then
  pass "net.core.rmem_max = $rmem (60-livod.conf applied at boot)"
else
  check_fail "net.core.rmem_max = $rmem"
fi
# The Avia's capture socket (port 56001) got its 8 MiB (socket_buffer_bytes; the kernel reports
# twice the request) without CAP_NET_ADMIN: ss's skmem rb is the socket's receive buffer limit.
sock=$(ss -uanmp 'sport = :56001' | tr '\n' ' ')
rb=$(grep -o 'skmem:(r[0-9]*,rb[0-9]*' <<<"$sock" | sed 's/.*,rb//')
if [[ $sock == *livod* ]] && ((${rb:-0} >= 16777216)); then
  pass "capture socket :56001 receive buffer rb$rb (8 MiB asked, doubled by the kernel)"
else
  check_fail "capture socket :56001: rb='${rb:-none}' ($sock)"
fi

verify=$(systemd-analyze verify livod.service 2>&1)
if [[ -z $verify ]]; then
  pass "systemd-analyze verify livod.service: no output"
else
  check_fail "systemd-analyze verify livod.service: $(tr '\n' ' ' <<<"$verify")"
fi
security=$(systemd-analyze security --no-pager livod.service 2>&1)
exposure=$(sed -n 's/.*Overall exposure level for livod\.service: \([0-9.]*\) \(.*\)$/\1 \2/p' <<<"$security")
if [[ -n $exposure ]] && awk -v e="${exposure%% *}" -v m="$max_exposure" 'BEGIN { exit !(e <= m) }'; then
  pass "systemd-analyze security livod.service (running unit): exposure $exposure (limit $max_exposure)"
else
  check_fail "systemd-analyze security: '${exposure:-no figure}' (limit $max_exposure)"
fi
grep '✗' <<<"$security" | sed 's/^/livod-vm:   security /'

# No sensor, WatchdogSec=10s: the idle threads still beat, so no watchdog kill over UP_S seconds.
now=$(awk '{ printf "%d", $1 * 1000000 }' /proc/uptime)
wait_s=$((up_s - (now - started) / 1000000))
((wait_s > 0)) && sleep "$wait_s"
up=$((($(awk '{ printf "%d", $1 * 1000000 }' /proc/uptime) - started) / 1000000))
if [[ $(prop MainPID) == "$pid" && $(prop NRestarts) == 0 && $(prop ActiveState) == active ]] &&
  ! journal | grep -qi 'watchdog timeout'; then
  pass "up ${up} s without sensors: same MainPID $pid, NRestarts=0, no watchdog timeout; STATUS=$(prop StatusText)"
else
  check_fail "after ${up} s: $(systemctl show livod.service -p MainPID,NRestarts,ActiveState | tr '\n' ' '); $(journal | grep -i -m2 watchdog | tr '\n' ' ')"
fi
if journal | grep -q 'not pinging'; then
  check_fail "a ping was withheld: $(journal | grep -m1 'not pinging')"
else
  pass "no withheld watchdog ping in the journal"
fi

# SIGUSR1 to the main process: a map save request. No scan has been registered (no sensor), so
# the answer is the logged refusal; the daemon keeps running.
systemctl kill --signal=SIGUSR1 --kill-who=main livod.service
sleep 3
if answer=$(journal | grep -m1 'map save\|map saved'); then
  if [[ $(prop MainPID) == "$pid" && $(prop ActiveState) == active ]]; then
    pass "SIGUSR1 answered, still running: $answer"
  else
    check_fail "SIGUSR1: $answer, then $(systemctl show livod.service -p MainPID,ActiveState | tr '\n' ' ')"
  fi
else
  check_fail "SIGUSR1: no map save line in the journal"
fi

# A clean stop: STOPPING=1 (deactivating), exit 0, result success.
t0=$(date +%s%N)
systemctl stop livod.service
stop_ms=$((($(date +%s%N) - t0) / 1000000))
result="$(systemctl show livod.service -p Result,ExecMainCode,ExecMainStatus | tr '\n' ' ')"
if [[ $(prop Result) == success && $(prop ExecMainStatus) == 0 && $(prop ExecMainCode) == 1 ]]; then
  pass "systemctl stop in $stop_ms ms: $result"
else
  check_fail "systemctl stop: $result"
fi
if journal | grep -q 'SIGTERM: stopping'; then
  pass "journal: $(journal | grep -m1 'SIGTERM: stopping')"
else
  check_fail "no 'SIGTERM: stopping' in the journal"
fi

# The service writes only where the unit lets it (ProtectSystem=strict): the administrator points
# the outputs at StateDirectory and LogsDirectory (docs/deploy.md "Where things live"); at stop
# they are written there, owned by livod, not readable by others (UMask=0027).
cp /etc/livod/livod.yaml /root/livod.yaml.example
sed -i -e 's|^  trajectory: null$|  trajectory: /var/lib/livod/trajectory.txt|' \
  -e 's|^  map_pcd: null$|  map_pcd: /var/lib/livod/map.pcd\n  timing_report: /var/log/livod/timing.txt|' \
  /etc/livod/livod.yaml
if systemctl start livod.service && sleep 5 && systemctl stop livod.service &&
  [[ $(prop Result) == success && $(prop ExecMainStatus) == 0 ]]; then
  for f in /var/lib/livod/trajectory.txt /var/lib/livod/map.pcd /var/log/livod/timing.txt; do
    expect_owner_mode "$f" "livod:livod 640" "output written at stop: "
  done
else
  check_fail "restart with outputs: $(systemctl show livod.service -p Result,ExecMainStatus | tr '\n' ' ')"
fi
cp /root/livod.yaml.example /etc/livod/livod.yaml

say "--- journalctl -u livod (this boot) ---"
journalctl -b -u livod.service -o short-monotonic --no-pager | sed 's/^/livod-vm: | /'
if ((failed == 0)); then say "RESULT PASS"; else say "RESULT FAIL ($failed failed)"; fi
