#!/usr/bin/env bash
# The DDS twin of benches/zenoh_fleet.sh (docs/zenoh.md, "Fleet figures"): N robot
# processes (`plan-runner robot`, one DDS participant each, started 100 ms apart), then the
# supervisor running the patrol (N robots, a third per location) to F firings over DDS.
# Prints: robots, robots ready after (s), firings/s after ready, supervisor CPU seconds and
# peak RSS (MB), the robots' summed peak RSS (MB), and UDP datagrams sent per second from
# ready to the end (/proc/net/snmp: meaningful only in a network namespace of its own).
#
#   benches/dds_fleet.sh BIN N [F]     # BIN: a plan-runner built with --features ros2
#   # alone on a loopback of its own (root):
#   ip netns add db && ip -n db link set lo up && ip netns exec db benches/dds_fleet.sh BIN N
set -euo pipefail
BIN=$1 N=$2 F=${3:-1000}
cd "$(dirname "$0")/.."
DIR=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null || true; [ -n "${KEEP:-}" ] || rm -rf "$DIR"' EXIT
D=$((100 + RANDOM % 100))
python3 - "$N" "$DIR" <<'PY'
import re, sys
n, d = int(sys.argv[1]), sys.argv[2]
xml = open("plans/nets/temperature_patrol.xml").read()
one = "<initialMarking>\n      <value>Default,1</value>"
parts = xml.split(one)
counts = [n - 2 * (n // 3), n // 3, n // 3]
out = parts[0] + "".join(one.replace("Default,1", f"Default,{c}") + p for c, p in zip(counts, parts[1:]))
open(f"{d}/patrol.xml", "w").write(out)
plan = open("plans/temperature_patrol_ros2.toml").read()
ids = ", ".join(f'"r{i:04}"' for i in range(1, n + 1))
plan = re.sub(r"robots = \[[^\]]*\]", f"robots = [{ids}]", plan)
plan = plan.replace("nets/temperature_patrol.xml", "patrol.xml")
plan = plan.replace("startup = 30.0", "startup = 240.0").replace("lost_after = 1.0", "lost_after = 10.0")
plan = re.sub(r"\[stop\]\nmax_firings = \d+\n", "", plan)
open(f"{d}/plan.toml", "w").write(plan)
PY
PIDS=()
for i in $(seq 1 "$N"); do
    id=$(printf 'r%04d' "$i")
    "$BIN" robot --id "$id" --plan "$DIR/plan.toml" --ros2-domain "$D" 2> "$DIR/$id.log" &
    PIDS+=($!)
    sleep 0.1
done
T_START=$(date +%s.%N)
/usr/bin/time -f "%U %S %M" -o "$DIR/sup.time" "$BIN" run "$DIR/plan.toml" --max-firings "$F" --json --ros2-domain "$D" > "$DIR/out.json" 2> "$DIR/sup.log" &
SUP=$!
udp_out() { awk '/^Udp:/ { if (h) print $5; h = 1 }' /proc/net/snmp; }
T_READY=""
while kill -0 $SUP 2>/dev/null; do
    if [ -z "$T_READY" ] && grep -q "robots ready" "$DIR/sup.log"; then
        T_READY=$(date +%s.%N)
        U0=$(udp_out)
        # The robots' peak RSS so far (they leave as soon as the run is over).
        ROBOTS_RSS=0
        for p in "${PIDS[@]}"; do
            r=$(awk '/VmHWM/ {print $2}' /proc/$p/status 2>/dev/null || echo 0)
            ROBOTS_RSS=$((ROBOTS_RSS + ${r:-0}))
        done
    fi
    sleep 0.2
done
T_END=$(date +%s.%N)
U1=$(udp_out)
wait $SUP || { echo "supervisor failed:"; tail -20 "$DIR/sup.log"; exit 1; }
# The supervisor's user + system CPU seconds and peak RSS (GNU time).
read -r UT ST PEAK < "$DIR/sup.time"
CPU=$(echo "$UT + $ST" | bc)
[ -n "$T_READY" ] || { echo "no ready line in the supervisor's log:"; tail "$DIR/sup.log"; exit 1; }
# From the supervisor's start to its "robots ready" line (polled every 0.2 s).
READY=$(python3 -c "print(round($T_READY - $T_START, 1))")
RATE=$(python3 -c "import json;s=json.load(open('$DIR/out.json'));print(round(s['firings']/($T_END-$T_READY),1))")
DPS=$(python3 -c "print(round(($U1-$U0)/($T_END-$T_READY)))")
echo "robots=$N ready_after_s=$READY firings=$F firings_per_s=$RATE sup_cpu_s=$CPU sup_peak_rss_mb=$((PEAK / 1024)) robots_peak_rss_mb=$((ROBOTS_RSS / 1024)) udp_datagrams_per_s=$DPS"
