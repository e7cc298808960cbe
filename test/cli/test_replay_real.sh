#!/usr/bin/env bash
# A piece of a real capture with gaps (Sample26 frames 100-579, 2 s at 240 Hz, 954 of its 12000 samples 0,0,0)
# through scripts/replay-real: identify --select-structure chooses a model from the markers alone,
# convert makes the piece a bag, estimator_node replays it at the capture's rate with that model.
# Checked here, not only by the script: every frame accepted, ~stats' occluded count equal to
# the gaps counted in the piece by a parser of this test (the sensor muscles' anchors, fixed
# particles without markers, when written, are no hidden markers: the script checks that ~stats
# counts them apart, as model_only), nothing rejected, the replay not faster
# than the capture, the node alive to the end and no error in its log; --anchor-stiffness 0 reaches
# identify (its report says the anchor muscles have no stiffness of their own), a bad value exits 2.
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
source "$here/scripts/env.sh"
bin="$here/.ws/devel/lib/motion_model_estimation"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/data"
"$bin/convert" --trajectory "$here/test/data/real/Sample26_Walking_Hybrid_1_1.c3d" \
  --first-frame 100 --frames 480 --out "$tmp/data/sample26_piece.trc" >/dev/null
# The gaps, counted from the TRC text: a marker whose three fields are empty.
gaps=$(python3 - "$tmp/data/sample26_piece.trc" <<'PY'
import sys
lines = open(sys.argv[1]).read().split('\n')
names = [n for n in lines[3].split('\t')[2:] if n]
gaps = 0
for line in lines[5:]:
    if line.strip():
        f = line.split('\t') + [''] * (3 * len(names))
        gaps += sum(all(v == '' for v in f[2 + 3 * i: 5 + 3 * i]) for i in range(len(names)))
print(gaps)
PY
)
echo "the piece: 480 frames, $gaps occluded samples"
[ "$gaps" -gt 500 ]  # a piece with many gaps, or the test proves little

# A bad --anchor-stiffness is refused before any work (exit 2, the option named).
set +e
"$here/scripts/replay-real" --data "$tmp/data" --work "$tmp/work" --no-setup --anchor-stiffness yes \
  >"$tmp/bad.log" 2>&1
rc=$?
set -e
[ "$rc" -eq 2 ] && grep -q "anchor-stiffness must be 1, 0 or auto, got 'yes'" "$tmp/bad.log" ||
  { echo "FAIL: --anchor-stiffness yes gave exit $rc"; cat "$tmp/bad.log"; exit 1; }
[ ! -e "$tmp/work/summary.csv" ]

# The anchor muscles' own stiffness held at 0 (passed through to identify; checked below).
set +e
"$here/scripts/replay-real" --data "$tmp/data" --work "$tmp/work" --identify-max-s 30 --no-setup \
  --anchor-stiffness 0 >"$tmp/replay.log" 2>&1
rc=$?
set -e
cat "$tmp/replay.log"
[ "$rc" -eq 0 ] || { echo "FAIL: replay-real exited $rc"; tail -30 "$tmp/work/sample26_piece.replay.log"; exit 1; }
row=$(grep '^sample26_piece.trc,' "$tmp/work/summary.csv")
IFS=, read -r _ markers frames rate occluded chosen bonds _ _ _ _ _ _ accepted rejected seen span _ muscles sensor_mm sensor_passive_mm check <<<"$row"
echo "summary: markers $markers frames $frames rate $rate occluded $occluded chosen $chosen bonds $bonds accepted $accepted rejected $rejected occluded seen $seen span $span s check $check"
[ "$markers" = 25 ] && [ "$frames" = 480 ] && [ "$rate" = 240 ]
[ "$occluded" = "$gaps" ] || { echo "FAIL: convert counted $occluded gaps, the text has $gaps"; exit 1; }
[ "$accepted" = 480 ] || { echo "FAIL: the node accepted $accepted of 480 frames"; exit 1; }
# Model particles without a marker (sensor muscles' anchors, when written) are not occluded.
anchors=$(grep -c "{name: anchor_[xyz]," "$tmp/work/sample26_piece.yaml" || true)
[ "$seen" = "$gaps" ] ||
  { echo "FAIL: ~stats counted $seen occluded samples, the piece has $gaps (and $anchors anchors, no markers)"; exit 1; }
[ "$rejected" = 0 ] || { echo "FAIL: $rejected frames rejected"; exit 1; }
[ "$bonds" -gt 0 ] || { echo "FAIL: no bond chosen"; exit 1; }
# Sensor muscles were fitted and judged (written or not, by identify's own check).
[[ "$muscles" =~ ^[0-9]+$ ]] && [[ "$sensor_mm" =~ ^[0-9.]+$ ]] && [[ "$sensor_passive_mm" =~ ^[0-9.]+$ ]] ||
  { echo "FAIL: no sensor-muscle figures ($muscles, $sensor_mm, $sensor_passive_mm)"; exit 1; }
if [ "$muscles" -gt 0 ]; then
  awk -v m="$sensor_mm" -v p="$sensor_passive_mm" 'BEGIN { exit !(m < p) }' ||
    { echo "FAIL: sensor muscles written although $sensor_mm mm >= passive $sensor_passive_mm mm"; exit 1; }
  [ "$(grep -c "kind: muscle" "$tmp/work/sample26_piece.yaml")" -eq "$muscles" ]
  # The anchors exactly when identify says it kept them (--muscle-anchors auto, the default).
  want=0
  grep -q "^identify: sensor muscles: .*, with anchors;" "$tmp/work/sample26_piece.identify.log" && want=3
  [ "$anchors" -eq "$want" ] || { echo "FAIL: $anchors anchors in the written model, $want reported"; exit 1; }
  # With anchors, identify held their own stiffness at 0 as replay-real was asked.
  [ "$want" -eq 0 ] || grep -q "; the anchor muscles without a stiffness of their own" "$tmp/work/sample26_piece.identify.log" ||
    { echo "FAIL: --anchor-stiffness 0 did not reach identify"; grep "sensor muscles" "$tmp/work/sample26_piece.identify.log"; exit 1; }
else
  [ "$anchors" -eq 0 ]
fi
# 480 frames at 240 Hz: 479 intervals take 2.0 s at the capture's rate.
awk -v s="$span" 'BEGIN { exit !(s >= 1.98 && s < 30) }' || { echo "FAIL: replayed in $span s"; exit 1; }
[ "$check" = ok ]
grep -q "replaying 480 frames" "$tmp/work/sample26_piece.replay.log"
! grep -E "FATAL|ERROR|exit code|has died" "$tmp/work/sample26_piece.replay.log" ||
  { echo "FAIL: errors in the node's log"; exit 1; }
echo "test_replay_real: ok"
