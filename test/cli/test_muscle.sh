#!/usr/bin/env bash
# Muscles through the tools: the documented muscle example (taken from docs/muscles.md itself, so
# the documented file stays valid) is simulated and identified from guesses to round-off with its
# network parameters named <type>/w2_<i>; the export loads back and simulates the same motion; bad muscle
# definitions stop identify with exit 2 and one line naming file, line and key.
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
source "$here/scripts/env.sh"
bin="$here/.ws/devel/lib/motion_model_estimation"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT

# The first yaml block of docs/muscles.md's "## Muscles" section (the `muscle` bond kind).
awk '/^## Muscles/ { s = 1 } s && /^```yaml/ { p = 1; next } p && /^```/ { exit } p' \
  "$here/docs/muscles.md" >"$tmp/muscle.yaml"
grep -q "kind: muscle" "$tmp/muscle.yaml"
"$bin/simulate" --model "$tmp/muscle.yaml" --frames 100 --out "$tmp/data.trc" >/dev/null
"$bin/identify" --sensor-muscles off --model "$tmp/muscle.yaml" --trajectory "$tmp/data.trc" --out "$tmp/out.yaml" \
  >"$tmp/out.log"
for name in s/stiffness m/stiffness m/rest_length m/gain m/w2_0 m/w2_1 m/w2_2 m/w2_3 m/b2; do
  grep -q "^$name " "$tmp/out.log" || { echo "no row for $name"; cat "$tmp/out.log"; exit 1; }
done
# Every value back to round-off (the file's guesses are the truth, perturbed by the search).
values() { grep -o 'value: [^,}]*' "$1" | awk '{print $2}'; }
[ "$(values "$tmp/muscle.yaml" | wc -l)" -eq "$(values "$tmp/out.yaml" | wc -l)" ]
paste <(values "$tmp/muscle.yaml") <(values "$tmp/out.yaml") | awk '
  { e = ($2 - $1) / $1; if (e < 0) e = -e; if (e > worst) worst = e; n++ }
  END { printf "muscle: max relative error %.3g over %d values\n", worst, n; exit !(n == 9 && worst < 1e-6) }'
grep -q "inputs: \[upper, lower\]" "$tmp/out.yaml"
# The export loads back and moves like the truth.
"$bin/simulate" --model "$tmp/out.yaml" --frames 100 --out "$tmp/again.trc" >/dev/null
paste <(tail -n +7 "$tmp/data.trc" | tr '\t' '\n') <(tail -n +7 "$tmp/again.trc" | tr '\t' '\n') | awk '
  { d = $2 - $1; if (d < 0) d = -d; if (d > worst) worst = d; n++ }
  END { printf "muscle: export re-simulated, largest difference %.3g mm over %d numbers\n", worst, n;
        exit !(n > 1000 && worst < 1e-6) }'

# Bad muscle definitions: exit 2, one line naming the file, line and key.
sed 's/inputs: \[upper, lower\]/inputs: [upper, nowhere]/' "$tmp/muscle.yaml" >"$tmp/bad.yaml"
line=$(grep -n "nowhere" "$tmp/bad.yaml" | cut -d: -f1)
set +e
"$bin/identify" --model "$tmp/bad.yaml" --trajectory "$tmp/data.trc" --out "$tmp/x.yaml" 2>"$tmp/bad.err" >/dev/null
rc=$?
set -e
[ "$rc" -eq 2 ] || { echo "expected exit 2, got $rc"; exit 1; }
[ "$(wc -l <"$tmp/bad.err")" -eq 1 ] || { echo "expected one line:"; cat "$tmp/bad.err"; exit 1; }
grep -q "$tmp/bad.yaml:$line: key 'inputs': unknown input bond 'nowhere'" "$tmp/bad.err" ||
  { echo "unexpected error: $(cat "$tmp/bad.err")"; exit 1; }
