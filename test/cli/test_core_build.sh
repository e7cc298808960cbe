#!/usr/bin/env bash
# The ROS-free build (plain CMake, MME_CORE_ONLY=ON) builds the offline tools and they work on
# TRC and C3D: simulate writes a TRC, identify finds the scene's parameters from it, evaluate
# judges the result, convert reads a real C3D capture and writes a TRC; a rosbag is refused with
# exit 2 and a message saying the ROS build reads it. The build directory is the one
# scripts/bench uses (scripts/core_build_dir.sh: outside the repository), so after the quick
# benchmark only the tools are compiled here.
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH   # no ROS in this build's environment
unset CMAKE_PREFIX_PATH ROS_PACKAGE_PATH
# shellcheck disable=SC1091
source "$here/scripts/core_build_dir.sh"
build=$(core_build_dir "$here")
mkdir -p "$build"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT

cmake -S "$here" -B "$build" -DMME_CORE_ONLY=ON -DCMAKE_BUILD_TYPE=Release >"$tmp/configure.log" 2>&1 ||
  { echo "core build: configure failed:"; tail -20 "$tmp/configure.log"; exit 1; }
if grep -qi "catkin\|roscpp" "$build/CMakeCache.txt"; then echo "core build: the cache names ROS"; exit 1; fi
cmake --build "$build" -j"${MME_JOBS:-$(nproc)}" --target simulate identify evaluate convert >"$tmp/build.log" 2>&1 ||
  { echo "core build: build failed:"; grep -E -A5 'error' "$tmp/build.log" | head -30; exit 1; }
bin="$build"
for tool in simulate identify evaluate convert; do
  if ldd "$bin/$tool" | grep -q "libroscpp\|librosbag\|libmme_ros"; then echo "core build: $tool links ROS"; exit 1; fi
done

# TRC: simulated, identified, judged.
"$bin/simulate" --scene paper_object --frames 60 --out "$tmp/data.trc" --truth-out "$tmp/truth.yaml" >/dev/null
sed -E 's/\{value: [^,]*, free: true/{free: true/' "$tmp/truth.yaml" >"$tmp/free.yaml"
"$bin/identify" --sensor-muscles off --model "$tmp/free.yaml" --trajectory "$tmp/data.trc" --out "$tmp/fit.yaml" --quiet >"$tmp/id.log"
grep -q "^identify: wrote a passive model (.*) to $tmp/fit.yaml: " "$tmp/id.log" || { echo "core build: identify wrote nothing"; cat "$tmp/id.log"; exit 1; }
cost=$(sed -n 's/^global cost \([^ ]*\) m^2.*/\1/p' "$tmp/id.log")
awk -v c="$cost" 'BEGIN { exit !(c != "" && c < 1e-12) }' || { echo "core build: cost $cost on noiseless data"; exit 1; }
"$bin/evaluate" --model "$tmp/fit.yaml" --trajectory "$tmp/data.trc" >"$tmp/eval.log"
# The identified model predicts its own noiseless data to round-off, one frame ahead.
awk '$1 == 1 && $2 == "model" { found = 1; ok = $3 < 1e-6 } END { exit !(found && ok) }' "$tmp/eval.log" ||
  { echo "core build: evaluate's one-frame model row:"; cat "$tmp/eval.log"; exit 1; }

# C3D: a real capture read and written as TRC.
"$bin/convert" --trajectory "$here/test/data/real/Sample01_Eb015pi.c3d" --out "$tmp/s01.trc" >"$tmp/conv.log"
[ -s "$tmp/s01.trc" ] || { echo "core build: convert wrote no TRC"; cat "$tmp/conv.log"; exit 1; }

# A bag: refused by name, exit 2, not a crash.
set +e
"$bin/convert" --trajectory "$tmp/s01.trc" --out "$tmp/x.bag" 2>"$tmp/bag.err"; rc=$?
set -e
[ "$rc" -eq 2 ] && grep -q "rosbags need the ROS build" "$tmp/bag.err" ||
  { echo "core build: a bag gave exit $rc:"; cat "$tmp/bag.err"; exit 1; }
echo "test_core_build: ok"
