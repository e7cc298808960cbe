#!/usr/bin/env bash
# convert: a real capture with gaps through TRC and bag and back, checked against readers that are
# not the package's (a TRC parser and Python's rosbag, below): every position, gap, frame number
# and frame interval kept; a C3D capture's gaps become occluded flags in the bag (Sample26: the
# 3902 samples an independent count found at 0,0,0, see test_c3d); --first-frame/--frames cut a
# piece; --particles-out writes a model identify takes; identify --select-structure runs without
# --model; bad input gives one line naming the file or option, exit 2, and writes nothing.
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
source "$here/scripts/env.sh"
bin="$here/.ws/devel/lib/motion_model_estimation"
real="$here/test/data/real"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT

# A TRC capture with gaps (empty fields): Sample26's gaps written by convert's TRC writer.
"$bin/convert" --trajectory "$real/Sample26_Walking_Hybrid_1_1.c3d" --out "$tmp/s26.trc" >"$tmp/c1.log"
grep -q "672 frames x 25 markers at 240 Hz, times 0 .. 2.79583 s, 3902 of 16800 samples occluded" "$tmp/c1.log"
# TRC -> bag, and the bag -> TRC again.
"$bin/convert" --trajectory "$tmp/s26.trc" --out "$tmp/s26.bag" --out-topic /mocap/markers \
  --frame-id mocap >"$tmp/c2.log"
grep -q "wrote $tmp/s26.bag (topic '/mocap/markers', frame 'mocap')" "$tmp/c2.log"
"$bin/convert" --trajectory "$tmp/s26.bag" --out "$tmp/back.trc" --units m >"$tmp/c3.log"
# The C3D straight to a bag.
"$bin/convert" --trajectory "$real/Sample26_Walking_Hybrid_1_1.c3d" --out "$tmp/direct.bag" >/dev/null

# Independent readers: the TRC files parsed here, the bags with Python's rosbag.
python3 - "$tmp" <<'PY'
import sys, math, rosbag
tmp = sys.argv[1]

def read_trc(path):
    lines = open(path).read().split('\n')
    keys, values = lines[1].split('\t'), lines[2].split('\t')
    meta = dict(zip(keys, values))
    scale = {'mm': 1e-3, 'cm': 1e-2, 'm': 1.0}[meta['Units']]
    names = [n for n in lines[3].split('\t')[2:] if n]
    frames = []
    for line in lines[5:]:
        if not line.strip():
            continue
        f = line.split('\t')
        f += [''] * (2 + 3 * len(names) - len(f))
        pos = []
        for i in range(len(names)):
            xyz = f[2 + 3 * i: 5 + 3 * i]
            pos.append(None if all(v == '' for v in xyz) else tuple(float(v) * scale for v in xyz))
        frames.append((int(f[0]), float(f[1]), pos))
    return float(meta['DataRate']), names, frames

def read_bag(path, topic):
    out = []
    with rosbag.Bag(path) as bag:
        for _, msg, _ in bag.read_messages(topics=[topic]):
            occ = list(msg.occluded) or [False] * len(msg.names)
            pos = [None if o else (p.x, p.y, p.z) for p, o in zip(msg.positions, occ)]
            out.append((msg.frame_number, msg.header.stamp.to_sec(), msg.header.frame_id, list(msg.names), pos))
    return out

def same(a, b, tol):
    return (a is None) == (b is None) and (a is None or max(abs(x - y) for x, y in zip(a, b)) <= tol)

rate, names, trc = read_trc(tmp + '/s26.trc')
assert rate == 240.0 and len(names) == 25 and len(trc) == 672, (rate, len(names), len(trc))
gaps = sum(p is None for f in trc for p in f[2])
assert gaps == 3902, gaps
bag = read_bag(tmp + '/s26.bag', '/mocap/markers')
assert len(bag) == 672, len(bag)
for (n, t, pos), (bn, bt, frame_id, bnames, bpos) in zip(trc, bag):
    assert frame_id == 'mocap' and bnames == names and bn == n, (frame_id, bn, n)
    # Frame times: the same intervals (a bag cannot hold time 0: stamped from 1 s on).
    assert abs((bt - bag[0][1]) - (t - trc[0][1])) < 1e-6, (n, bt, t)
    for i in range(len(names)):
        assert same(pos[i], bpos[i], 1e-12), (n, names[i], pos[i], bpos[i])
