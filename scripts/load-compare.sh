#!/usr/bin/env bash
# Runs the 1,000-robot load (or N robots) against one fresh release server per build, the builds interleaved in
# each round, and prints one line per run: on-time %, lateness p99, the server's CPU seconds during the load, the
# generator's CPU seconds and the server's peak RSS. The figures in BENCHMARKS.md name this script.
#
# Usage: scripts/load-compare.sh ROBOTS ROUNDS SERVER_BINARY...
#   e.g. scripts/load-compare.sh 500 3 /work/bench-base/dmp-server target/release/dmp-server
# The generator is target/release/dmpctl (DMPCTL overrides it); port 50152. LOAD_ARGS adds flags to the load
# (e.g. LOAD_ARGS=--pose for pose robots at the Panda profile).
set -euo pipefail
n=$1 rounds=$2
shift 2
generator=${DMPCTL:-target/release/dmpctl}
one() {
  local server=$1 dir pid t0 t1
  dir=$(mktemp -d)
  RUST_LOG=warn "$server" --data-dir "$dir/data" --grpc-addr 127.0.0.1:50152 --no-zenoh >"$dir/server.log" 2>&1 &
  pid=$!
  for _ in $(seq 100); do (echo >/dev/tcp/127.0.0.1/50152) 2>/dev/null && break; sleep 0.1; done
  t0=$(awk '{print $14+$15}' "/proc/$pid/stat")
  /usr/bin/time -f "%U %S" -o "$dir/gtime" "$generator" --server http://127.0.0.1:50152 load --robots "$n" \
    --rate 1000 --segment-s 0.01 --duration-s 10 ${LOAD_ARGS:-} >"$dir/load.json" 2>"$dir/load.err"
  t1=$(awk '{print $14+$15}' "/proc/$pid/stat")
  rss=$(awk '/VmHWM/{print $2}' "/proc/$pid/status")
  kill -INT "$pid"
  wait "$pid" || true
  python3 - "$dir/load.json" "$server" "$((t1 - t0))" "$(awk '{print $1+$2}' "$dir/gtime")" "$rss" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
ticks = int(sys.argv[3])
print(f"{sys.argv[2]} N={r['robots']}{' pose' if r.get('pose') else ''} on_time={r['setpoints_on_time_percent']}% "
      f"p99={r['lateness_ms']['p99']}ms server_cpu={ticks / 100:.1f}s generator_cpu={sys.argv[4]}s "
      f"rss={int(sys.argv[5]) // 1024}MiB failed={r['streams_failed']}")
PY
  rm -rf "$dir"
}
for _ in $(seq "$rounds"); do
  for server in "$@"; do one "$server"; done
done
