#!/usr/bin/env bash
# estimator_node refuses bad parameters: the node exits with code 2 and a message naming the
# parameter; with good parameters `rosrun motion_model_estimation estimator_node` runs. Needs a
# ROS master: starts its own roscore on a free port and stops it by its PID. The bad cases run
# the binary by its devel-space path (rosrun's `find -L` over the repository costs about a
# second a call, more on a loaded machine); the good case goes through rosrun, the user's
# command, which must find one estimator_node and not ask which to run (the sanitizer workspace
# of `scripts/test --sanitize` lies outside the repository for that; docs/reliability.md "Tests").
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
expect_exit2 "~preset must be default or paper" _model:="$model" _preset:=fast
expect_exit2 "~cost must be auto, short_term or output_error" _model:="$model" _cost:=robust
expect_exit2 "~update_budget_sec must be > 0" _model:="$model" _update_budget_sec:=0.0
expect_exit2 "~segment_frames must be >= 2" _model:="$model" _segment_frames:=1
expect_exit2 "~grow_segments must be >= 0 (0 = off)" _model:="$model" _grow_segments:=-1
expect_exit2 "~prediction_period_sec must be >= 0" _model:="$model" _prediction_period_sec:=-1.0
expect_exit2 "~min_frames" _model:="$model" _window_frames:=20 _min_frames:=50
expect_exit2 "missing_model.yaml" _model:="$tmp/missing_model.yaml"
printf 'particles:\n  - {name: a, mass: -1}\n' >"$tmp/bad_model.yaml"
expect_exit2 "bad_model.yaml" _model:="$tmp/bad_model.yaml"

# Good parameters: the node starts and keeps running until stopped. Its start-up line is awaited
# (rosrun's search alone can take seconds on a loaded machine), then it must still run 2 s later;
# SIGINT (rosrun execs the node, so the PID is the node's) lets it shut down cleanly, and
# line-buffered output keeps its start-up line. stdin from /dev/null: were rosrun to find two
# copies, its "please pick one" menu would read end of file and the node would not start.
export ROSCONSOLE_STDOUT_LINE_BUFFERED=1
started="20 free parameters, window 100 frames, population 60"
rosrun motion_model_estimation estimator_node __name:=good _model:="$model" \
  _window_frames:=100 _population:=60 _grow_segments:=2 </dev/null >"$tmp/out" 2>&1 &
good=$!
for _ in $(seq 300); do
  grep -q "$started" "$tmp/out" && break
  kill -0 "$good" 2>/dev/null || break
  sleep 0.1
done
grep -q "$started" "$tmp/out" ||
  { kill "$good" 2>/dev/null || true; echo "good parameters: no start-up line within 30 s: $(cat "$tmp/out")"; exit 1; }
sleep 2
kill -0 "$good" 2>/dev/null ||
  { echo "good parameters: the node did not keep running: $(cat "$tmp/out")"; exit 1; }
kill -INT "$good"
wait "$good" || true
echo "estimator_node params CLI ok"
