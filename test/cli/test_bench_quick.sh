#!/usr/bin/env bash
# scripts/bench --quick: builds the peer benchmark, runs every method available (the
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
grep -q "^bench_peers: methods: default .*es_local.*lls" "$tmp/out.txt"

# Independent checks of what scripts/bench asserted, so the test does not trust the tool alone.
for f in speed_accuracy_runs speed_accuracy_trace stability_runs stability_rates rollout scaling \
         unknowns_generations efficiency targets; do
  [ -s "$tmp/$f.csv" ] || { echo "missing or empty: $f.csv"; exit 1; }
  [ "$(wc -l <"$tmp/$f.csv")" -ge 2 ] || { echo "no data line: $f.csv"; exit 1; }
  if grep -Eiq '(^|,)[-+]?(nan|inf)' "$tmp/$f.csv"; then echo "not finite: $f.csv"; exit 1; fi
done
[ -s "$tmp/summary.md" ]
# Every available method ran on the speed-accuracy scene, and the exact solver found the truth
# of the linear paper_object (its equation error is the paper's cost there).
# (sade_final, sade judged on its final answer, runs on the map's conditional axis only; the
# islands run in the stability map only.)
for m in $(grep '^bench_peers: methods:' "$tmp/out.txt" | sed 's/^bench_peers: methods://; s/;.*//'); do
  [ "$m" = sade_final ] || [ "$m" = islands ] && continue
  grep -q "^paper_object,$m," "$tmp/speed_accuracy_runs.csv" || { echo "no run of $m"; exit 1; }
done
# The default engine (judged on its final answer) ran on every map cell, says which estimator
# gave its answer (1/0, as the islands, which run identify too; n/a for the other methods) and
# finds noise-free paper_object's truth.
col() { head -1 "$2" | tr ',' '\n' | grep -nx "$1" | cut -d: -f1; }
runs="$tmp/stability_runs.csv"
for c in bound_median_pct bound_max_pct efficiency output_error substeps noise_estimate_m residual_std_m \
         efficient_success_prob threshold_middle_max_pct ever_within_1pct; do
  [ -n "$(col "$c" "$runs")" ] || { echo "stability_runs.csv has no column $c"; exit 1; }
done
oe=$(col output_error "$runs"); eff=$(col efficiency "$runs"); bmed=$(col bound_median_pct "$runs")
[ "$(awk -F, 'NR > 1 { print $1 "," $2 }' "$runs" | sort -u | wc -l)" -eq \
  "$(awk -F, 'NR > 1 && $4 == "default" { print $1 "," $2 }' "$runs" | sort -u | wc -l)" ] ||
  { echo "default did not run on every map cell"; exit 1; }
awk -F, -v oe="$oe" 'NR > 1 && (($4 == "default" || $4 == "islands") != ($oe != "n/a")) { print "output_error column: " $0; bad = 1 }
                     NR > 1 && $oe != "n/a" && $oe != 0 && $oe != 1 { print "output_error not 0/1: " $0; bad = 1 }
                     END { exit bad }' "$runs"
awk -F, '$1 == "noise" && $2 == 0 && $4 == "default" && $7 != 1 { print "default failed noise-free: " $0; exit 1 }' "$runs"
# Noisy instances carry the Cramer-Rao bound and every method an efficiency; noise-free ones n/a.
awk -F, -v e="$eff" -v b="$bmed" 'NR > 1 && $1 == "noise" && $2 > 0 && !($b > 0 && $e > 0) { print "no bound: " $0; bad = 1 }
                                  NR > 1 && $1 == "noise" && $2 == 0 && ($b != "n/a" || $e != "n/a") { print "bound without noise: " $0; bad = 1 }
                                  END { exit bad }' "$runs"
grep -q "^1e-05,default," "$tmp/efficiency.csv" || { echo "efficiency.csv has no default row at 1e-05"; exit 1; }
grep -q "^| default engine: in every stability-map cell" "$tmp/summary.md"
grep -q "^#### noise 1e-05 m" "$tmp/summary.md"
if command -v gnuplot >/dev/null; then [ -s "$tmp/efficiency.png" ] || { echo "no efficiency.png"; exit 1; }; fi
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
