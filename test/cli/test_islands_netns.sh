#!/usr/bin/env bash
# The island model between two hosts: two network namespaces joined by a veth pair, each with its
# own address, stand for two machines. The ROS master (roscore) runs in the first; one
# estimator_node island runs in each with ROS_IP and ROS_MASTER_URI set as on real hosts, both
# replaying the same simulated bag of paper_object with their own seeds. Passes when migrants
# arrive in both directions and 99 % of the batches' trips (sender's send stamp to the
# receiver's arrival, ~stats migrant_latency_p99_ms) are shorter than one migration period of
# their sender (its median, ~stats migration_period_ms); the figures are printed, with the
# largest trip and the batches later than their sender's own period. Needs root (ip netns); where network
# namespaces cannot be made the test FAILS saying so: it is never skipped.
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
source "$here/scripts/env.sh"
bin="$here/.ws/devel/lib/motion_model_estimation"
tmp=$(mktemp -d)
ns_a=mme_isl_a_$$ ns_b=mme_isl_b_$$
veth_a=mmea$$ veth_b=mmeb$$  # interface names: 15 characters at most
addr_a=10.254.41.1 addr_b=10.254.41.2 port=11311
master=http://$addr_a:$port
timeout_s=${MME_ISLANDS_TIMEOUT_S:-120}
pids=()
cleanup() {
  local rc=$?
  for p in "${pids[@]}"; do kill -INT "$p" 2>/dev/null || true; done
  for p in "${pids[@]}"; do timeout 10 tail --pid="$p" -f /dev/null 2>/dev/null || kill -9 "$p" 2>/dev/null || true; done
  # Whatever still runs inside the namespaces was started by this script (roscore's children).
  for ns in "$ns_a" "$ns_b"; do
    ip netns pids "$ns" 2>/dev/null | while read -r p; do kill -9 "$p" 2>/dev/null || true; done
    ip netns del "$ns" 2>/dev/null || true
  done
  if [ "$rc" -ne 0 ]; then
    for f in "$tmp"/*.log; do [ -e "$f" ] && { echo "--- $f"; tail -15 "$f"; }; done
  fi
  [ -n "${MME_KEEP_TMP:-}" ] && echo "kept $tmp" || rm -rf "$tmp"
}
trap cleanup EXIT

if ! ip netns add "$ns_a" 2>"$tmp/netns.err"; then
  echo "test_islands_netns: FAILED, not skipped: 'ip netns add' is impossible here ($(cat "$tmp/netns.err")); it needs root and network namespaces" >&2
  exit 1
fi
ip netns add "$ns_b"
ip link add "$veth_a" type veth peer name "$veth_b"
ip link set "$veth_a" netns "$ns_a"
ip link set "$veth_b" netns "$ns_b"
ip -n "$ns_a" addr add "$addr_a/24" dev "$veth_a"
ip -n "$ns_b" addr add "$addr_b/24" dev "$veth_b"
for ns in "$ns_a" "$ns_b"; do ip -n "$ns" link set lo up; done
ip -n "$ns_a" link set "$veth_a" up
ip -n "$ns_b" link set "$veth_b" up

# in_host A|B CMD...: CMD on host A (the master's) or B, with the ROS network set as there.
in_host() {
  local host=$1; shift
  local ns=$ns_a ip=$addr_a
  [ "$host" = B ] && { ns=$ns_b; ip=$addr_b; }
  ip netns exec "$ns" env -u ROS_HOSTNAME ROS_IP="$ip" ROS_MASTER_URI="$master" \
    ROS_HOME="$tmp/ros_home_$host" "$@"
}

"$bin/simulate" --scene paper_object --frames 150 --out "$tmp/paper_object.bag" >/dev/null
in_host A roscore -p "$port" >"$tmp/roscore.log" 2>&1 &
pids+=($!)
for _ in $(seq 100); do in_host B rosparam get /rosdistro >/dev/null 2>&1 && break; sleep 0.2; done
in_host B rosparam get /rosdistro >/dev/null || { echo "the master in host A does not answer from host B" >&2; exit 1; }

period=10  # the default ~migration_period_generations
island() {  # island A|B SEED
  in_host "$1" "$bin/estimator_node" __name:=estimator __ns:="island_$1" \
    _model:="$here/config/models/paper_object.yaml" _bag:="$tmp/paper_object.bag" \
    _population:=40 _seed:="$2" _islands/enabled:=true \
    _migration_period_generations:=$period _migrants:=3 _publish_markers:=false \
    >"$tmp/island_$1.log" 2>&1 &
  pids+=($!)
}
island A 1
island B 2

# stats A|B: the island's latest ~stats line, read from its own host ("" when none came; the
# CSV form keeps it on one line; rostopic takes seconds to start on a busy machine).
stats() {
  { in_host "$1" timeout 40 rostopic echo -p -n 1 "/island_$1/estimator/stats" 2>/dev/null || true; } |
    sed -n '2s/^[^,]*,//p'
}
value() {  # value LINE KEY
  tr ' ' '\n' <<<"$1" | sed -n "s/^$2=//p"
}
start=$SECONDS
while :; do
  line_a=$(stats A) line_b=$(stats B)
  ready=1
  for line in "$line_a" "$line_b"; do
    [ -n "$(value "$line" migration_period_ms)" ] && [ -n "$(value "$line" migrant_latency_max_ms)" ] &&
      [ "$(value "$line" migrants_received)" -gt 0 ] 2>/dev/null || ready=0
  done
  [ "$ready" -eq 1 ] && break
  if [ $((SECONDS - start)) -gt "$timeout_s" ]; then
    echo "no migrants in both directions within $timeout_s s:" >&2
    echo "A: $line_a" >&2
    echo "B: $line_b" >&2
    exit 1
  fi
  sleep 1
done
# A few more periods, so that the figures cover more than the first batch.
sleep 5
line_a=$(stats A) line_b=$(stats B)
echo "A ($addr_a): $line_a"
echo "B ($addr_b): $line_b"
fail=0
for pair in "A B" "B A"; do
  set -- $pair
  receiver=$1 sender=$2
  line_r=$line_a line_s=$line_b
  [ "$receiver" = B ] && { line_r=$line_b; line_s=$line_a; }
  p50=$(value "$line_r" migrant_latency_p50_ms)
  p99=$(value "$line_r" migrant_latency_p99_ms)
  max=$(value "$line_r" migrant_latency_max_ms)
  late=$(value "$line_r" migrant_batches_late)
  batches=$(value "$line_r" migrant_batches_from_peers)
  received=$(value "$line_r" migrants_received)
  accepted=$(value "$line_r" migrants_accepted)
  period_ms=$(value "$line_s" migration_period_ms)
  echo "$sender -> $receiver: $batches batches, $received migrants received, $accepted accepted;" \
       "latency p50 $p50 ms, p99 $p99 ms, max $max ms; $late batches later than their sender's" \
       "period; $sender's migration period ($period generations, median) $period_ms ms"
  if ! awk -v l="$p99" -v p="$period_ms" 'BEGIN { exit !(l >= 0 && l < p) }'; then
    echo "FAILED: $sender -> $receiver: 1 % of the batches took $p99 ms or more, over one migration period ($period_ms ms)" >&2
    fail=1
  fi
done
[ "$fail" -eq 0 ]
echo "test_islands_netns: ok"
