#!/usr/bin/env bash
# `make bench`: builds (Release) and runs every benchmark program; each
# writes JSON lines {"name", "value", "unit", "peer", "peer_value"} to
# results/bench/<program>.jsonl and prints a table.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="${SEMEXP_BENCH_OUT:-$ROOT/results/bench}"
bash "$ROOT/scripts/setup.sh"
BUILD_TYPE=Release bash "$ROOT/scripts/build.sh" > /tmp/semexp-bench-build.log 2>&1 || {
  tail -n 40 /tmp/semexp-bench-build.log; exit 1; }
export PATH="/usr/bin:$PATH"
unset PYTHONPATH
# shellcheck disable=SC1091
set +u
. "$ROOT/.colcon/install/setup.sh"
set -u
export SEMEXP_VENV="${SEMEXP_VENV:-$ROOT/.venv}"
mkdir -p "$OUT"
BIN="$ROOT/.colcon/install/semantic_exploration/lib/semantic_exploration"
status=0
for b in "$BIN"/bench_*; do
  [ -x "$b" ] || continue
  case "$(basename "$b")" in *.*) continue ;; esac  # scripts/bench_*.py run below, in the venv
  name=$(basename "$b")
  rm -f "$OUT/$name.jsonl"
  echo "== $name"
  (cd "$ROOT" && "$b" --out "$OUT/$name.jsonl") || { echo "$name failed"; status=1; }
done
for s in "$ROOT"/scripts/bench_*.py; do
  [ -f "$s" ] || continue
  name=$(basename "$s" .py)
  rm -f "$OUT/$name.jsonl"
  echo "== $name"
  (cd "$ROOT" && "$SEMEXP_VENV/bin/python" "$s" --out "$OUT/$name.jsonl") || { echo "$name failed"; status=1; }
done
echo "benchmark figures: $OUT/*.jsonl"
exit $status