sed 's/    hidden: 0 /    hidden: 0\n    w1_0_0: 1 /' "$tmp/muscle.yaml" >"$tmp/bad2.yaml"
set +e
"$bin/simulate" --model "$tmp/bad2.yaml" --frames 3 --out "$tmp/x.trc" 2>"$tmp/bad2.err" >/dev/null
rc=$?
set -e
[ "$rc" -eq 2 ] || { echo "simulate: expected exit 2, got $rc"; exit 1; }
grep -q "key 'w1_0_0': unknown key for a muscle in bond type 'm'" "$tmp/bad2.err" ||
  { echo "unexpected error: $(cat "$tmp/bad2.err")"; exit 1; }
# Muscles on a passive model (--add-muscles): the documented example's bonds, all passive (the
# muscle a plain spring, every spring part free with the file's values as guesses), fitted to the
# muscle's motion; then every spring type a muscle started from that fit: the cost falls (a
# warm start never loses the passive fit), the export names the inputs and simulates.
sed -e '/^  - name: m$/,/^    b2:/c\  - {name: m, kind: spring, stiffness: {value: 40, free: true}, rest_length: {value: 0.25, free: true}, damping: {value: 0.2, free: true}}' \
    -e 's/, inputs: \[upper, lower\]//' "$tmp/muscle.yaml" >"$tmp/passive.yaml"
if grep -q "kind: muscle" "$tmp/passive.yaml"; then echo "passive model still has a muscle"; exit 1; fi
cost() { sed -n 's/^global cost \([^ ]*\) m^2.*/\1/p' "$1"; }
"$bin/identify" --sensor-muscles off --model "$tmp/passive.yaml" --trajectory "$tmp/data.trc" --out "$tmp/passive_fit.yaml" \
  --cost short_term >"$tmp/passive.log" 2>"$tmp/passive.err"
"$bin/identify" --sensor-muscles off --model "$tmp/passive_fit.yaml" --trajectory "$tmp/data.trc" --out "$tmp/muscled.yaml" \
  --cost short_term --add-muscles 2 >"$tmp/muscled.log" 2>"$tmp/muscled.err"
grep -q "^identify: 3 spring type(s) became muscles reading 2 bond(s) each, 0 hidden unit(s)" "$tmp/muscled.log" ||
  { echo "no placement line:"; head -5 "$tmp/muscled.log"; exit 1; }
awk -v p="$(cost "$tmp/passive.log")" -v m="$(cost "$tmp/muscled.log")" 'BEGIN {
  printf "muscle: passive cost %g m^2, with muscles %g m^2\n", p, m; exit !(p > 0 && m < 0.5 * p) }'
[ "$(grep -c "kind: muscle" "$tmp/muscled.yaml")" -eq 3 ]
grep -q "inputs: \[" "$tmp/muscled.yaml"
"$bin/simulate" --model "$tmp/muscled.yaml" --frames 20 --out "$tmp/muscled.trc" >/dev/null
# Out of range or nothing to place: exit 2 and the reason.
for bad in "--add-muscles 17|--add-muscles must be" "--muscle-hidden -1|--muscle-hidden must be" \
           "--sensor-muscles 17|--sensor-muscles must be" "--muscle-neighbours 65|--muscle-neighbours must be" \
           "--rollout-rounds 21|--rollout-rounds must be" "--muscle-anchors 2|--muscle-anchors must be" \
           "--anchor-stiffness yes|--anchor-stiffness must be" \
           "--sensor-muscles 0 --muscle-neighbours 2|need sensor muscles (--sensor-muscles off turns them off)" \
           "--sensor-muscles off --muscle-neighbours 2|need sensor muscles (--sensor-muscles off turns them off)" \
           "--sensor-muscles 6 --muscles-max-time-s -1|--muscles-max-time-s must be" \
           "--sensor-muscles yes|--sensor-muscles must be" \
           "--sensor-muscles off --muscles-max-time-s 60|--muscles-max-time-s needs sensor muscles"; do
  set +e
  "$bin/identify" --model "$tmp/passive_fit.yaml" --trajectory "$tmp/data.trc" --out "$tmp/x.yaml" \
    ${bad%%|*} 2>"$tmp/bad3.err" >/dev/null
  rc=$?
  set -e
  [ "$rc" -eq 2 ] && grep -q -- "${bad#*|}" "$tmp/bad3.err" ||
    { echo "${bad%%|*}: exit $rc, $(cat "$tmp/bad3.err")"; exit 1; }
