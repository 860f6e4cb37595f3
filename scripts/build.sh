#!/usr/bin/env bash
# Builds the package with colcon into .colcon/{build,install} (Release by
# default; BUILD_TYPE=Debug for a debug build). Serialised with a lock so
# that concurrent callers do not build over each other.
# The core gtest programs are not built here (SEMEXP_BUILD_CORE_TESTS=ON to
# build them): make test builds and runs them with the sanitizers
# (scripts/run_sanitize.sh).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
WS="${SEMEXP_WS:-$ROOT/.colcon}"
BUILD_TYPE="${BUILD_TYPE:-Release}"
JOBS="${JOBS:-$(nproc)}"
mkdir -p "$WS"
# Debian's python3 must come first: catkin needs catkin_pkg (see README).
export PATH="/usr/bin:$PATH"
unset PYTHONPATH
if [ -f /opt/ros/noetic/setup.sh ]; then . /opt/ros/noetic/setup.sh; fi
exec 9>"$WS/.build.lock"
flock 9
cd "$ROOT"
MAKEFLAGS="-j$JOBS" colcon --log-base "$WS/log" build \
  --paths "$ROOT" --build-base "$WS/build" --install-base "$WS/install" \
  --event-handlers console_direct+ \
  --cmake-args -DCMAKE_BUILD_TYPE="$BUILD_TYPE" -DPYTHON_EXECUTABLE=/usr/bin/python3 \
               -DSEMEXP_WERROR="${SEMEXP_WERROR:-ON}" -DCATKIN_ENABLE_TESTING=OFF \
               -DSEMEXP_BUILD_CORE_TESTS="${SEMEXP_BUILD_CORE_TESTS:-OFF}"