rate_m, names_m, back = read_trc(tmp + '/back.trc')
assert rate_m == 240.0 and names_m == names and len(back) == 672
for (n, t, pos), (bn, bt, bpos) in zip(trc, back):
    assert n == bn and abs((bt - back[0][1]) - (t - trc[0][1])) < 1e-6
    for i in range(len(names)):
        assert same(pos[i], bpos[i], 1e-9), (n, names[i], pos[i], bpos[i])
direct = read_bag(tmp + '/direct.bag', 'markers')
assert len(direct) == 672 and sum(p is None for f in direct for p in f[4]) == 3902
for (n, t, pos), d in zip(trc, direct):
    assert abs((d[1] - direct[0][1]) - (t - trc[0][1])) < 1e-9
    for i in range(len(names)):
        assert same(pos[i], d[4][i], 1e-9), (n, names[i])
print('independent readers: 672 frames, 3902 gaps, positions, frame numbers and times kept')
PY

# A piece, and the particles-only model.
"$bin/convert" --trajectory "$real/Sample01_Eb015pi.c3d" --first-frame 100 --frames 50 \
  --out "$tmp/piece.bag" --particles-out "$tmp/particles.yaml" >"$tmp/c4.log"
grep -q "50 frames x 26 markers at 50 Hz, times 2 .. 2.98 s" "$tmp/c4.log"
[ "$(python3 -c "import rosbag; print(rosbag.Bag('$tmp/piece.bag').get_message_count())")" = 50 ]
[ "$(grep -c '{name:' "$tmp/particles.yaml")" = 26 ]
grep -q "frame_rate_hz: 50" "$tmp/particles.yaml"
if grep -q "kind:" "$tmp/particles.yaml"; then echo "FAIL: a bond type in the particles-only model"; exit 1; fi
# identify --select-structure from the markers alone (no --model), on a bag convert made.
"$bin/convert" --trajectory "$real/arm26_elbow_flex.trc" --out "$tmp/arm.bag" >/dev/null
"$bin/identify" --select-structure --trajectory "$tmp/arm.bag" --out "$tmp/arm.yaml" --quiet >"$tmp/id.log"
grep -q "no --model: the 3 markers of $tmp/arm.bag are the particles" "$tmp/id.log"
grep -q "<- chosen" "$tmp/id.log"
grep -q "kind:" "$tmp/arm.yaml"
# Sensor muscles by default (auto): arm26's driven elbow gets them (the gain gate lets them
# through), the report names them and the closing line says which kind was written and why.
grep -q "^identify: sensor muscles: 3 sensors, [0-9]* muscles, .*anchors; 10 frames ahead" "$tmp/id.log" ||
  { echo "no sensor muscles by default:"; grep "sensor muscles" "$tmp/id.log"; exit 1; }
[ "$(grep -c "kind: muscle" "$tmp/arm.yaml")" -gt 0 ] || { echo "arm.yaml has no muscle"; exit 1; }
grep -q "^identify: wrote sensor muscles (3 sensors, .*) to $tmp/arm.yaml: they predict 10 frames ahead in .* mm against .* mm passive" \
  "$tmp/id.log" || { echo "no 'which kind and why' line:"; grep "wrote" "$tmp/id.log"; exit 1; }
grep -q "model_kind: sensor_muscles" "$tmp/arm.yaml"
# Off: the passive model alone.
for off in "--sensor-muscles off" "--sensor-muscles 0" "--preset paper --generations 30"; do
  # shellcheck disable=SC2086
  "$bin/identify" --select-structure --trajectory "$tmp/arm.bag" --out "$tmp/arm_passive.yaml" --quiet $off \
    >"$tmp/id_passive.log"
  grep -q "<- chosen" "$tmp/id_passive.log"
  ! grep -q "^identify: sensor muscles:" "$tmp/id_passive.log" || { echo "$off: sensor muscles fitted"; exit 1; }
  ! grep -q "kind: muscle" "$tmp/arm_passive.yaml" || { echo "$off: a muscle written"; exit 1; }
