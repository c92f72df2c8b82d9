#!/usr/bin/env bash
# Make nav2_msgs (the Nav2 Jazzy action ComputePathToPose and service IsPathValid) importable in a venv.
#   scripts/tools/build_nav2_msgs.sh [VENV]     (default: $DRD_VENV or .venv; scripts/run.sh calls it)
# - a nav2_msgs that the venv's python already imports with both interfaces (a ROS install's, or one
#   built here before from the same sources) is used as it is;
# - otherwise interfaces/nav2_msgs is built with the PyPI ROS build tools (interfaces/requirements-build.txt)
#   and Debian's cmake and g++ (installed with apt when missing) and installed into the venv itself
#   (its lib/, share/ and site-packages), about 1-2 minutes on 2 cores, once: a stamp of the sources
#   in share/nav2_msgs skips the build next time.
set -euo pipefail
cd "$(dirname "$0")/../.."

venv=${1:-${DRD_VENV:-.venv}}
venv=$(cd "$venv" && pwd)
py="$venv/bin/python"
src="$PWD/interfaces/nav2_msgs"
stamp_file="$venv/share/nav2_msgs/drd_planner_build.sha256"
stamp=$(cat "$src"/CMakeLists.txt "$src"/package.xml "$src"/action/*.action "$src"/srv/*.srv \
  interfaces/requirements-build.txt scripts/tools/build_nav2_msgs.sh | sha256sum | cut -d' ' -f1)

importable() {
  "$py" -c 'from nav2_msgs.action import ComputePathToPose; from nav2_msgs.srv import IsPathValid' \
    >/dev/null 2>&1
}

if [ -f "$stamp_file" ] && [ "$(cat "$stamp_file")" = "$stamp" ] && importable; then
  echo "nav2_msgs: built here before, cached in $venv" >&2
  exit 0
fi
if [ ! -f "$stamp_file" ] && importable; then
  where=$("$py" -c 'import nav2_msgs, os; print(os.path.dirname(nav2_msgs.__file__))')
  echo "nav2_msgs: using the installed one at $where" >&2
  exit 0
fi

echo "nav2_msgs: building the Nav2 interfaces (ComputePathToPose, IsPathValid) into $venv" >&2
missing=()
for tool in cmake g++ make; do
  command -v "$tool" >/dev/null 2>&1 || missing+=("$tool")
done
include=$("$py" -c 'import sysconfig; print(sysconfig.get_paths()["include"])')
[ -f "$include/Python.h" ] || missing+=("python3-dev")
if [ "${#missing[@]}" -gt 0 ]; then
  echo "nav2_msgs: installing ${missing[*]} with apt" >&2
  sudo_cmd=""
  [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  $sudo_cmd apt-get install -y -qq "${missing[@]}" >/dev/null
fi

echo "nav2_msgs: [1/4] the ROS build tools (pip)" >&2
"$py" -m pip install -q --disable-pip-version-check -r interfaces/requirements-build.txt

build="$venv/build/nav2_msgs"
log="$venv/build/nav2_msgs.log"
rm -rf "$build"
mkdir -p "$build"
includes="$include;$("$py" -c 'import numpy; print(numpy.get_include())')"
jobs=$(nproc 2>/dev/null || echo 2)
started=$SECONDS
fail() {
  echo "nav2_msgs: $1 failed; the last lines of $log:" >&2
  tail -n 30 "$log" >&2
  exit 1
}
echo "nav2_msgs: [2/4] configure (log: $log)" >&2
AMENT_PREFIX_PATH="$venv" cmake -S "$src" -B "$build" \
  -DCMAKE_INSTALL_PREFIX="$venv" -DCMAKE_PREFIX_PATH="$venv" -DCMAKE_BUILD_TYPE=Release \
  -DBUILD_TESTING=OFF -DPython3_EXECUTABLE="$py" -DDRD_PYTHON_INCLUDES="$includes" >"$log" 2>&1 ||
  fail configure
echo "nav2_msgs: [3/4] compile ($jobs jobs; about a minute on 2 cores)" >&2
AMENT_PREFIX_PATH="$venv" cmake --build "$build" -j "$jobs" >>"$log" 2>&1 || fail compile
echo "nav2_msgs: [4/4] install into $venv" >&2
cmake --install "$build" >>"$log" 2>&1 || fail install
importable || fail "import check (python -c 'from nav2_msgs.action import ComputePathToPose')"
echo "$stamp" >"$stamp_file"
rm -rf "$build"
echo "nav2_msgs: built in $((SECONDS - started)) s, cached in $venv" >&2
