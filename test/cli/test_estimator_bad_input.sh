#!/usr/bin/env bash
# estimator_node against bad parameters, bad live frames and bad service paths
# (docs/reliability.md). Starts its own roscore on a free port.
# 1. Absurd or missing parameters and a broken model file: the node stops at once with exit 2
#    and ROS_FATAL naming the parameter or the file and line.
# 2. Live frames of the wrong type, with arrays of unequal length or only unknown names are
#    skipped and counted in ~stats; the node keeps running.
# 3. ~export_model and ~load_model stay inside ~model_dir: "..", absolute paths elsewhere,
#    symlinks out (a directory or a file) and a missing directory are refused with success
#    false and a message, nothing is written outside; paths inside (relative, absolute) work;
#    a bad model file inside is refused with the loader's message and the node keeps running.
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
source "$here/scripts/env.sh"
bin="$here/.ws/devel/lib/motion_model_estimation"
tmp=$(mktemp -d)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  for p in "${pids[@]}"; do wait "$p" 2>/dev/null || true; done
  rm -rf "$tmp"
}
trap cleanup EXIT

# shellcheck disable=SC1091
source "$here/scripts/free_port.sh"
port=$(free_port test_estimator_bad_input) || exit 1
export ROS_MASTER_URI=http://127.0.0.1:$port ROS_HOME="$tmp/ros_home"
roscore -p "$port" >"$tmp/roscore.log" 2>&1 &
pids+=($!)
for _ in $(seq 100); do rosparam get /rosdistro >/dev/null 2>&1 && break; sleep 0.2; done
rosparam get /rosdistro >/dev/null

# 1. Absurd parameters: exit 2 within seconds, the reason names the parameter.
expect_fatal() {  # expect_fatal PATTERN PARAMS...
  local pattern=$1; shift
  set +e
  timeout 20 "$bin/estimator_node" __name:=bad_params "$@" >"$tmp/fatal.log" 2>&1
  local rc=$?
  set -e
  echo "estimator_node $* -> exit $rc: $(grep -o 'estimator_node: .*' "$tmp/fatal.log" | head -1 | sed 's/\x1b\[[0-9;]*m//g' | cut -c1-150)"
  [ "$rc" -eq 2 ] || { echo "FAIL: expected exit 2, got $rc"; cat "$tmp/fatal.log"; exit 1; }
  grep -q -- "$pattern" "$tmp/fatal.log" || { echo "FAIL: no '$pattern' in the log"; cat "$tmp/fatal.log"; exit 1; }
  rosparam delete /bad_params >/dev/null 2>&1 || true
}
model="$here/config/models/paper_object.yaml"
printf 'particles:\n  - {name: a, mass: -1}\n' >"$tmp/broken.yaml"
expect_fatal "~model is required"
expect_fatal "window_frames" _model:="$model" _window_frames:=1
expect_fatal "population" _model:="$model" _population:=-5
expect_fatal "update_rate_hz" _model:="$model" _update_rate_hz:=0.0
expect_fatal "autosave_period_sec" _model:="$model" _autosave_period_sec:=-1.0
expect_fatal "input_type" _model:="$model" _input_type:=laser
expect_fatal "threads" _model:="$model" _threads:=100000
expect_fatal "window_frames" _model:="$model" _window_frames:=lots
expect_fatal "broken.yaml:2" _model:="$tmp/broken.yaml"
expect_fatal "missing.yaml" _model:="$tmp/missing.yaml"

models="$tmp/models" outside="$tmp/outside"
mkdir -p "$models" "$outside"
cp "$here/config/models/paper_object.yaml" "$outside/elsewhere.yaml"
ln -s "$outside" "$models/link_dir"                       # a directory symlink leading out
ln -s "$outside/elsewhere.yaml" "$models/link_file.yaml"  # a file symlink leading out
"$bin/estimator_node" __name:=estimator _model:="$here/config/models/paper_object.yaml" \
  _model_dir:="$models" >"$tmp/estimator.log" 2>&1 &
