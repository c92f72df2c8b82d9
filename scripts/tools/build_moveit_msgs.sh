#!/usr/bin/env bash
# Make moveit_msgs (MoveIt Jazzy's message PlanningScene and service GetMotionPlan) importable in a venv.
#   scripts/tools/build_moveit_msgs.sh [VENV]     (default: $DRD_VENV or .venv; scripts/run.sh calls it)
# - a moveit_msgs that the venv's python already imports with both interfaces (a ROS install's, or one
#   built here before from the same sources) is used as it is;
# - otherwise three interface packages are built in order with the PyPI ROS build tools
#   (interfaces/requirements-build.txt) and Debian's cmake and g++, and installed into the venv itself:
#   interfaces/object_recognition_msgs (ObjectType), interfaces/octomap_msgs (Octomap, OctomapWithPose) and
#   interfaces/moveit_msgs (26 messages and GetMotionPlan), for Python only (no C++ type supports:
#   DRD_PYTHON_ONLY); 202 s on 2 busy cores (101 s of CPU), once: a stamp of the sources in
#   share/moveit_msgs skips the build next time.
# scripts/tools/build_nav2_msgs.sh has installed cmake, g++ and the build tools before (run.sh calls it first).
set -euo pipefail
cd "$(dirname "$0")/../.."

venv=${1:-${DRD_VENV:-.venv}}
venv=$(cd "$venv" && pwd)
py="$venv/bin/python"
packages=(object_recognition_msgs octomap_msgs moveit_msgs)
stamp_file="$venv/share/moveit_msgs/drd_planner_build.sha256"
stamp=$(for pkg in "${packages[@]}"; do
  cat "interfaces/$pkg/CMakeLists.txt" "interfaces/$pkg/package.xml" "interfaces/$pkg"/msg/*.msg
done | cat - interfaces/moveit_msgs/srv/*.srv interfaces/requirements-build.txt scripts/tools/build_moveit_msgs.sh |
  sha256sum | cut -d' ' -f1)

importable() {
  "$py" -c 'from moveit_msgs.msg import PlanningScene; from moveit_msgs.srv import GetMotionPlan' \
    >/dev/null 2>&1
}

if [ -f "$stamp_file" ] && [ "$(cat "$stamp_file")" = "$stamp" ] && importable; then
  echo "moveit_msgs: built here before, cached in $venv" >&2
  exit 0
fi
if [ ! -f "$stamp_file" ] && importable; then
  where=$("$py" -c 'import moveit_msgs, os; print(os.path.dirname(moveit_msgs.__file__))')
  echo "moveit_msgs: using the installed one at $where" >&2
  exit 0
fi

echo "moveit_msgs: building MoveIt's interfaces (PlanningScene, GetMotionPlan) into $venv" >&2
missing=()
for tool in cmake g++ make; do
  command -v "$tool" >/dev/null 2>&1 || missing+=("$tool")
done
include=$("$py" -c 'import sysconfig; print(sysconfig.get_paths()["include"])')
[ -f "$include/Python.h" ] || missing+=("python3-dev")
if [ "${#missing[@]}" -gt 0 ]; then
  echo "moveit_msgs: installing ${missing[*]} with apt" >&2
  sudo_cmd=""
  [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  $sudo_cmd apt-get install -y -qq "${missing[@]}" >/dev/null
fi
"$py" -m pip install -q --disable-pip-version-check -r interfaces/requirements-build.txt

includes="$include;$("$py" -c 'import numpy; print(numpy.get_include())')"
jobs=$(nproc 2>/dev/null || echo 2)
started=$SECONDS
step=0
for pkg in "${packages[@]}"; do
  step=$((step + 1))
  build="$venv/build/$pkg"
  log="$venv/build/$pkg.log"
  rm -rf "$build"
  mkdir -p "$build"
  fail() {
    echo "moveit_msgs: $pkg: $1 failed; the last lines of $log:" >&2
    tail -n 30 "$log" >&2
    exit 1
  }
  echo "moveit_msgs: [$step/${#packages[@]}] $pkg: configure, compile ($jobs jobs), install (log: $log)" >&2
  AMENT_PREFIX_PATH="$venv" cmake -S "interfaces/$pkg" -B "$build" \
    -DCMAKE_INSTALL_PREFIX="$venv" -DCMAKE_PREFIX_PATH="$venv" -DCMAKE_BUILD_TYPE=Release \
    -DBUILD_TESTING=OFF -DPython3_EXECUTABLE="$py" -DDRD_PYTHON_INCLUDES="$includes" -DDRD_PYTHON_ONLY=ON \
    >"$log" 2>&1 ||
    fail configure
  AMENT_PREFIX_PATH="$venv" cmake --build "$build" -j "$jobs" >>"$log" 2>&1 || fail compile
  cmake --install "$build" >>"$log" 2>&1 || fail install
  rm -rf "$build"
done
importable || {
  echo "moveit_msgs: built, but python -c 'from moveit_msgs.srv import GetMotionPlan' fails" >&2
  exit 1
}
echo "$stamp" >"$stamp_file"
echo "moveit_msgs: built in $((SECONDS - started)) s, cached in $venv" >&2