done
# ... and the particles file identify and the node start from.
"$bin/identify" --sensor-muscles off --select-structure --model "$tmp/particles.yaml" --trajectory "$tmp/piece.bag" \
  --out "$tmp/piece.yaml" --quiet >/dev/null

# Bad input: exit 2, one line naming what is wrong, nothing written.
expect_bad() {  # expect_bad PATTERN ARGS...
  local pattern=$1; shift
  set +e
  "$bin/convert" "$@" >"$tmp/bad.out" 2>"$tmp/bad.err"
  local rc=$?
  set -e
  echo "convert $* -> exit $rc: $(cat "$tmp/bad.err")"
  [ "$rc" -eq 2 ] || { echo "FAIL: expected exit 2, got $rc"; exit 1; }
  [ "$(wc -l <"$tmp/bad.err")" -eq 1 ] || { echo "FAIL: expected one line"; exit 1; }
  grep -q -- "$pattern" "$tmp/bad.err" || { echo "FAIL: no '$pattern'"; exit 1; }
  if [ -e "$tmp/out.bag" ] || [ -e "$tmp/out.trc" ]; then echo "FAIL: something was written"; exit 1; fi
}
printf 'not a c3d file at all, far too short' >"$tmp/garbage.c3d"
printf 'PathFileType\t4\t(X/Y/Z)\tx.trc\nDataRate\n' >"$tmp/cut.trc"
expect_bad "missing.trc: cannot open" --trajectory "$tmp/missing.trc" --out "$tmp/out.bag"
expect_bad "garbage.c3d" --trajectory "$tmp/garbage.c3d" --out "$tmp/out.bag"
expect_bad "cut.trc" --trajectory "$tmp/cut.trc" --out "$tmp/out.bag"
echo "frame,x" >"$tmp/notes.txt"
expect_bad "notes.txt" --trajectory "$tmp/notes.txt" --out "$tmp/out.bag"
expect_bad "out.csv: --out must end in .bag or .trc" --trajectory "$tmp/s26.trc" --out "$tmp/out.csv"
expect_bad "--units is for a TRC output" --trajectory "$tmp/s26.trc" --out "$tmp/out.bag" --units m
expect_bad "--units 'inch' is unknown" --trajectory "$tmp/s26.trc" --out "$tmp/out.trc" --units inch
expect_bad "--out-topic and --frame-id are for a bag output" --trajectory "$tmp/s26.trc" --out "$tmp/out.trc" --frame-id x
expect_bad "--trajectory is required" --out "$tmp/out.bag"
expect_bad "--out is required" --trajectory "$tmp/s26.trc"
expect_bad "--frames" --trajectory "$tmp/s26.trc" --out "$tmp/out.bag" --frames 0
expect_bad "--first-frame" --trajectory "$tmp/s26.trc" --out "$tmp/out.bag" --first-frame 672
expect_bad "topic 'nothing'" --trajectory "$tmp/s26.bag" --topic nothing --out "$tmp/out.trc"
expect_bad "unknown option" --trajectory "$tmp/s26.trc" --out "$tmp/out.bag" --speed 2
expect_bad "cannot write bag" --trajectory "$tmp/s26.trc" --out /nonexistent_dir_mme/out.bag
set +e
"$bin/identify" --trajectory "$tmp/arm.bag" --out "$tmp/x.yaml" 2>"$tmp/id.err"; rc=$?
set -e
[ "$rc" -eq 2 ] && grep -q "\-\-model is required" "$tmp/id.err"
set +e
"$bin/identify" --select-structure --compare-to-model --trajectory "$tmp/arm.bag" --out "$tmp/x.yaml" 2>"$tmp/id.err"; rc=$?
set -e
[ "$rc" -eq 2 ] && grep -q "\-\-compare-to-model needs --model" "$tmp/id.err"
echo "test_convert: ok"
