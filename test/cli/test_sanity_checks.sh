#!/usr/bin/env bash
# Sanity checks in plain words (docs/tools.md "Exit codes and warnings"): a capture in millimetres
# whose header says m is warned of by convert and identify, which still exit 0; simulate warns of
# a --noise-std of centimetres; identify's table has units, "-" for a std not determined (with the
# reason under it) and says when stiffnesses are per kilogram of marker; evaluate warns when a
# guess predicts better than the model; a TRC header that disagrees with its data is warned of;
# a C3D given as --model, an empty model, a marker-name mismatch and an absurd sample are errors
# (exit 2) naming what is wrong.
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
source "$here/scripts/env.sh"
bin="$here/.ws/devel/lib/motion_model_estimation"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

"$bin/simulate" --scene paper_object --frames 60 --out "$tmp/data.trc" --truth-out "$tmp/truth.yaml" >/dev/null
sed -E 's/\{value: [^,]*, free: true/{free: true/' "$tmp/truth.yaml" >"$tmp/free.yaml"

# Millimetre numbers under a header saying m: the markers span hundreds of metres.
awk 'BEGIN { FS = OFS = "\t" } NR == 3 { $5 = "m" } { print }' "$tmp/data.trc" >"$tmp/mm_as_m.trc"
"$bin/convert" --trajectory "$tmp/mm_as_m.trc" --out "$tmp/conv.trc" >/dev/null 2>"$tmp/conv.err" ||
  fail "convert failed on a file in the wrong units: $(cat "$tmp/conv.err")"
grep -q "convert: warning: $tmp/mm_as_m.trc: the markers span [0-9.]* m (median over frames): a human capture spans 0.1-3 m; is the file in millimetres with a header saying m" \
  "$tmp/conv.err" || fail "convert: no units warning: $(cat "$tmp/conv.err")"
"$bin/identify" --sensor-muscles off --model "$tmp/free.yaml" --trajectory "$tmp/mm_as_m.trc" --out "$tmp/mm.yaml" \
  --generations 2 --quiet >/dev/null 2>"$tmp/mm.err" || fail "identify failed: $(cat "$tmp/mm.err")"
grep -q "identify: warning: .*the markers span" "$tmp/mm.err" || fail "identify: no units warning: $(cat "$tmp/mm.err")"
"$bin/convert" --trajectory "$tmp/data.trc" --out "$tmp/conv2.trc" >/dev/null 2>"$tmp/good.err"
[ ! -s "$tmp/good.err" ] || fail "a capture in the right units warned: $(cat "$tmp/good.err")"

# simulate: --noise-std is metres; 0.1 (meant as millimetres) is 10 cm of noise: warned, exit 0.
"$bin/simulate" --scene paper_object --frames 5 --noise-std 0.1 --out "$tmp/noisy.trc" >/dev/null 2>"$tmp/noise.err"
grep -q "simulate: warning: --noise-std 0.1 is in metres (whatever --units): 100 mm of noise per coordinate" \
  "$tmp/noise.err" || fail "simulate: no noise warning: $(cat "$tmp/noise.err")"
"$bin/simulate" --scene paper_object --frames 5 --noise-std 0.0001 --out "$tmp/quiet.trc" >/dev/null 2>"$tmp/quiet.err"
[ ! -s "$tmp/quiet.err" ] || fail "0.1 mm of noise warned: $(cat "$tmp/quiet.err")"

# The table: units per parameter; a bond type no bond uses leaves its parameters undetermined:
# its std is "-" with the reason under the table, not nan; masses of 1 kg: per kilogram.
sed -E 's/mass: [0-9.]+/mass: 1/' "$tmp/free.yaml" >"$tmp/unit_mass.yaml"
printf '  - name: unused\n    kind: spring\n    stiffness: {free: true, min: 1, max: 100}\n' >"$tmp/unused_type"
sed "/^bond_types:/r $tmp/unused_type" "$tmp/unit_mass.yaml" >"$tmp/unused.yaml"
"$bin/identify" --sensor-muscles off --model "$tmp/unused.yaml" --trajectory "$tmp/data.trc" --out "$tmp/unused_out.yaml" \
  --generations 3 --quiet >"$tmp/table.log" 2>"$tmp/table.err" || fail "identify failed: $(cat "$tmp/table.err")"
grep -E -q "^parameter +value +std +unit +flag$" "$tmp/table.log" || fail "no unit column: $(cat "$tmp/table.log")"
grep -E -q "^s00/stiffness +[-0-9.e+]+ +[-0-9.e+]+ +N/m( |$)" "$tmp/table.log" || fail "s00/stiffness without N/m: $(cat "$tmp/table.log")"
grep -E -q "^s00/rest_length +[-0-9.e+]+ +[-0-9.e+]+ +m( |$)" "$tmp/table.log" || fail "rest_length without m"
grep -E -q "^unused/stiffness +[-0-9.e+]+ +- +N/m" "$tmp/table.log" || fail "undetermined std not '-': $(grep unused "$tmp/table.log")"
grep -q "^std '-': not determined: " "$tmp/table.log" || fail "no reason for the '-' std"
if grep -qi "nan" "$tmp/table.log"; then fail "nan in the table: $(grep -i nan "$tmp/table.log")"; fi
grep -q "^masses: 1 kg per marker (not measured): stiffness, damping and gain are per kilogram of marker" \
  "$tmp/table.log" || fail "no per-kilogram line"