done

# Sensor muscles (--sensor-muscles): on the passive fit, muscles reading the pairs whose distance
# varies most, fitted by least squares; the ridge is chosen on the last 20 % of the frames and the
# muscles are written only when they predict those better than the passive model (here they do:
# the muscle's motion is not passive). With the anchors (--muscle-anchors 1) each of the 3 free
# particles also has a muscle to each of three fixed anchor particles far along x, y and z:
# 6 + 9 muscles.
# The export simulates, and evaluate judges it on the data, which have no anchor markers (fixed
# particles need none). (Out-of-range options: above.)
"$bin/identify" --model "$tmp/passive_fit.yaml" --trajectory "$tmp/data.trc" --out "$tmp/sensor.yaml" \
  --cost short_term --sensor-muscles 6 --muscle-neighbours 3 --muscle-anchors 1 >"$tmp/sensor.log" 2>"$tmp/sensor.err"
grep -q "^identify: sensor muscles: 6 sensors, 15 muscles, ridge .*, with anchors; 10 frames ahead on the last frames" "$tmp/sensor.log" ||
  { echo "no sensor-muscle report:"; grep sensor "$tmp/sensor.log"; exit 1; }
awk '/^identify: sensor muscles: 6 sensors, 15 muscles, ridge/ {
  for (i = 1; i <= NF; ++i) { if ($i == "frames" && $(i+1) ~ /^[0-9]/) m = $(i+1); if ($i == "(passive") p = $(i+1) }
  printf "muscle: sensor muscles %s m against passive %s m, 10 frames ahead on held-out frames\n", m, p
  exit !(m + 0 > 0 && m + 0 < p + 0) }' "$tmp/sensor.log"
# The anchor muscles' own stiffness is fitted by default (and by auto: the object hangs from a
# fixed particle); --anchor-stiffness 0 holds it at 0 (the report says which).
grep -q "^identify: sensor muscles: 6 sensors, .*; the anchor muscles with a stiffness of their own" "$tmp/sensor.log" ||
  { echo "auto did not fit the anchor muscles' stiffness:"; grep sensor "$tmp/sensor.log"; exit 1; }
"$bin/identify" --model "$tmp/passive_fit.yaml" --trajectory "$tmp/data.trc" --out "$tmp/sensor_k0.yaml" \
  --cost short_term --sensor-muscles 6 --muscle-neighbours 3 --muscle-anchors 1 --anchor-stiffness 0 >"$tmp/sensor_k0.log" 2>&1
grep -q "^identify: sensor muscles: 6 sensors, .*; the anchor muscles without a stiffness of their own" "$tmp/sensor_k0.log" ||
  { echo "--anchor-stiffness 0:"; grep sensor "$tmp/sensor_k0.log"; exit 1; }
"$bin/identify" --model "$tmp/passive_fit.yaml" --trajectory "$tmp/data.trc" --out "$tmp/sensor_ka.yaml" \
  --cost short_term --sensor-muscles 6 --muscle-neighbours 3 --muscle-anchors 1 --anchor-stiffness auto >"$tmp/sensor_ka.log" 2>&1
grep -q "^identify: sensor muscles: 6 sensors, .*; the anchor muscles with a stiffness of their own" "$tmp/sensor_ka.log" ||
  { echo "--anchor-stiffness auto:"; grep sensor "$tmp/sensor_ka.log"; exit 1; }
