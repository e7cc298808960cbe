#!/usr/bin/env bash
# evaluate: the identified paper_object predicts held-out frames (not the ones it was identified
# on) better than the three model-free guesses at 1, 5 and 10 frames; the CSV has the columns
# horizon,predictor,rms_m and one row per horizon and predictor; a marker hidden through the
# judged frames is placed from --history frames; a fixed particle needs no marker (and is not
# counted as one), a free one does; bad options give exit 2.
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
source "$here/scripts/env.sh"
bin="$here/.ws/devel/lib/motion_model_estimation"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT

"$bin/simulate" --scene paper_object --frames 160 --out "$tmp/data.trc" --noise-std 1e-5 \
  --truth-out "$tmp/truth.yaml" >/dev/null
sed -E 's/\{value: [^,]*, free: true/{free: true/' "$tmp/truth.yaml" >"$tmp/free.yaml"
"$bin/identify" --sensor-muscles off --model "$tmp/free.yaml" --trajectory "$tmp/data.trc" --frames 100 \
  --out "$tmp/identified.yaml" --quiet >/dev/null 2>&1
"$bin/evaluate" --model "$tmp/identified.yaml" --trajectory "$tmp/data.trc" --first-frame 100 \
  --csv "$tmp/out.csv" >"$tmp/out.log"
head -1 "$tmp/out.csv" | grep -qx "horizon,predictor,rms_m"
[ "$(tail -n +2 "$tmp/out.csv" | wc -l)" -eq 12 ]
grep -q "rollout of 600 frames from the first start: bounded" "$tmp/out.log"
rms() { awk -F, -v h="$1" -v p="$2" '$1 == h && $2 == p { print $3 }' "$tmp/out.csv"; }
for h in 1 5 10; do
  for guess in constant_velocity constant_acceleration gravity_only; do
    awk -v m="$(rms "$h" model)" -v g="$(rms "$h" "$guess")" 'BEGIN { exit !(m < g) }' ||
      { echo "horizon $h: model $(rms "$h" model) not below $guess $(rms "$h" "$guess")"; cat "$tmp/out.csv"; exit 1; }
  done
done

# A marker hidden from frame 100 on: nothing to judge from on frames 100.. alone; with 20 frames
# of history before them, it is placed by its neighbours' rigid motion at every start.
awk -F'\t' 'BEGIN { OFS = "\t" } NR > 5 && $1 + 0 >= 100 { $3 = ""; $4 = ""; $5 = "" } { print }' \
  "$tmp/data.trc" >"$tmp/gap.trc"
"$bin/evaluate" --model "$tmp/identified.yaml" --trajectory "$tmp/gap.trc" --first-frame 100 \
  --history 20 >"$tmp/gap.log"
grep -q "80 frames x 15 markers at 100 Hz (20 of them history), 59 prediction starts (59 particle starts filled" "$tmp/gap.log" ||
  { echo "history: unexpected"; cat "$tmp/gap.log"; exit 1; }

# A fixed particle needs no marker (it stays where the model holds it: sensor muscles' anchors);
# with nothing bonded to it the figures are the same. A free particle without one is an error.
sed 's/^particles:$/particles:\n  - {name: ground, mass: 1, position: [0, 0, -5], fixed: true}/' \
  "$tmp/identified.yaml" >"$tmp/anchored.yaml"
grep -q "name: ground" "$tmp/anchored.yaml"
"$bin/evaluate" --model "$tmp/anchored.yaml" --trajectory "$tmp/data.trc" --first-frame 100 \
  --csv "$tmp/anchored.csv" >"$tmp/anchored.log"
cmp "$tmp/out.csv" "$tmp/anchored.csv" || { echo "a markerless fixed particle changed the figures"; exit 1; }
# ... and it is no marker of the capture: still 15 markers, the anchor said apart.
grep -q "x 15 markers (and 1 fixed particle(s) of the model without a marker, e.g. anchors) at 100 Hz" \
  "$tmp/anchored.log" || { echo "anchor counted as a marker:"; cat "$tmp/anchored.log"; exit 1; }
sed 's/^particles:$/particles:\n  - {name: ghost, mass: 1, position: [0, 0, -5], fixed: false}/' \
  "$tmp/identified.yaml" >"$tmp/ghost.yaml"

expect_exit2() {  # expect_exit2 PATTERN ARGS...
  local pattern=$1; shift
  set +e; "$bin/evaluate" "$@" 2>"$tmp/err" >/dev/null; local rc=$?; set -e
  [ "$rc" -eq 2 ] || { echo "expected exit 2, got $rc for: $*"; cat "$tmp/err"; exit 1; }
  grep -q -- "$pattern" "$tmp/err" || { echo "missing '$pattern' in: $(cat "$tmp/err")"; exit 1; }
}
expect_exit2 "has no value (evaluate needs an identified model" --model "$tmp/free.yaml" --trajectory "$tmp/data.trc"
expect_exit2 "--horizons: '0'" --model "$tmp/identified.yaml" --trajectory "$tmp/data.trc" --horizons 1,0
expect_exit2 "--trajectory is required" --model "$tmp/identified.yaml"
expect_exit2 "nothing to predict from (--history H" --model "$tmp/identified.yaml" --trajectory "$tmp/gap.trc" --first-frame 100
expect_exit2 "option --history must be an integer" --model "$tmp/identified.yaml" --trajectory "$tmp/gap.trc" --history -1
expect_exit2 "nope.trc" --model "$tmp/identified.yaml" --trajectory "$tmp/nope.trc"
expect_exit2 "marker 'ghost' of the model is not in the trajectory" --model "$tmp/ghost.yaml" --trajectory "$tmp/data.trc"
echo "test_evaluate: ok"
