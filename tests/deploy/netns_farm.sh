# netns_farm.sh: the farm over impaired links. The coordinator and each worker live in network
# namespaces of their own, joined by veth pairs to a bridge in the coordinator's; each worker's
# link has 50 +- 10 ms delay each way (net_delay on a netfilter queue, since this kernel has no
# sch_netem), 1% loss each way (iptables statistic) and 20 Mbit/s each way (tbf). A job ends
# with exact counts and sums equal to a single-process render; then one worker's link stalls
# (all packets dropped) for longer than the heartbeat timeout: it is handled like a dead worker,
# its range re-assigned, and what it sends after the stall is not counted twice.
# Nothing here touches the host's own network: every address is inside these namespaces.
# The same job runs first over clean links, for the throughput ratio.
#   NETNS_STALL=60 NETNS_SPP=600 bash netns_farm.sh  # tests/bench/bench_netns.sh: a 60 s stall
set -euo pipefail
B=${PCBPT_BINARY_DIR:?}
S=${PCBPT_SOURCE_DIR:?}
export PATH=$PATH:/usr/sbin:/sbin
[ "$(id -u)" = 0 ] || { echo "SKIP: network namespaces need root"; exit 77; }
for p in ip tc iptables; do command -v $p >/dev/null || { echo "SKIP: $p is not installed (deploy/install-deps.sh)"; exit 77; }; done
[ -x "$B/tests/net_delay" ] || { echo "SKIP: net_delay was not built (libnetfilter-queue-dev)"; exit 77; }
NW=2
HB=4
STALL=${NETNS_STALL:-$((3 * HB))}
SPP=${NETNS_SPP:-120}
T=$(mktemp -d /tmp/pcbpt-netns-XXXXXX)
tag=p$$
C=$tag-c
PIDS=()
cleanup() {
  for p in "${PIDS[@]}"; do kill -9 "$p" 2>/dev/null || true; done
  for k in $(seq $NW); do ip netns del $tag-w$k 2>/dev/null || true; done
  ip netns del $C 2>/dev/null || true
  if [ "${KEEP:-0}" = 0 ]; then rm -rf "$T"; fi
}
trap cleanup EXIT
if ! ip netns add $C 2>"$T/err"; then echo "SKIP: cannot create a network namespace: $(cat "$T/err")"; exit 77; fi
fail() {
  echo "FAIL: $*"
  for f in "$T"/*.log; do echo "--- $f"; tail -25 "$f"; done
  exit 1
}
inc() { ip netns exec $C "$@"; }
inw() { local k=$1; shift; ip netns exec $tag-w$k "$@"; }
inc ip link set lo up
inc ip link add br0 type bridge
inc ip addr add 10.231.0.1/24 dev br0
inc ip link set br0 up
for k in $(seq $NW); do
  ip netns add $tag-w$k
  ip link add $tag-h$k type veth peer name $tag-v$k
  ip link set $tag-h$k netns $C
  ip link set $tag-v$k netns $tag-w$k
  inc ip link set $tag-h$k master br0
  inc ip link set $tag-h$k up
  inw $k ip link set lo up
  inw $k ip addr add 10.231.0.$((10 + k))/24 dev $tag-v$k
  inw $k ip link set $tag-v$k up
done
impair() { # k: 20 Mbit/s, 1% loss and 50 +- 10 ms, each way
  local k=$1
  inw $k tc qdisc add dev $tag-v$k root tbf rate 20mbit burst 32kbit latency 400ms
  inc tc qdisc add dev $tag-h$k root tbf rate 20mbit burst 32kbit latency 400ms
  # the loss first; the queue is bypassed if net_delay is gone
  for dir in "OUTPUT -o" "INPUT -i"; do
    set -- $dir
    inw $k iptables -A $1 $2 $tag-v$k -m statistic --mode random --probability 0.01 -j DROP
    inw $k iptables -A $1 $2 $tag-v$k -j NFQUEUE --queue-num 0 --queue-bypass
  done
  # (backgrounded through `ip netns exec` itself, not a shell function, so $! is the program)
  ip netns exec $tag-w$k "$B/tests/net_delay" --queue 0 --delay-ms 50 --jitter-ms 10 --seconds 900 2>>"$T/net_delay$k.log" &
  PIDS+=($!)
}
echo "netns-test-token-$$-$RANDOM" > "$T/tok"; chmod 600 "$T/tok"
ip netns exec $C "$B/pcbpt-coord" serve --listen 10.231.0.1:0 --data-dir "$T/data" --token-file "$T/tok" --port-file "$T/port" \
  --orphan-grace 1 --heartbeat-timeout $HB --range-seconds 1 >>"$T/coord.log" 2>&1 &
PIDS+=($!)
for _ in $(seq 50); do [ -s "$T/port" ] && break; sleep 0.1; done
[ -s "$T/port" ] || fail "the coordinator did not start"
ADDR=10.231.0.1:$(cat "$T/port")
H="--host $ADDR --token-file $T/tok"
for k in $(seq $NW); do
  ip netns exec $tag-w$k "$B/pcbpt-worker" --connect $ADDR --token-file "$T/tok" --threads 1 --name w$k --cache-dir "$T/cache$k" \
    >>"$T/w$k.log" 2>&1 &
  PIDS+=($!)
done
field() { inc "$B/pcbpt-coord" status "$1" $H --json | python3 -c "import json,sys; print(json.load(sys.stdin)['$2'])"; }
ckpt() { ls "$T/data/jobs/$1"/ckpt.* | sort -t. -k2 -n | tail -1; }
run() { # label spp [stall]
  local t0=$(date +%s.%N)
  J=$(inc "$B/pcbpt-coord" submit "$S/scenes/cornell-box/scene.xml" --method pt --spp $2 --width 64 --height 64 $H | tail -1) \
    || fail "$1: submit"
  if [ -n "${3:-}" ]; then
    for _ in $(seq 200); do [ "$(field "$J" iterations)" -gt 0 ] && break; sleep 0.1; done
    grep -q "range .* -> w1 " "$T/coord.log" || sleep 1
    inw 1 iptables -I INPUT 1 -j DROP
    inw 1 iptables -I OUTPUT 1 -j DROP
    sleep "$3"
    inw 1 iptables -D INPUT 1
    inw 1 iptables -D OUTPUT 1
  fi
  timeout 300 ip netns exec $C "$B/pcbpt-coord" wait "$J" $H >/dev/null || fail "$1: wait"
  local t1=$(date +%s.%N)
  [ "$(field "$J" state)" = done ] || fail "$1: state $(field "$J" state)"
  [ "$(field "$J" iterations)" = $2 ] || fail "$1: iterations $(field "$J" iterations) != $2"
  "$B/tests/farm_tool" exact "$(ckpt "$J")" "$S/scenes/cornell-box/scene.xml" --spp $2 --method pt --width 64 --height 64 \
    || fail "$1: the farm's sums differ from a single-process render"
  SECS=$(python3 -c "print(round($t1 - $t0, 2))")
  echo "$1: $2 iterations in $SECS s (the job's own elapsed time: $(field "$J" elapsed) s)"
}
run clean "$SPP"; clean=$SECS
for k in $(seq $NW); do impair $k; done
run impaired "$SPP"
echo "impaired links: $(python3 -c "print(round($clean / $SECS, 2))")x the clean links' throughput"
# four times the iterations: the stall must begin while w1 still holds a range (at 120 the job
# once ended 0.25 s into the stall, with nothing of w1's left to orphan)
run stalled $((4 * SPP)) "$STALL"
grep -q "w1.*\(timed out\|heartbeat\|gone\|orphaned\)" "$T/coord.log" || fail "the stalled worker was never dropped"
echo PASS
