#!/usr/bin/env bash
# identify: with its defaults (no option) recovers paper_object's 20 parameters from a trajectory
# file and a model without values and stops once converged; writes the same model for any thread
# count; --preset paper runs the paper's schedule; a parameter on a user's bound is flagged in the
# table, on stderr and in the export; a file cut short of its header's frame count is reported
# and its rows used; --select-structure finds paper_object's bonds and types from its particles;
# --grow-segments grows the output error's data in stages; bad options and missing files give
# exit 2.
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
source "$here/scripts/env.sh"
bin="$here/.ws/devel/lib/motion_model_estimation"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT

"$bin/simulate" --scene paper_object --frames 60 --out "$tmp/data.trc" --truth-out "$tmp/truth.yaml"
# The model as identification sees it: free parameters without values.
sed -E 's/\{value: [^,]*, free: true/{free: true/' "$tmp/truth.yaml" >"$tmp/free.yaml"
if grep -q "value:" "$tmp/free.yaml"; then echo "free.yaml still holds values"; exit 1; fi
"$bin/identify" --sensor-muscles off --model "$tmp/free.yaml" --trajectory "$tmp/data.trc" --out "$tmp/one.yaml" \
  >"$tmp/one.log" 2>"$tmp/one.err"
grep -q "preset default (refinement levenberg_marquardt from generation 5, every 5)" "$tmp/one.log"
grep -q "^stopped: converged" "$tmp/one.log"
[ ! -s "$tmp/one.err" ] || { echo "warnings on a whole file: $(cat "$tmp/one.err")"; exit 1; }
"$bin/identify" --sensor-muscles off --model "$tmp/free.yaml" --trajectory "$tmp/data.trc" --out "$tmp/two.yaml" \
  --threads 2 --quiet >/dev/null
# Same seed and input: the same model for 1 and 2 threads (only the recorded wall time differs).
cmp <(grep -v wall_time_s "$tmp/one.yaml") <(grep -v wall_time_s "$tmp/two.yaml")
grep -q wall_time_s "$tmp/one.yaml"
values() { grep -o 'value: [^,}]*' "$1" | awk '{print $2}'; }
[ "$(values "$tmp/truth.yaml" | wc -l)" -eq 20 ]
paste <(values "$tmp/truth.yaml") <(values "$tmp/one.yaml") | awk '
  { e = ($2 - $1) / $1; if (e < 0) e = -e; if (e > worst) worst = e; n++ }
  END { printf "identify: max relative error %.3g over %d parameters\n", worst, n;
        exit !(n == 20 && worst < 1e-6) }'

# The paper's preset: its schedule, and the whole generation budget.
"$bin/identify" --model "$tmp/free.yaml" --trajectory "$tmp/data.trc" --out "$tmp/paper.yaml" \
  --preset paper --generations 3 >"$tmp/paper.log"
grep -q "preset paper (refinement bobyqa from generation 400, every 100)" "$tmp/paper.log"
grep -q "3 generations" "$tmp/paper.log"

# A user's bound below the truth (10.4 N/m): flagged, never crossed.
sed -E '0,/stiffness: \{free: true, min: 1.04, max: 104\}/s//stiffness: {free: true, min: 1.04, max: 8}/' \
  "$tmp/free.yaml" >"$tmp/bounded.yaml"
grep -q "max: 8}" "$tmp/bounded.yaml"
"$bin/identify" --sensor-muscles off --model "$tmp/bounded.yaml" --trajectory "$tmp/data.trc" --out "$tmp/bounded_out.yaml" \
  --quiet >"$tmp/bounded.log" 2>"$tmp/bounded.err"
grep -E -q "^s00/stiffness +8(\.0*)? .*at_upper_bound$" "$tmp/bounded.log"
grep -q "ended within 1 % of a search bound" "$tmp/bounded.err"
grep -q "s00/stiffness: at_upper_bound" "$tmp/bounded_out.yaml"

# A cut-off copy (the header, the blank line and 14 of the 60 rows NumFrames declares): identify
# says so on stderr, naming the file and both counts, and goes on with the 14 frames.
head -n 20 "$tmp/data.trc" >"$tmp/cut.trc"
"$bin/identify" --sensor-muscles off --model "$tmp/free.yaml" --trajectory "$tmp/cut.trc" --out "$tmp/cut.yaml" \
  --generations 2 --quiet >/dev/null 2>"$tmp/cut.err" ||
  { echo "identify failed on the cut-off file: $(cat "$tmp/cut.err")"; exit 1; }
expected="identify: warning: $tmp/cut.trc: header declares 60 frames, found 14 (file cut short?)"
[ "$(cat "$tmp/cut.err")" = "$expected" ] ||
  { echo "expected stderr '$expected', got '$(cat "$tmp/cut.err")'"; exit 1; }
grep -q "frames: 14" "$tmp/cut.yaml" || { echo "cut.yaml does not record 14 frames:"; cat "$tmp/cut.yaml"; exit 1; }

# --select-structure from the particles alone (the model file without bond_types and bonds):
# paper_object's 31 bonds in 10 types, springs only (no damper), the report beside the output,
# then the chosen model identified as usual; the true bonds' pairs are the chosen ones.
"$bin/simulate" --scene paper_object --frames 150 --out "$tmp/long.trc" >/dev/null
sed '/^bond_types:/,$d' "$tmp/truth.yaml" >"$tmp/particles.yaml"
"$bin/identify" --model "$tmp/particles.yaml" --trajectory "$tmp/long.trc" --out "$tmp/sel.yaml" \
  --select-structure --sensor-muscles 16 >"$tmp/sel.log" 2>"$tmp/sel.err" ||
  { echo "identify --select-structure failed:"; cat "$tmp/sel.err"; exit 1; }
