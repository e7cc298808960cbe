#!/usr/bin/env bash
# scripts/bench --quick (issue 5): builds the peer benchmark, runs every method available (the
# peer optimisers only when pagmo2/Ceres are installed: without them the run says so and the
# remaining methods still run), and fails when a CSV file is missing, empty or not finite.
# No package is installed here (--no-setup); results go to a temporary directory.
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT

"$here/scripts/bench" --quick --no-setup --out "$tmp" >"$tmp/out.txt" 2>&1 ||
  { cat "$tmp/out.txt"; echo "scripts/bench --quick failed"; exit 1; }
tail -3 "$tmp/out.txt"
grep -q "CSV files checked" "$tmp/out.txt"
grep -q "^bench_peers: methods:.*es_local.*lls" "$tmp/out.txt"

# Independent checks of what scripts/bench asserted, so the test does not trust the tool alone.
for f in speed_accuracy_runs speed_accuracy_trace stability_runs stability_rates rollout scaling \
         unknowns_generations targets; do
  [ -s "$tmp/$f.csv" ] || { echo "missing or empty: $f.csv"; exit 1; }
  [ "$(wc -l <"$tmp/$f.csv")" -ge 2 ] || { echo "no data line: $f.csv"; exit 1; }
  if grep -Eiq '(^|,)[-+]?(nan|inf)' "$tmp/$f.csv"; then echo "not finite: $f.csv"; exit 1; fi
done
[ -s "$tmp/summary.md" ]
# Every available method ran on the speed-accuracy scene, and the exact solver found the truth
# of the linear paper_object (its equation error is the paper's cost there).
for m in $(grep '^bench_peers: methods:' "$tmp/out.txt" | sed 's/^bench_peers: methods://; s/;.*//'); do
  grep -q "^paper_object,$m," "$tmp/speed_accuracy_runs.csv" || { echo "no run of $m"; exit 1; }
done
awk -F, '$1 == "paper_object" && $2 == "lls" && $9 + 0 > 1e-3 { print "lls error " $9; exit 1 }' \
  "$tmp/speed_accuracy_runs.csv"
# The parallel timing is a positive number for both thread counts.
awk -F, 'NR > 1 && $6 > 0 { n[$5]++ } END { exit !(n[1] > 0 && n[2] > 0) }' "$tmp/scaling.csv"
if ! grep -q "not compiled in" "$tmp/out.txt"; then
  grep -q "^paper_object,cmaes," "$tmp/speed_accuracy_runs.csv"
  grep -q "^paper_object,lm," "$tmp/speed_accuracy_runs.csv"
fi

# One part alone into a fresh directory: only its files are required, the charts it has data for
# are drawn, and a scene name the mode does not have is refused before anything runs.
part="$tmp/part"
"$here/scripts/bench" --quick --no-setup --out "$part" --only speed --scenes paper_object \
  --methods es_lm,lls >"$tmp/part.txt" 2>&1 || { cat "$tmp/part.txt"; echo "partial run failed"; exit 1; }
grep -q "CSV files checked" "$tmp/part.txt"
[ -s "$part/speed_accuracy_paper_object.png" ] && [ ! -e "$part/scaling.csv" ] && [ ! -e "$part/stability_map.png" ]
[ "$(cut -d, -f1 "$part/speed_accuracy_runs.csv" | sort -u | grep -vc scene)" -eq 1 ]
if "$here/scripts/bench" --quick --no-setup --out "$part" --only speed --scenes provot_cloth >"$tmp/bad.txt" 2>&1; then
  echo "an unknown --scenes name was accepted"; exit 1
fi
grep -q "no speed scene 'provot_cloth'" "$tmp/bad.txt"
echo "test_bench_quick: ok"
