#!/usr/bin/env bash
# Runs `dmpctl load --via-zenoh-discovery` against a plant on this machine: a Zenoh router, three fresh release
# servers each serving a third of the load's cells (load-0, load-3, ... on s0; load-1, load-4, ... on s1; ...),
# and prints the load's totals and one line per server. The plant figures in BENCHMARKS.md name this script.
#
# Usage: scripts/load-plant.sh ROBOTS [LOAD FLAGS...]
#   e.g. scripts/load-plant.sh 1000 --duration-s 10
# The router is `zenohd` when on the PATH, else eclipse-zenoh's Python session in router mode
# (DMP_TEST_PYTHON, default .venv/bin/python); it listens on tcp/127.0.0.1:7647, the servers on 50160-50162.
# DMP_SERVER_BIN and DMPCTL override target/release/dmp-server and target/release/dmpctl.
set -euo pipefail
n=$1
shift
server=${DMP_SERVER_BIN:-target/release/dmp-server}
generator=${DMPCTL:-target/release/dmpctl}
python=${DMP_TEST_PYTHON:-.venv/bin/python}
router=tcp/127.0.0.1:7647
cells=$(((n + 9) / 10))
dir=$(mktemp -d)
pids=()
cleanup() {
  # The servers stop on SIGINT; the router (started first) on SIGTERM, after them.
  for p in "${pids[@]:1}"; do kill -INT "$p" 2>/dev/null || true; done
  for p in "${pids[@]:1}"; do wait "$p" 2>/dev/null || true; done
  kill -TERM "${pids[0]}" 2>/dev/null || true
  wait 2>/dev/null || true
  rm -rf "$dir"
}
trap cleanup EXIT
if command -v zenohd >/dev/null; then
  zenohd --listen "$router" --no-multicast-scouting >"$dir/router.log" 2>&1 &
else
  "$python" - "$router" >"$dir/router.log" 2>&1 <<'PY' &
import json, signal, sys, zenoh
c = zenoh.Config()
c.insert_json5("mode", '"router"')
c.insert_json5("listen/endpoints", json.dumps([sys.argv[1]]))
c.insert_json5("scouting/multicast/enabled", "false")
stop = {signal.SIGINT, signal.SIGTERM}
signal.pthread_sigmask(signal.SIG_BLOCK, stop)
s = zenoh.open(c)
signal.sigwait(stop)
s.close()
PY
fi
pids+=($!)
for _ in $(seq 100); do (echo >/dev/tcp/127.0.0.1/7647) 2>/dev/null && break; sleep 0.1; done
for i in 0 1 2; do
  mine=$(seq -s, -f "load-%g" "$i" 3 $((cells - 1)))
  RUST_LOG=warn "$server" --data-dir "$dir/s$i" --grpc-addr "127.0.0.1:5016$i" --server-id "s$i" --cells "$mine" \
    --zenoh-mode client --zenoh-connect "$router" --zenoh-listen tcp/127.0.0.1:0 --zenoh-no-multicast \
    >"$dir/s$i.log" 2>&1 &
  pids+=($!)
done
for i in 0 1 2; do
  for _ in $(seq 100); do (echo >/dev/tcp/127.0.0.1/5016$i) 2>/dev/null && break; sleep 0.1; done
done
"$generator" --zenoh-connect "$router" load --via-zenoh-discovery --robots "$n" --rate 1000 --segment-s 0.01 "$@" \
  >"$dir/load.json" 2>"$dir/load.err" || { cat "$dir/load.err" >&2; exit 1; }
python3 - "$dir/load.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
print(f"total N={r['robots']}{' pose' if r['pose'] else ''} on_time={r['setpoints_on_time_percent']}% "
      f"p99={r['lateness_ms']['p99']}ms failed={r['streams_failed']} generator_cpu={r['generator_cpu_percent']}% "
      f"errors={[(e['message'], e['count']) for e in r['errors']]}")
for s in r["servers"]:
    print(f"  {s['server_id']} cells={len(s['cells'])} robots={s['robots']} on_time={s['setpoints_on_time_percent']}% "
          f"p99={s['lateness_ms']['p99']}ms cpu={s['cpu_percent']}% rss_max={s['rss_mib_max']}MiB")
PY
