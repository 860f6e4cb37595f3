#!/usr/bin/env bash
# `make run`: installs what is missing, builds, and runs one semantic
# exploration of a generated house headless (lockstep simulation), showing
# progress; writes report.md, summary.json, maps and meshes under results/.
# Extra arguments go to scripts/run_mission.py (see --help there), e.g.
#   make run ARGS="--mode classic --seed 3"
# With --experiments first, runs scripts/run_experiments.py instead (make experiments).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$ROOT/scripts/setup.sh"
echo "[run] building (log: $ROOT/.colcon/build.log)"
mkdir -p "$ROOT/.colcon"
bash "$ROOT/scripts/build.sh" > "$ROOT/.colcon/build.log" 2>&1 || { tail -n 40 "$ROOT/.colcon/build.log"; exit 1; }
export PATH="/usr/bin:$PATH"
unset PYTHONPATH
set +u
# shellcheck disable=SC1091
. "$ROOT/.colcon/install/setup.sh"
set -u
export SEMEXP_VENV="${SEMEXP_VENV:-$ROOT/.venv}"
cd "$ROOT"
if [ "${1:-}" = "--experiments" ]; then
  shift
  exec "$SEMEXP_VENV/bin/python" "$ROOT/scripts/run_experiments.py" --out "$ROOT/results/experiments" "$@"
fi
SHOT=()  # rviz.png in the results when rviz can run headless
command -v rviz >/dev/null && command -v Xvfb >/dev/null && command -v import >/dev/null && SHOT=(--rviz-screenshot)
exec "$SEMEXP_VENV/bin/python" "$ROOT/scripts/run_mission.py" --out "$ROOT/results/run-$(date +%Y%m%d-%H%M%S)" \
  "${SHOT[@]}" "$@"