# The grouped selection may leave muscles and sensors out; the report says how many it kept.
kept_muscles=$(sed -n 's/^identify: sensor muscles: 6 sensors, 15 muscles, .*which kept \([0-9]*\) sensors and \([0-9]*\) muscles.*/\2/p' "$tmp/sensor.log")
kept_sensors=$(sed -n 's/^identify: sensor muscles: 6 sensors, 15 muscles, .*which kept \([0-9]*\) sensors and \([0-9]*\) muscles.*/\1/p' "$tmp/sensor.log")
[ "$(grep -c "kind: muscle" "$tmp/sensor.yaml")" -eq "${kept_muscles:-15}" ]
[ "$(grep -c "name: sensor_" "$tmp/sensor.yaml")" -ge "${kept_sensors:-6}" ]
[ "$(grep -c "name: anchor_[xyz]" "$tmp/sensor.yaml")" -eq 3 ]
"$bin/simulate" --model "$tmp/sensor.yaml" --frames 20 --out "$tmp/sensor.trc" >/dev/null
"$bin/evaluate" --model "$tmp/sensor.yaml" --trajectory "$tmp/data.trc" --horizons 10 >"$tmp/sensor_eval.log"
grep -q "constant_velocity" "$tmp/sensor_eval.log" || { echo "evaluate:"; cat "$tmp/sensor_eval.log"; exit 1; }
# Without anchors (--muscle-anchors 0): the body's own 6 muscles.
"$bin/identify" --model "$tmp/passive_fit.yaml" --trajectory "$tmp/data.trc" --out "$tmp/sensor0.yaml" \
  --cost short_term --sensor-muscles 6 --muscle-neighbours 3 --muscle-anchors 0 >"$tmp/sensor0.log" 2>&1
grep -q "^identify: sensor muscles: 6 sensors, 6 muscles, ridge" "$tmp/sensor0.log" ||
  { echo "--muscle-anchors 0:"; grep sensor "$tmp/sensor0.log"; exit 1; }
! grep -q "name: anchor_" "$tmp/sensor0.yaml"
# A time limit on the muscles' fit (--muscles-max-time-s; spent at once here): one candidate
# judged, the layout with anchors alone, the report says so, and a model is still written.
"$bin/identify" --model "$tmp/passive_fit.yaml" --trajectory "$tmp/data.trc" --out "$tmp/sensor_t.yaml" \
  --cost short_term --sensor-muscles 6 --muscle-neighbours 3 --muscles-max-time-s 1e-9 >"$tmp/sensor_t.log" 2>&1
grep -q "^identify: sensor muscles: time limit of 1e-09 s spent (.* s): no further ridge" "$tmp/sensor_t.log" &&
  grep -q "^identify: sensor muscles: time limit of 1e-09 s spent (.* s): no fit without anchors" "$tmp/sensor_t.log" &&
  grep -q "^identify: sensor muscles: 6 sensors, .*, with anchors; .*(stopped by --muscles-max-time-s" "$tmp/sensor_t.log" ||
  { echo "--muscles-max-time-s:"; grep sensor "$tmp/sensor_t.log"; exit 1; }
[ "$(grep -c "^identify: sensor muscles: window 1, ridge" "$tmp/sensor_t.log")" -eq 1 ] ||
  { echo "--muscles-max-time-s judged more than one ridge:"; grep sensor "$tmp/sensor_t.log"; exit 1; }
[ -s "$tmp/sensor_t.yaml" ]
# The default (auto): both layouts fitted, the one predicting the last 20 % better kept; the
# report names it and the file has the anchors exactly when it says so.
"$bin/identify" --model "$tmp/passive_fit.yaml" --trajectory "$tmp/data.trc" --out "$tmp/sensor_auto.yaml" \
  --cost short_term --sensor-muscles 6 --muscle-neighbours 3 >"$tmp/sensor_auto.log" 2>&1
grep -q "^identify: sensor muscles: \(with\|without\) anchors (validation .* mm, \(with\|without\) them .* mm)" \
  "$tmp/sensor_auto.log" || { echo "no anchor choice:"; grep sensor "$tmp/sensor_auto.log"; exit 1; }
