#!/usr/bin/env bash
# replay.launch shows an identified model as it is: with initial_model:=FILE (here an identified
# model with an anchor, a fixed particle without a marker) and estimate:=false, over model:= a
# file without values, the node replays a capture (a .trc file given as bag:=, read directly)
# and never changes the values: ~export_model gives
# exactly FILE's values, ~markers draws the model's prediction, and ~stats counts the anchor's
# samples as model_only, not as occluded markers (the capture has no gap). Needs a ROS master:
# starts its own roscore on a free port and stops it by its PID.
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH   # pyenv's python breaks the ROS CLIs
bin="$here/.ws/devel/lib/motion_model_estimation"
# shellcheck disable=SC1091
set +u; source "$here/.ws/devel/setup.bash"; set -u
# shellcheck disable=SC1091
source "$here/scripts/free_port.sh"
port=$(free_port test_replay_model) || exit 1
tmp=$(mktemp -d)
export ROS_HOME="$tmp/ros_home"   # logs, and the node's ~model_dir (the export below)
mkdir -p "$ROS_HOME"
export ROS_MASTER_URI="http://localhost:$port"
roscore -p "$port" >"$tmp/roscore.log" 2>&1 &
core=$!
launch=""
cleanup() {
  [ -z "$launch" ] || { kill -INT "$launch" 2>/dev/null || true; wait "$launch" 2>/dev/null || true; }
  kill "$core" 2>/dev/null || true; wait "$core" 2>/dev/null || true; rm -rf "$tmp"
}
trap cleanup EXIT

"$bin/simulate" --scene paper_object --frames 150 --out "$tmp/data.trc" --truth-out "$tmp/truth.yaml" >/dev/null
# The identified model: the truth's values, and an anchor the capture has no marker for.
sed 's/^particles:$/particles:\n  - {name: anchor, mass: 1, position: [0, 0, -5], fixed: true}/' \
  "$tmp/truth.yaml" >"$tmp/identified.yaml"
grep -q "name: anchor" "$tmp/identified.yaml"
sed -E 's/\{value: [^,]*, free: true/{free: true/' "$tmp/truth.yaml" >"$tmp/free.yaml"

for _ in $(seq 150); do rosparam get /rosdistro >/dev/null 2>&1 && break; sleep 0.1; done
rosparam get /rosdistro >/dev/null || { echo "roscore did not come up"; cat "$tmp/roscore.log"; exit 1; }

export ROSCONSOLE_STDOUT_LINE_BUFFERED=1
roslaunch motion_model_estimation replay.launch model:="$tmp/free.yaml" bag:="$tmp/data.trc" \
  initial_model:="$tmp/identified.yaml" estimate:=false </dev/null >"$tmp/launch.log" 2>&1 &
launch=$!
for _ in $(seq 1200); do
  grep -q "bag replay finished" "$tmp/launch.log" && break
  kill -0 "$launch" 2>/dev/null || break
  sleep 0.1
done
grep -q "bag replay finished" "$tmp/launch.log" ||
  { echo "the replay did not finish within 120 s:"; cat "$tmp/launch.log"; exit 1; }
grep -q "is shown as it is" "$tmp/launch.log" || { echo "no 'shown as it is' line:"; cat "$tmp/launch.log"; exit 1; }
grep -q "replaying 150 frames of $tmp/data.trc" "$tmp/launch.log" || { echo "the .trc file was not replayed:"; cat "$tmp/launch.log"; exit 1; }

# The values shown are the file's, every one unchanged (same writer, same digits).
timeout 60 rosservice call /estimator/export_model "path: 'shown.yaml'" >"$tmp/export.log"
grep -q "success: True" "$tmp/export.log" || { echo "export failed:"; cat "$tmp/export.log"; exit 1; }
values() { grep -o '{value: [^,]*, free: true' "$1"; }
[ "$(values "$tmp/identified.yaml" | wc -l)" -eq 20 ]
diff <(values "$tmp/identified.yaml") <(values "$ROS_HOME/shown.yaml") ||
  { echo "the shown model's values changed"; exit 1; }

# ~markers draws the model's one-step prediction on the replayed frames.
timeout 30 rostopic echo -n 1 /estimator/markers >"$tmp/markers.log" || true
grep -q 'ns: "predicted"' "$tmp/markers.log" || { echo "no predicted markers:"; head -40 "$tmp/markers.log"; exit 1; }

# ~stats: every frame accepted; the anchor is no hidden marker (the capture has no gap).
timeout 30 rostopic echo -n 1 /estimator/stats >"$tmp/stats.log" || true
grep -q "accepted=150 rejected=0 occluded=0 model_only=150 " "$tmp/stats.log" ||
  { echo "unexpected ~stats:"; cat "$tmp/stats.log"; exit 1; }
echo "ok: initial_model shown as it is (20 values unchanged), predicted markers, occluded=0 model_only=150"
