#!/usr/bin/env bash
# simulate: writes TRC and bag, is deterministic for a seed, and refuses bad input with exit 2.
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
source "$here/scripts/env.sh"
sim="$here/.ws/devel/lib/motion_model_estimation/simulate"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT

"$sim" --scene paper_object --frames 40 --out "$tmp/a.trc" --noise-std 0.001 --seed 7 \
  --truth-out "$tmp/truth.yaml"
"$sim" --scene paper_object --frames 40 --out "$tmp/b.trc" --noise-std 0.001 --seed 7
"$sim" --scene paper_object --frames 40 --out "$tmp/c.trc" --noise-std 0.001 --seed 8
body() { tail -n +2 "$1"; }                        # line 1 names the file itself
cmp <(body "$tmp/a.trc") <(body "$tmp/b.trc")      # same seed: same bytes
if cmp -s <(body "$tmp/a.trc") <(body "$tmp/c.trc"); then echo "another seed gave the same noise"; exit 1; fi
grep -q "NumFrames" "$tmp/a.trc"
[ "$(awk 'NR==3{print $4}' "$tmp/a.trc")" = "15" ]   # NumMarkers
[ "$(awk 'NR==3{print $3}' "$tmp/a.trc")" = "40" ]   # NumFrames
grep -q "s00/stiffness\|s00:" "$tmp/truth.yaml" || grep -q "name: s00" "$tmp/truth.yaml"
# The truth export is a model file: simulating from it gives the same noiseless trajectory.
"$sim" --scene paper_object --frames 40 --out "$tmp/d.trc"
"$sim" --model "$tmp/truth.yaml" --frames 40 --out "$tmp/e.trc"
cmp <(body "$tmp/d.trc") <(body "$tmp/e.trc")
"$sim" --scene paper_object --frames 10 --out "$tmp/a.bag"
[ -s "$tmp/a.bag" ]

expect_exit2() {  # expect_exit2 PATTERN ARGS... : exit code 2 and PATTERN in stderr
  local pattern=$1; shift
  set +e; "$sim" "$@" 2>"$tmp/err"; local rc=$?; set -e
  [ "$rc" -eq 2 ] || { echo "expected exit 2, got $rc for: $*"; cat "$tmp/err"; exit 1; }
  grep -q -- "$pattern" "$tmp/err" || { echo "missing '$pattern' in: $(cat "$tmp/err")"; exit 1; }
  [ "$(wc -l <"$tmp/err")" -eq 1 ] || { echo "error is not one line: $(cat "$tmp/err")"; exit 1; }
}
expect_exit2 "unknown scene 'nope'" --scene nope --frames 5 --out "$tmp/x.trc"
expect_exit2 "--out" --scene paper_object --frames 5
expect_exit2 "--frames" --scene paper_object --frames abc --out "$tmp/x.trc"
expect_exit2 "unknown option --bogus" --scene paper_object --bogus 1 --out "$tmp/x.trc"
expect_exit2 ".csv" --scene paper_object --frames 5 --out "$tmp/x.csv"
printf 'particles:\n  - {name: a, mass: -1}\n' >"$tmp/bad.yaml"
expect_exit2 "bad.yaml" --model "$tmp/bad.yaml" --frames 5 --out "$tmp/x.trc"
expect_exit2 "missing.yaml" --model "$tmp/missing.yaml" --frames 5 --out "$tmp/x.trc"
expect_exit2 "/nonexistent_dir" --scene paper_object --frames 5 --out /nonexistent_dir/x.trc
[ ! -e "$tmp/x.trc" ]
echo "simulate CLI ok"
