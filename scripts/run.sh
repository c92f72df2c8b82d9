#!/usr/bin/env bash
# Set up a virtual environment with both packages and run one job.
#   scripts/run.sh demo    the main job: the planner node on the bundled real-scale helicopter bag heli_lines (planner_demo)
#   scripts/run.sh test    the whole suite: ruff, mypy, the docs build (warnings as errors), pytest
# Works on a fresh Debian/Ubuntu machine with Python 3.10+ (installs python3-venv, and cmake, g++ and the
# Python headers for the nav2_msgs and moveit_msgs builds, with apt when missing).
set -euo pipefail
cd "$(dirname "$0")/.."

job=${1:-}
case "$job" in
  demo|test) ;;
  *) echo "usage: scripts/run.sh demo|test" >&2; exit 2 ;;
esac

python3 - <<'PY' || { echo "drd_planner needs Python 3.10 or newer" >&2; exit 2; }
import sys
raise SystemExit(0 if sys.version_info >= (3, 10) else 1)
PY

venv=${DRD_VENV:-.venv}
if [ ! -x "$venv/bin/python" ]; then
  if ! python3 -m venv "$venv" >/dev/null 2>&1; then
    rm -rf "$venv"
    echo "python3 -m venv is unavailable; installing python3-venv" >&2
    sudo_cmd=""
    [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
    $sudo_cmd apt-get update -qq
    $sudo_cmd apt-get install -y -qq python3-venv
    python3 -m venv "$venv"
  fi
fi
py="$venv/bin/python"
"$py" -m pip install -q --disable-pip-version-check --upgrade pip
# The test job also installs the benchmark peer (OMPL 1.7.0), so the comparisons the docs quote are tested.
extras="plots,test"
[ "$job" = test ] && extras="plots,test,peer"
"$py" -m pip install -q --disable-pip-version-check \
  -e ros2_ws/src/drd_msgs_py -e "ros2_ws/src/drd_planner[$extras]" -r requirements-dev.txt
# Nav2's planner interface (compute_path_to_pose, is_path_valid) needs nav2_msgs: a ROS install's, or the
# two interfaces built into the venv once (about 1-2 minutes; cached, skipped on later runs).
bash scripts/tools/build_nav2_msgs.sh "$venv"
# MoveIt's scene topic and plan_kinematic_path (arm) need moveit_msgs: a ROS install's, or its PlanningScene and
# GetMotionPlan subset built into the venv once (3 small packages, about 2-3.5 minutes on 2 cores; cached).
bash scripts/tools/build_moveit_msgs.sh "$venv"

case "$job" in
  demo)
    "$venv/bin/planner_demo" "${@:2}"
    echo "drd, planner_node, drd_replay and planner_demo are in $venv/bin; to run them by name: . $venv/bin/activate" >&2
    ;;
  test)
    "$venv/bin/ruff" check .
    "$venv/bin/ruff" format --check .
    "$venv/bin/mypy"
    "$venv/bin/sphinx-build" -W --keep-going -q -b html docs build/docs
    "$py" -m pytest -q
    ;;
esac
