#!/usr/bin/env bash
# Installs everything semantic_exploration needs to build, test and run.
# Idempotent: re-running it only installs what is missing.
#   Debian 12 (bookworm): ROS 1 from Debian's own archive.
#   Ubuntu 20.04 (focal): ROS Noetic from packages.ros.org.
# Also creates the Python venv (.venv, --system-site-packages so rospy
# imports alongside) holding the simulator's PyPI-only dependencies.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="${SEMEXP_VENV:-$ROOT/.venv}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi

. /etc/os-release
log() { echo "[setup] $*"; }

DEBIAN_PKGS=(
  build-essential cmake pkg-config python3-venv python3-pip
  ros-core-dev python3-rostest python3-rosbag python3-roslaunch
  python3-rosmaster python3-rosnode python3-rostopic python3-rosservice
  python3-rosparam rosbash libtf2-ros-dev python3-tf2-ros libtf2-eigen-dev libtf2-msgs-dev
  libtf2-geometry-msgs-dev libmessage-filters-dev libcv-bridge-dev
  python3-cv-bridge libimage-transport-dev liboctomap-dev libompl-dev
  libopencv-dev libopencv-dnn-dev libeigen3-dev libgtest-dev
  python3-onnx
  colcon python3-colcon-ros python3-colcon-cmake python3-colcon-bash
  python3-std-msgs python3-sensor-msgs python3-geometry-msgs
  python3-nav-msgs python3-visualization-msgs python3-std-srvs
  libtrajectory-msgs-dev python3-trajectory-msgs
  python3-tf2-msgs python3-numpy python3-yaml python3-scipy
  python3-matplotlib libembree3-3
  rviz xvfb xauth imagemagick libgl1-mesa-dri
)

NOETIC_PKGS=(
  build-essential cmake pkg-config python3-venv python3-pip
  ros-noetic-ros-base ros-noetic-rostest ros-noetic-tf2-ros
  ros-noetic-tf2-eigen ros-noetic-tf2-geometry-msgs ros-noetic-tf2-msgs ros-noetic-cv-bridge
  ros-noetic-image-transport ros-noetic-message-filters
  ros-noetic-octomap
  ros-noetic-ompl ros-noetic-sensor-msgs ros-noetic-nav-msgs ros-noetic-trajectory-msgs
  ros-noetic-visualization-msgs ros-noetic-std-srvs ros-noetic-rosbag
  libeigen3-dev libopencv-dev libopencv-dnn-dev libgtest-dev
  python3-colcon-common-extensions python3-numpy python3-yaml python3-scipy
  python3-matplotlib libembree3-3
  ros-noetic-rviz xvfb xauth imagemagick libgl1-mesa-dri
)

missing() {
  local out=()
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || out+=("$p")
  done
  echo "${out[@]:-}"
}

apt_install() {
  local todo
  todo=$(missing "$@")
  if [ -z "$todo" ]; then log "system packages: all present"; return; fi
  log "installing: $todo"
  $SUDO apt-get update -qq
  # shellcheck disable=SC2086
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends $todo
}

case "${ID}:${VERSION_ID:-}" in
  debian:12*) apt_install "${DEBIAN_PKGS[@]}" ;;
  ubuntu:20.04)
    if [ ! -f /etc/apt/sources.list.d/ros-latest.list ]; then
      log "adding the ROS Noetic apt source"
      $SUDO apt-get update -qq
      DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq curl gnupg lsb-release
      curl -sSL https://raw.githubusercontent.com/ros/rosdistro/master/ros.key \
        | $SUDO gpg --dearmor -o /usr/share/keyrings/ros-archive-keyring.gpg
      echo "deb [signed-by=/usr/share/keyrings/ros-archive-keyring.gpg] http://packages.ros.org/ros/ubuntu focal main" \
        | $SUDO tee /etc/apt/sources.list.d/ros-latest.list >/dev/null
    fi
    apt_install "${NOETIC_PKGS[@]}" ;;
  *)
    echo "[setup] unsupported OS '${PRETTY_NAME:-unknown}': need Debian 12 or Ubuntu 20.04" >&2
    exit 1 ;;
esac

# Python venv for the simulator's PyPI-only needs (ray tracing).
PY_REQS="$ROOT/scripts/requirements-sim.txt"
if [ ! -x "$VENV/bin/python" ]; then
  log "creating venv $VENV"
  /usr/bin/python3 -m venv --system-site-packages "$VENV"
fi
stamp="$VENV/.requirements.sha"
want=$(sha256sum "$PY_REQS" | cut -d' ' -f1)
if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "$want" ]; then
  log "installing Python requirements into $VENV"
  "$VENV/bin/python" -m pip install -q --disable-pip-version-check -r "$PY_REQS"
  echo "$want" > "$stamp"
else
  log "venv: requirements present"
fi
# The detector's tests build their ONNX model with the onnx package: python3-onnx on Debian; Ubuntu 20.04
# has no such package, so there it goes into the venv (which the tests use when SEMEXP_VENV is set).
if [ "${ID}" = ubuntu ] && ! "$VENV/bin/python" -c "import onnx" 2>/dev/null; then
  log "installing onnx into $VENV (Ubuntu 20.04 has no python3-onnx)"
  "$VENV/bin/python" -m pip install -q --disable-pip-version-check "onnx>=1.12,<1.17"
fi
log "done"