pids+=($!)
for _ in $(seq 100); do grep -q /estimator/load_model <<<"$(rosservice list 2>/dev/null || true)" && break; sleep 0.2; done

call() {  # call SERVICE PATH -> prints the response
  rosservice call "/estimator/$1" "path: '$2'" 2>&1
}
expect_refused() {  # expect_refused SERVICE PATH PATTERN
  local out; out=$(call "$1" "$2")
  echo "$1 '$2' -> $(echo "$out" | tr '\n' ' ' | cut -c1-200)"
  grep -q "success: False" <<<"$out" || { echo "FAIL: $1 '$2' was not refused"; exit 1; }
  grep -q "$3" <<<"$out" || { echo "FAIL: message lacks '$3'"; exit 1; }
}
expect_ok() {  # expect_ok SERVICE PATH
  local out; out=$(call "$1" "$2")
  echo "$1 '$2' -> $(echo "$out" | grep -E 'success|message' | tr '\n' ' ' | cut -c1-200)"
  grep -q "success: True" <<<"$out" || { echo "FAIL: $1 '$2' was refused"; exit 1; }
}

# 2. Live frames the node must survive: a topic of the wrong type (roscpp drops the
#    connection), arrays of unequal length and only unknown marker names (skipped and counted).
timeout 4 rostopic pub -r 20 /markers std_msgs/String "data: not markers" >/dev/null 2>&1 || true
rostopic pub -1 /markers motion_model_estimation/MarkerFrame \
  "{names: [m00, m01], positions: [{x: 0.1, y: 0.2, z: 0.3}]}" >/dev/null
rostopic pub -1 /markers motion_model_estimation/MarkerFrame \
  "{names: [nobody], positions: [{x: 0.1, y: 0.2, z: 0.3}]}" >/dev/null
sleep 1.5
stats=$(rostopic echo -n 1 /estimator/stats)
echo "after a wrong type and two bad frames: $stats"
grep -q "accepted=0 rejected=2 " <<<"$stats" || { echo "FAIL: unexpected ~stats"; exit 1; }
kill -0 "${pids[1]}" || { echo "FAIL: estimator_node died"; cat "$tmp/estimator.log"; exit 1; }

# 3. Service paths confined to ~model_dir.
before=$(ls -A "$outside" | sort | tr '\n' ' ')
expect_refused export_model "../escape.yaml" "outside the model directory"
expect_refused export_model "$outside/abs.yaml" "outside the model directory"
expect_refused export_model "/etc/mme_should_not_exist.yaml" "outside the model directory"
expect_refused export_model "link_dir/through_link.yaml" "outside the model directory"
expect_refused export_model "link_file.yaml" "symlink"
expect_refused export_model "no_such_dir/x.yaml" "does not exist"
expect_refused export_model "sub/../../escape2.yaml" "outside\|does not exist"
expect_refused load_model "../outside/elsewhere.yaml" "outside the model directory"
expect_refused load_model "$outside/elsewhere.yaml" "outside the model directory"
expect_refused load_model "link_file.yaml" "outside the model directory"
expect_refused load_model "link_dir/elsewhere.yaml" "outside the model directory"
expect_refused load_model "missing.yaml" "does not exist"
[ "$(ls -A "$outside" | sort | tr '\n' ' ')" = "$before" ] || { echo "FAIL: a file appeared outside"; ls -la "$outside"; exit 1; }
[ ! -e /etc/mme_should_not_exist.yaml ]

expect_ok export_model "inside.yaml"
[ -s "$models/inside.yaml" ]
expect_ok export_model "$models/absolute_inside.yaml"
[ -s "$models/absolute_inside.yaml" ]
expect_ok load_model "inside.yaml"
expect_ok load_model "$models/absolute_inside.yaml"
# A bad model inside the directory: refused with the loader's message, the node keeps running.
printf 'particles:\n  - {name: a, mass: -1}\n' >"$models/bad.yaml"
expect_refused load_model "bad.yaml" "bad.yaml:2"
kill -0 "${pids[1]}" || { echo "FAIL: estimator_node died"; cat "$tmp/estimator.log"; exit 1; }
echo "estimator bad input ok"