anchors=$(grep -c "name: anchor_[xyz]" "$tmp/sensor_auto.yaml" || true)
# The same model file but for the wall times (the identification's, and the sensor muscles'
# seconds in their note, which the machine's load moves across a rounding boundary).
same_model() {
  local d
  without_times() { grep -v "wall_time_s:" "$1" | sed -E 's/ m\), [0-9]+ s(;|")/ m), N s\1/'; }
  d=$(diff <(without_times "$tmp/sensor_auto.yaml") <(without_times "$1") || true)
  [ -z "$d" ] || { echo "$d" | head; return 1; }
}
if grep -q "^identify: sensor muscles: 6 sensors, .*, with anchors;" "$tmp/sensor_auto.log"; then
  [ "$anchors" -eq 3 ]; same_model "$tmp/sensor.yaml" || { echo "auto with anchors differs from --muscle-anchors 1"; exit 1; }
else
  [ "$anchors" -eq 0 ]; same_model "$tmp/sensor0.yaml" || { echo "auto without anchors differs from --muscle-anchors 0"; exit 1; }
fi
# Data the sensor muscles cannot use (40 frames: too few to hold out a validation 10 frames
# ahead): the identified passive model is still written, with a warning naming the reason.
"$bin/simulate" --model "$tmp/muscle.yaml" --frames 40 --out "$tmp/short.trc" >/dev/null
"$bin/identify" --model "$tmp/passive_fit.yaml" --trajectory "$tmp/short.trc" --out "$tmp/short.yaml" \
  --cost short_term --sensor-muscles 6 >"$tmp/short.log" 2>"$tmp/short.err" ||
  { echo "identify failed where only the sensor muscles could not be fitted:"; cat "$tmp/short.err"; exit 1; }
grep -q "^identify: warning: no sensor muscles (sensor muscles: 40 frames are too few .*): the passive model is written" \
  "$tmp/short.err" || { echo "no warning:"; cat "$tmp/short.err"; exit 1; }
[ -s "$tmp/short.yaml" ] && ! grep -q "kind: muscle" "$tmp/short.yaml"
grep -q "sensor muscles: none (sensor muscles: 40 frames are too few" "$tmp/short.yaml" ||
  { echo "the written model's notes do not say why it has no sensor muscles"; exit 1; }

# --sensor-muscles auto, the default (no flag here): the search is not started where the passive
# model already explains the data (here its own simulation, noiseless): the closing line and the
# file's notes say why, and the passive model is written. On the muscle's data the gate lets the
# search through.
"$bin/simulate" --model "$tmp/passive_fit.yaml" --frames 100 --out "$tmp/passive_data.trc" >/dev/null
"$bin/identify" --model "$tmp/passive_fit.yaml" --trajectory "$tmp/passive_data.trc" --out "$tmp/gate.yaml" \
  --cost short_term --generations 5 >"$tmp/gate.log" 2>&1
grep -q "^identify: sensor muscles: not fitted: the passive model predicts the validation frames" "$tmp/gate.log" ||
  { echo "--sensor-muscles auto on passive data:"; grep sensor "$tmp/gate.log"; exit 1; }
grep -q "sensor muscles: not fitted: " "$tmp/gate.yaml" || { echo "no note in the file"; exit 1; }
! grep -q "kind: muscle" "$tmp/gate.yaml"
"$bin/identify" --model "$tmp/passive_fit.yaml" --trajectory "$tmp/data.trc" --out "$tmp/gate_on.yaml" \
  --cost short_term --sensor-muscles auto --muscle-anchors 0 >"$tmp/gate_on.log" 2>&1
grep -q "^identify: sensor muscles: 16 sensors\|^identify: sensor muscles: [0-9]* sensors, [0-9]* muscles, ridge .*, [0-9]* parameters on [0-9]* samples" \
  "$tmp/gate_on.log" || { echo "--sensor-muscles auto on the muscle's data:"; grep sensor "$tmp/gate_on.log"; exit 1; }
echo "muscle: documented example simulated, identified, exported and reloaded; bad definitions refused; muscles placed on a passive fit lower its cost; sensor muscles predict its held-out frames better; --sensor-muscles auto (the default) skips them on passive data"