"$bin/identify" --sensor-muscles off --model "$tmp/free.yaml" --trajectory "$tmp/data.trc" --out "$tmp/fit.yaml" \
  --generations 2 --quiet >"$tmp/fit.log" 2>/dev/null
if grep -q "^masses:" "$tmp/fit.log"; then fail "per-kilogram line with measured masses"; fi

# evaluate: a model whose rest lengths are all wrong predicts worse than the guesses: warned;
# the truth does not.
"$bin/evaluate" --model "$tmp/truth.yaml" --trajectory "$tmp/data.trc" >/dev/null 2>"$tmp/truth.err"
[ ! -s "$tmp/truth.err" ] || fail "the truth warned: $(cat "$tmp/truth.err")"
sed -E 's/rest_length: \{value: [^,]*/rest_length: {value: 0.5/' "$tmp/truth.yaml" >"$tmp/wrong.yaml"
"$bin/evaluate" --model "$tmp/wrong.yaml" --trajectory "$tmp/data.trc" >"$tmp/wrong.log" 2>"$tmp/wrong.err"
grep -q "evaluate: warning: 10 frame(s) ahead the model (.* mm) predicts worse than a guess that needs no model (constant_velocity .* mm" \
  "$tmp/wrong.err" || fail "evaluate: no losing-model warning: $(cat "$tmp/wrong.err")"

# A TRC header that disagrees with its data: NumMarkers 16 over 15 names; the last marker's
# columns cut from every row.
awk 'BEGIN { FS = OFS = "\t" } NR == 3 { $4 = 16 } { print }' "$tmp/data.trc" >"$tmp/count.trc"
"$bin/convert" --trajectory "$tmp/count.trc" --out "$tmp/c.trc" >/dev/null 2>"$tmp/count.err"
grep -q "convert: warning: $tmp/count.trc: header declares 16 markers (NumMarkers), its names line names 15" \
  "$tmp/count.err" || fail "NumMarkers mismatch not warned: $(cat "$tmp/count.err")"
awk 'BEGIN { FS = OFS = "\t" } NR > 5 && NF > 44 { NF = 44 } { print }' "$tmp/data.trc" >"$tmp/cols.trc"
"$bin/convert" --trajectory "$tmp/cols.trc" --out "$tmp/c.trc" >/dev/null 2>"$tmp/cols.err"
grep -q "the names line names 15 markers but the widest data row holds 42 coordinate fields (14 markers): 'm14' and after are never in the data" \
  "$tmp/cols.err" || fail "missing columns not warned: $(cat "$tmp/cols.err")"

expect_exit2() {  # expect_exit2 TOOL PATTERN ARGS... : exit code 2 and PATTERN in a one-line stderr
  local tool=$1 pattern=$2; shift 2
  set +e; "$bin/$tool" "$@" 2>"$tmp/err" >/dev/null; local rc=$?; set -e
  [ "$rc" -eq 2 ] || fail "expected exit 2, got $rc for: $tool $* ($(cat "$tmp/err"))"
  grep -q -- "$pattern" "$tmp/err" || fail "missing '$pattern' in: $(cat "$tmp/err")"
  [ "$(wc -l <"$tmp/err")" -eq 1 ] || fail "error is not one line: $(cat "$tmp/err")"
}
c3d="$here/test/data/real/Sample26_Walking_Hybrid_1_1.c3d"
expect_exit2 identify "$c3d: this is a C3D file (a capture), not a model file" \
  --model "$c3d" --trajectory "$tmp/data.trc" --out "$tmp/x.yaml"
expect_exit2 identify "$tmp/data.trc: this is a TRC marker file (a capture), not a model file" \
  --model "$tmp/data.trc" --trajectory "$tmp/data.trc" --out "$tmp/x.yaml"
printf 'frame_rate_hz: 100\nparticles: []\n' >"$tmp/empty.yaml"
expect_exit2 identify "$tmp/empty.yaml: the model has no particles: nothing to identify" \
  --model "$tmp/empty.yaml" --trajectory "$tmp/data.trc" --out "$tmp/x.yaml"
expect_exit2 evaluate "$tmp/empty.yaml: the model has no particles" --model "$tmp/empty.yaml" --trajectory "$tmp/data.trc"
# A marker renamed in the file: both sides listed.
awk 'BEGIN { FS = OFS = "\t" } NR == 4 { sub(/^m03$/, "M03", $12) } { print }' "$tmp/data.trc" >"$tmp/renamed.trc"
expect_exit2 identify "marker 'm03' of the model is not in the trajectory (1 missing: m03); the file's markers: m00, m01, m02, M03, m04, .*; the model's particles: m00, m01, m02, m03, m04, " \
  --model "$tmp/free.yaml" --trajectory "$tmp/renamed.trc" --out "$tmp/x.yaml"
# 1e308 mm in line 12 (the 6th row: frame 5), marker m01's y.
awk 'BEGIN { FS = OFS = "\t" } NR == 12 { $7 = "1e308" } { print }' "$tmp/data.trc" >"$tmp/absurd.trc"
expect_exit2 identify "$tmp/absurd.trc:12: frame 5, marker 'm01': coordinate '1e308' is 1e+305 m from the origin" \
  --model "$tmp/free.yaml" --trajectory "$tmp/absurd.trc" --out "$tmp/x.yaml"
[ ! -e "$tmp/x.yaml" ]
echo "test_sanity_checks: ok"
