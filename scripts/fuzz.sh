#!/usr/bin/env bash
# Fuzzes every target of the `fuzz` test binary (tests/tests/fuzz/) for SECONDS each (default 600): the wire's
# decoders, the scenario and CSV files, and every gRPC request through the real server. The targets run in
# parallel (DMP_FUZZ_THREADS, default: one per core); each prints `fuzz <target>: <N> cases in <S> s, 0 failures`,
# or its shrunk failing input and the DMP_FUZZ_SEED that replays it.
#
# Usage: scripts/fuzz.sh [SECONDS]        (from any directory)
set -euo pipefail

seconds="${1:-600}"
if ! [[ "$seconds" =~ ^[0-9]+([.][0-9]+)?$ ]]; then
    echo "usage: $0 [SECONDS]" >&2
    exit 2
fi
cd "$(dirname "${BASH_SOURCE[0]}")/.."
threads="${DMP_FUZZ_THREADS:-$(nproc)}"

cargo test -p dmp-tests --test fuzz --locked --no-run
log="$(mktemp)"
trap 'rm -f "$log"' EXIT
status=0
DMP_FUZZ_SECONDS="$seconds" cargo test -p dmp-tests --test fuzz --locked -- --nocapture --test-threads="$threads" \
    2>&1 | tee "$log" || status=$?
echo
echo "== fuzz summary (${seconds} s per target) =="
grep -E '^fuzz [a-z_]+: ' "$log" || true
exit "$status"