grep -q "^springs,31,10,20,.*,1,1,$" "$tmp/sel.yaml.structure.csv" ||
  { echo "structure report:"; cat "$tmp/sel.yaml.structure.csv"; exit 1; }
grep -q "^constant_velocity," "$tmp/sel.yaml.structure.csv"
grep -q "^stopped: converged" "$tmp/sel.log"
bond_pairs() {  # the sorted particle pairs of a model file's bonds
  sed -n 's/.*particles: \[\([a-z0-9_]*\), \([a-z0-9_]*\)\].*/\1 \2/p' "$1" |
    awk '{ if ($1 > $2) print $2, $1; else print $1, $2 }' | sort
}
[ "$(bond_pairs "$tmp/sel.yaml")" = "$(bond_pairs "$tmp/truth.yaml")" ] ||
  { echo "selected bonds differ from the truth's"; diff <(bond_pairs "$tmp/sel.yaml") <(bond_pairs "$tmp/truth.yaml"); exit 1; }
[ "$(grep -c "kind: spring" "$tmp/sel.yaml")" -eq 10 ]
if grep -q "damping:" "$tmp/sel.yaml"; then echo "a damper was selected on springs-only data"; exit 1; fi
# The sensor muscles ran (asked for) and were not kept: the passive model already explains these
# data, and a fit of its residue is not 1 % of the motion's scale better.
grep -q "warning: the sensor muscles are not kept (its validation error .* is not below the passive model's .* by .*, 1 % of the larger" \
  "$tmp/sel.err" || { echo "sensor muscles on controller-free data:"; grep "sensor muscles" "$tmp/sel.log" "$tmp/sel.err"; exit 1; }
# The passive model was written before the sensor muscles' first step, and the closing line says
# which kind the file holds and why.
awk -v out="$tmp/sel.yaml" '
  index($0, "identify: wrote a passive model (15 particles, 31 bonds) to " out "; the sensor muscles replace it") == 1 { written = NR }
  /^identify: sensor muscles: / && !first_step { first_step = NR }
  END { exit !(written && first_step > written) }' "$tmp/sel.log" ||
  { echo "the passive model was not written first:"; grep "wrote\|sensor muscles" "$tmp/sel.log"; exit 1; }
grep -q "^identify: wrote a passive model (15 particles, 31 bonds) to $tmp/sel.yaml: sensor muscles not kept (" "$tmp/sel.log" ||
  { echo "no 'which kind and why' line:"; grep "wrote" "$tmp/sel.log"; exit 1; }

# --grow-segments: the output error on noisy data (0.1 mm) grown from the first 2 segments' frames
# (21, then 41, then all 60 frames: 3 stages), every parameter within 1 % of the truth (the worst
# 0.85 % off, as without growing: the noise's).
"$bin/simulate" --scene paper_object --frames 60 --noise-std 1e-4 --seed 5 --out "$tmp/noisy.trc" >/dev/null
"$bin/identify" --sensor-muscles off --model "$tmp/free.yaml" --trajectory "$tmp/noisy.trc" --out "$tmp/grown.yaml" \
  --cost output_error --grow-segments 2 >"$tmp/grown.log" 2>"$tmp/grown.err" ||
  { echo "identify --grow-segments failed:"; cat "$tmp/grown.err"; exit 1; }
grep -q "output error: 6 segments, .* iterations of the final fit (over 3 stages growing the data, " \
  "$tmp/grown.log" "$tmp/grown.err" || { echo "no grown output error:"; cat "$tmp/grown.log" "$tmp/grown.err"; exit 1; }
paste <(values "$tmp/truth.yaml") <(values "$tmp/grown.yaml") | awk '
  { e = ($2 - $1) / $1; if (e < 0) e = -e; if (e > worst) worst = e; n++ }
  END { printf "identify --grow-segments 2: max relative error %.3g over %d parameters\n", worst, n;
        exit !(n == 20 && worst < 0.01) }'

expect_exit2() {  # expect_exit2 PATTERN ARGS... : exit code 2 and PATTERN in a one-line stderr
  local pattern=$1; shift
  set +e; "$bin/identify" "$@" 2>"$tmp/err" >/dev/null; local rc=$?; set -e
  [ "$rc" -eq 2 ] || { echo "expected exit 2, got $rc for: $*"; cat "$tmp/err"; exit 1; }
  grep -q -- "$pattern" "$tmp/err" || { echo "missing '$pattern' in: $(cat "$tmp/err")"; exit 1; }
  [ "$(wc -l <"$tmp/err")" -eq 1 ] || { echo "error is not one line: $(cat "$tmp/err")"; exit 1; }
}
ok=(--model "$tmp/free.yaml" --trajectory "$tmp/data.trc" --out "$tmp/x.yaml")
expect_exit2 "--refine 'lm' is unknown" "${ok[@]}" --refine lm
expect_exit2 "--preset 'fast' is unknown (available: default or paper)" "${ok[@]}" --preset fast
expect_exit2 "--refine-start" "${ok[@]}" --refine-start -1
expect_exit2 "--refine-period" "${ok[@]}" --refine-period many
expect_exit2 "option --grow-segments must be an integer in \[0, 100000\], got '-1'" "${ok[@]}" --grow-segments -1
expect_exit2 "do not go together" "${ok[@]}" --select-structure --compare-to-model
expect_exit2 "nope.trc" --model "$tmp/free.yaml" --trajectory "$tmp/nope.trc" --out "$tmp/x.yaml"
[ ! -e "$tmp/x.yaml" ]
echo "test_identify: ok"
