#!/usr/bin/env bash
# Fleet figures over Zenoh (docs/zenoh.md): a router, N robots in ceil(N/100) `fleet`
# processes, the supervisor running the patrol (N robots, a third per location) to F firings.
# Prints: robots, fleet processes, robots ready after (s), firings/s after ready, supervisor
# CPU seconds and peak RSS (MB), router CPU seconds and peak RSS, and the loopback's packets
# and bytes per second from ready to the end (TCP segments between the processes and the
# router: meaningful only in a network namespace of its own, where nothing else uses lo).
#
#   benches/zenoh_fleet.sh BIN N [F]     # BIN: a plan-runner built with --features zenoh
#   # alone on a loopback of its own (root):
#   ip netns add zb && ip -n zb link set lo up && ip netns exec zb benches/zenoh_fleet.sh BIN N
set -euo pipefail
BIN=$1 N=$2 F=${3:-1000}
cd "$(dirname "$0")/.."
DIR=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null || true; [ -n "${KEEP:-}" ] || rm -rf "$DIR"' EXIT
PORT=$((20000 + RANDOM % 20000))
E=tcp/127.0.0.1:$PORT
python3 - "$N" "$DIR" "$E" <<'PY'
import sys
n, d, e = int(sys.argv[1]), sys.argv[2], sys.argv[3]
xml = open("plans/nets/temperature_patrol.xml").read()
one = "<initialMarking>\n      <value>Default,1</value>"
parts = xml.split(one)
counts = [n - 2 * (n // 3), n // 3, n // 3]
out = parts[0] + "".join(one.replace("Default,1", f"Default,{c}") + p for c, p in zip(counts, parts[1:]))
open(f"{d}/patrol.xml", "w").write(out)
plan = open("plans/fleet-zenoh/patrol.toml").read()
ids = ", ".join(f'"r{i:04}"' for i in range(1, n + 1))
import re
plan = re.sub(r"robots = \[[^\]]*\]", f"robots = [{ids}]", plan)
plan = plan.replace('net = "patrol-210.xml"', 'net = "patrol.xml"').replace('tcp/127.0.0.1:7447', e)
open(f"{d}/plan.toml", "w").write(plan)
PY
"$BIN" router --listen "$E" 2> "$DIR/router.log" &
ROUTER=$!
sleep 1
P=$(( (N + 99) / 100 ))
for k in $(seq 0 $((P - 1))); do
    a=$((k * 100)); b=$(( (k + 1) * 100 < N ? (k + 1) * 100 : N ))
    "$BIN" fleet --plan "$DIR/plan.toml" --robots "$a..$b" 2> "$DIR/fleet$k.log" &
done
/usr/bin/time -f "%U %S %M" -o "$DIR/sup.time" "$BIN" run "$DIR/plan.toml" --max-firings "$F" --json > "$DIR/out.json" 2> "$DIR/sup.log" &
SUP=$!
HZ=$(getconf CLK_TCK)
LO=/sys/class/net/lo/statistics
T_READY=""
while kill -0 $SUP 2>/dev/null; do
    if [ -z "$T_READY" ] && grep -q "robots ready" "$DIR/sup.log"; then
        T_READY=$(date +%s.%N)
        P0=$(cat $LO/tx_packets) B0=$(cat $LO/tx_bytes)
    fi
    sleep 0.2
done
T_END=$(date +%s.%N)
P1=$(cat $LO/tx_packets) B1=$(cat $LO/tx_bytes)
wait $SUP || { echo "supervisor failed:"; tail -20 "$DIR/sup.log"; exit 1; }
# The supervisor's user + system CPU seconds and peak RSS (GNU time).
read -r UT ST PEAK < "$DIR/sup.time"
CPU=$(echo "$UT + $ST" | bc)
RCPU=$(awk '{print $14 + $15}' /proc/$ROUTER/stat)
RRSS=$(awk '/VmHWM/ {print $2}' /proc/$ROUTER/status)
READY=$(grep -o 'robots ready after [0-9.]*' "$DIR/sup.log" | awk '{print $4}')
RATE=$(python3 -c "import json;s=json.load(open('$DIR/out.json'));print(round(s['firings']/($T_END-$T_READY),1))")
PPS=$(python3 -c "print(round(($P1-$P0)/($T_END-$T_READY)))")
KBPS=$(python3 -c "print(round(($B1-$B0)/($T_END-$T_READY)/1000))")
echo "robots=$N fleets=$P ready_after_s=$READY firings=$F firings_per_s=$RATE sup_cpu_s=$CPU sup_peak_rss_mb=$((PEAK / 1024)) router_cpu_s=$(echo "scale=2; $RCPU/$HZ" | bc) router_peak_rss_mb=$((RRSS / 1024)) lo_packets_per_s=$PPS lo_kB_per_s=$KBPS"
grep -h "published\|fleet:" "$DIR/sup.log" "$DIR"/fleet*.log | head -3
