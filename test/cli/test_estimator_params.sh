#!/usr/bin/env bash
# estimator_node refuses bad parameters: the node exits with code 2 and a message naming the
# parameter; with good parameters it runs. Needs a ROS master: starts its own roscore on a free
# port and stops it by its PID. The binary is run by its devel-space path, not through rosrun:
# the package directory is the repository, so rosrun's search also finds the copies in other
# workspaces inside it (.ws/asan of `scripts/test --sanitize`) and asks which one to run.
# MME_DEVEL=<catkin devel space> tests another workspace than the repository's .ws.
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH   # pyenv's python breaks the ROS CLIs
devel=${MME_DEVEL:-$here/.ws/devel}
node="$devel/lib/motion_model_estimation/estimator_node"
# shellcheck disable=SC1091
set +u; source "$devel/setup.bash"; set -u
model="$here/config/models/paper_object.yaml"
# shellcheck disable=SC1091
source "$here/scripts/free_port.sh"
port=$(free_port test_estimator_params) || exit 1
tmp=$(mktemp -d)
export ROS_HOME="$tmp/ros_home"   # logs of roscore and the nodes stay in the temp dir
export ROS_MASTER_URI="http://localhost:$port"
roscore -p "$port" >"$tmp/roscore.log" 2>&1 &
core=$!
cleanup() { kill "$core" 2>/dev/null || true; wait "$core" 2>/dev/null || true; rm -rf "$tmp"; }
trap cleanup EXIT
for _ in $(seq 150); do rosparam get /rosdistro >/dev/null 2>&1 && break; sleep 0.1; done
rosparam get /rosdistro >/dev/null || { echo "roscore did not come up"; cat "$tmp/roscore.log"; exit 1; }

n=0
expect_exit2() {  # expect_exit2 PATTERN ARGS... : exit code 2 and PATTERN in the output
  local pattern=$1; shift
  n=$((n + 1))
  # A node name of its own per run: private params set by `_name:=` stay on the master.
  set +e; timeout 30 "$node" __name:="bad_$n" "$@" \
    >"$tmp/out" 2>&1; local rc=$?; set -e
  [ "$rc" -eq 2 ] || { echo "expected exit 2, got $rc for: $*"; cat "$tmp/out"; exit 1; }
  grep -q -- "$pattern" "$tmp/out" || { echo "missing '$pattern' in: $(cat "$tmp/out")"; exit 1; }
  grep -q "FATAL" "$tmp/out" || { echo "no ROS_FATAL for: $*: $(cat "$tmp/out")"; exit 1; }
  echo "ok: exit 2, '$pattern' for: $*"
}
expect_exit2 "~model is required"
expect_exit2 "~window_frames must be >= 3" _model:="$model" _window_frames:=1
expect_exit2 "~population has the wrong type" _model:="$model" _population:=many
expect_exit2 "~population must be >= 2" _model:="$model" _population:=1
expect_exit2 "~input_type must be" _model:="$model" _input_type:=kinect
expect_exit2 "~update_rate_hz" _model:="$model" _update_rate_hz:=0
expect_exit2 "~threads" _model:="$model" _threads:=0
expect_exit2 "~refine_algorithm must be" _model:="$model" _refine_algorithm:=powell
expect_exit2 "~min_frames" _model:="$model" _window_frames:=20 _min_frames:=50
expect_exit2 "missing_model.yaml" _model:="$tmp/missing_model.yaml"
printf 'particles:\n  - {name: a, mass: -1}\n' >"$tmp/bad_model.yaml"
expect_exit2 "bad_model.yaml" _model:="$tmp/bad_model.yaml"

# Good parameters: the node starts and keeps running until stopped (exit 124 from timeout;
# SIGINT lets it shut down cleanly, line-buffered output keeps its start-up line).
export ROSCONSOLE_STDOUT_LINE_BUFFERED=1
set +e; timeout -s INT 8 "$node" __name:=good _model:="$model" \
  _window_frames:=100 _population:=60 >"$tmp/out" 2>&1; rc=$?; set -e
[ "$rc" -eq 124 ] || { echo "good parameters: expected to run until stopped, exit $rc"; cat "$tmp/out"; exit 1; }
grep -q "20 free parameters, window 100 frames, population 60" "$tmp/out" ||
  { echo "good parameters: no start-up line: $(cat "$tmp/out")"; exit 1; }
echo "estimator_node params CLI ok"
