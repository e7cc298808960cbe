#!/usr/bin/env bash
# A new user's defaults: every tool's --help is a reference (each option with its meaning and
# default, examples, the next step; identify does not call --model required; --first-frame
# counts from 0, said) and docs/tools.md names every option; identify writes a plain passive
# model by default and says which kind it wrote and why; its generation lines estimate the time
# left; Ctrl-C / SIGTERM write the best model so far and the exit says so; a warning after the
# table stays after it when stdout and stderr share a pipe; the identified model starts from the
# first used frame, and simulate --trajectory --start-frame starts from a frame of a capture.
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
source "$here/scripts/env.sh"
bin="$here/.ws/devel/lib/motion_model_estimation"
tmp=$(mktemp -d)
pid=""
cleanup() { [ -z "$pid" ] || kill -KILL "$pid" 2>/dev/null || true; rm -rf "$tmp"; }
trap cleanup EXIT
fail() { echo "FAIL: $*"; exit 1; }

# ---------------------------------------------------------------- --help of every tool
for tool in identify simulate evaluate convert; do
  "$bin/$tool" --help >"$tmp/$tool.help" || fail "$tool --help exited non-zero"
  # Every option: "  --name [VALUE]" then its meaning indented by 6; a valued option's meaning
  # ends with its default, unless it is required.
  awk -v tool="$tool" '
    function check() {
      if (name == "") return
      if (text == "") { printf "%s --%s: no description\n", tool, name; bad = 1 }
      if (valued && text !~ /Default: / && text !~ /\(required\)/) { printf "%s --%s: no default\n", tool, name; bad = 1 }
    }
    /^Examples:/ { check(); name = ""; done = 1 }
    done { next }
    /^  --/ { check(); name = substr($1, 3); valued = (NF > 1); text = ""; n++; next }
    /^      / { text = text $0; next }
    { check(); name = "" }
    END { check(); if (n < 5) { printf "%s: only %d options in --help\n", tool, n; bad = 1 }; exit bad }
  ' "$tmp/$tool.help" || fail "$tool --help is not a reference:"$'\n'"$(cat "$tmp/$tool.help")"
  for section in "^usage: $tool " "^Examples:" "^Next step:"; do
    grep -q "$section" "$tmp/$tool.help" || fail "$tool --help has no '$section'"
  done
  # docs/tools.md documents every option --help lists.
  for option in $(sed '/^Examples:/,$d' "$tmp/$tool.help" | grep -o '^  --[a-z0-9-]*' | sed 's/^  //'); do
    grep -q -- "\`$option" "$here/docs/tools.md" || fail "docs/tools.md does not document $tool $option"
  done
done
grep -q "^usage: identify .*(--model M.yaml | --select-structure)" "$tmp/identify.help" ||
  fail "identify --help's usage: $(head -1 "$tmp/identify.help")"
! awk '/^  --model /{getline; print}' "$tmp/identify.help" | grep -qi "required" ||
  fail "identify --help calls --model required"
for tool in identify evaluate convert; do
  awk '/^  --first-frame /{getline; print}' "$tmp/$tool.help" | grep -q "counted from 0 (not by the file's Frame#" ||
    fail "$tool --help does not say how --first-frame counts"
done

# ---------------------------------------------------------------- data
"$bin/simulate" --scene paper_object --frames 150 --out "$tmp/long.trc" --truth-out "$tmp/truth.yaml" >/dev/null
sed -E 's/\{value: [^,]*, free: true/{free: true/' "$tmp/truth.yaml" >"$tmp/free.yaml"
sed '/^bond_types:/,$d' "$tmp/truth.yaml" >"$tmp/particles.yaml"
# The same capture numbered from 1, as most TRC files are (simulate numbers from 0).
awk 'BEGIN { FS = OFS = "\t" } NR > 6 && $1 != "" { $1 = $1 + 1 } { print }' "$tmp/long.trc" >"$tmp/long1.trc"
# TRC row of Frame# F (1-based, as in the file) without its frame number and time columns.
trc_row() { awk -v f="$2" 'NR > 5 && $1 == f { $1 = ""; $2 = ""; print; exit }' "$1"; }
same_rows() {  # same_rows ROW_A ROW_B: equal to 1e-6 mm
  paste <(echo "$1" | tr -s ' ' '\n' | sed '/^$/d') <(echo "$2" | tr -s ' ' '\n' | sed '/^$/d') |
    awk '{ d = $1 - $2; if (d < 0) d = -d; if (d > 1e-6) bad = 1; n++ } END { exit bad || n != 45 }'
}

# ------------------------------------- the default: sensor muscles auto, stopped by the gain gate
# On a passive scene's own noiseless motion the gate finds nothing to gain: the passive model is
# written, and the closing line and the file say why no muscle was fitted.
"$bin/identify" --model "$tmp/particles.yaml" --trajectory "$tmp/long.trc" --select-structure \
  --out "$tmp/sel.yaml" >"$tmp/sel.log" 2>"$tmp/sel.err" || fail "identify --select-structure: $(cat "$tmp/sel.err")"
grep -q "^identify: wrote a passive model (15 particles, 31 bonds) to $tmp/sel.yaml: sensor muscles not fitted: the passive model predicts the validation frames 10 frames ahead" \
  "$tmp/sel.log" || fail "no 'which kind and why' line:"$'\n'"$(grep "wrote\|sensor" "$tmp/sel.log")"
! grep -q "kind: muscle\|name: anchor_" "$tmp/sel.yaml" || fail "a muscle or an anchor in the default model"
grep -q "sensor muscles: not fitted: " "$tmp/sel.yaml" || fail "the file does not say why it has no sensor muscles"
grep -q "model_kind: passive" "$tmp/sel.yaml" || fail "the file does not say which kind it holds"
# --sensor-muscles off: the plain passive model, and the closing line says how to get muscles.
"$bin/identify" --model "$tmp/particles.yaml" --trajectory "$tmp/long.trc" --select-structure \
  --sensor-muscles off --out "$tmp/off.yaml" >"$tmp/off.log" 2>"$tmp/off.err" || fail "identify --sensor-muscles off: $(cat "$tmp/off.err")"
grep -q "^identify: wrote a passive model (15 particles, 31 bonds) to $tmp/off.yaml: sensor muscles not tried (--sensor-muscles auto or 16 fits them); on the held-out frames it predicts 10 frames ahead in .* mm (constant velocity .* mm, constant acceleration .* mm)" \
  "$tmp/off.log" || fail "--sensor-muscles off: no 'which kind and why' line:"$'\n'"$(grep "wrote\|sensor" "$tmp/off.log")"
! grep -q "sensor muscles:" "$tmp/off.log" || fail "sensor muscles fitted with --sensor-muscles off"
# Structure selection says, level by level, how far it is and the time the rest would take.
grep -E -q "^identify: structure: 1 of [0-9]+ level\(s\) done in [0-9]+ s, about [0-9]+ s more at this pace$" \
  "$tmp/sel.log" || fail "no pace line after the first structure level: $(grep "level" "$tmp/sel.log")"
grep -E -q "^identify: structure: ([0-9]+) of \1 level\(s\) done in [0-9]+ s$" "$tmp/sel.log" ||
  fail "no line after the last structure level: $(grep "level(s) done" "$tmp/sel.log")"
# Every step's output says what to do next, down to rviz: identify (it used every frame here, so
# it says how to keep some for evaluate), a fit on fewer frames (evaluate on the frames after
# them), evaluate and convert.
rviz="roslaunch motion_model_estimation replay.launch model:=$tmp/sel.yaml bag:=$tmp/long.trc estimate:=false rviz:=true"
grep -q -F "identify: next: (every frame of the file was used: identify on fewer, --frames N, to keep some for evaluate) see it in rviz: $rviz" \
  "$tmp/sel.log" || fail "identify names no next step: $(grep next "$tmp/sel.log")"

# ---------------------------------------------------------------- frames, progress, initial state
# Frames 5..64 counted from 0 are this TRC's Frame# 6..65; the model written starts at Frame# 6.
"$bin/identify" --sensor-muscles off --model "$tmp/free.yaml" --trajectory "$tmp/long1.trc" --first-frame 5 --frames 60 \
  --generations 20 --patience 0 --out "$tmp/cut.yaml" >"$tmp/cut.log" 2>"$tmp/cut.err" ||
  fail "identify --first-frame: $(cat "$tmp/cut.err")"
grep -q "^identify: frames 5..64 of 150 used (counted from 0); the file's Frame# 6..65" "$tmp/cut.log" ||
  fail "frame numbering not stated: $(grep frames "$tmp/cut.log")"
grep -q -F "identify: next: judge it on frames it did not see: evaluate --model $tmp/cut.yaml --trajectory $tmp/long1.trc --first-frame 65 --history 20; see it in rviz:" \
  "$tmp/cut.log" || fail "identify on fewer frames names no evaluate step: $(grep next "$tmp/cut.log")"
"$bin/evaluate" --model "$tmp/cut.yaml" --trajectory "$tmp/long1.trc" --first-frame 65 --history 20 >"$tmp/ev.log"
grep -q -F "evaluate: next: see it in rviz: roslaunch motion_model_estimation replay.launch model:=$tmp/cut.yaml bag:=$tmp/long1.trc estimate:=false rviz:=true" \
  "$tmp/ev.log" || fail "evaluate names no next step: $(tail -n 2 "$tmp/ev.log")"
"$bin/convert" --trajectory "$tmp/long1.trc" --out "$tmp/conv.trc" >"$tmp/conv.log"
grep -q -F "convert: next: a model of the capture: identify --select-structure --trajectory $tmp/long1.trc --out MODEL.yaml" \
  "$tmp/conv.log" || fail "convert names no next step: $(tail -n 2 "$tmp/conv.log")"
grep -E -q "^generation 20/20 .* s, at most ~[0-9]+ s left$" "$tmp/cut.log" ||
  fail "no time-left estimate: $(grep generation "$tmp/cut.log")"
"$bin/simulate" --model "$tmp/cut.yaml" --frames 2 --out "$tmp/played.trc" >/dev/null
same_rows "$(trc_row "$tmp/played.trc" 0)" "$(trc_row "$tmp/long1.trc" 6)" ||
  fail "the identified model does not start at the first used frame:"$'\n'"$(trc_row "$tmp/played.trc" 0)"$'\n'"$(trc_row "$tmp/long1.trc" 6)"

# simulate --trajectory --start-frame: the truth played from frame 40 (Frame# 41) of the
# capture gives that frame first.
"$bin/simulate" --model "$tmp/truth.yaml" --trajectory "$tmp/long1.trc" --start-frame 40 --frames 5 \
  --out "$tmp/from40.trc" >"$tmp/from40.log"
grep -q "starting from frame 40 of $tmp/long1.trc (counted from 0; the file's Frame# 41), 15 of 15 particles placed" \
  "$tmp/from40.log" || fail "simulate --start-frame: $(cat "$tmp/from40.log")"
same_rows "$(trc_row "$tmp/from40.trc" 0)" "$(trc_row "$tmp/long1.trc" 41)" ||
  fail "simulate --start-frame 40 does not start at Frame# 41"
set +e; "$bin/simulate" --model "$tmp/truth.yaml" --start-frame 3 --out "$tmp/x.trc" 2>"$tmp/x.err"; rc=$?; set -e
[ "$rc" -eq 2 ] && grep -q "start-frame needs --trajectory" "$tmp/x.err" || fail "--start-frame alone: exit $rc $(cat "$tmp/x.err")"

# ---------------------------------------------------------------- a warning after the table
# A user's bound below the truth: the bound warning comes after the table and the summary also
# when stdout and stderr go to one pipe.
sed -E '0,/stiffness: \{free: true, min: 1.04, max: 104\}/s//stiffness: {free: true, min: 1.04, max: 8}/' \
  "$tmp/free.yaml" >"$tmp/bounded.yaml"
"$bin/identify" --sensor-muscles off --model "$tmp/bounded.yaml" --trajectory "$tmp/long.trc" --frames 60 --out "$tmp/b.yaml" 2>&1 |
  cat >"$tmp/piped.log"
awk '/^parameter / { table = NR } /^stopped: / { stopped = NR } /warning: .*search bound/ { warning = NR }
     END { exit !(table && stopped && warning > stopped) }' "$tmp/piped.log" ||
  fail "the warning is not after the table:"$'\n'"$(cat "$tmp/piped.log")"

# ---------------------------------------------------------------- Ctrl-C and SIGTERM
# A search that would run for ever: the signal ends it after the generation under way, the best
# model so far is written (valid: evaluate reads it) and the exit (128 + the signal) says so.
interrupt() {  # interrupt SIGNAL EXIT_CODE
  local out="$tmp/int_$1.yaml" log="$tmp/int_$1.log"
  "$bin/identify" --model "$tmp/free.yaml" --trajectory "$tmp/long.trc" --generations 100000000 \
    --patience 0 --out "$out" >"$log" 2>&1 &
  pid=$!
  for _ in $(seq 600); do grep -q "^generation " "$log" && break; sleep 0.1; done
  grep -q "^generation " "$log" || fail "identify printed no generation line: $(cat "$log")"
  kill "-$1" "$pid"
  for _ in $(seq 600); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
  if kill -0 "$pid" 2>/dev/null; then fail "identify still runs after SIG$1: $(cat "$log")"; fi
  set +e; wait "$pid"; local rc=$?; set -e
  pid=""
  [ "$rc" -eq "$2" ] || fail "SIG$1: exit $rc, expected $2: $(cat "$log")"
  grep -q "^identify: interrupted: $out holds the best model found before the interruption (exit $2)" "$log" ||
    fail "SIG$1: no closing line: $(cat "$log")"
  grep -q "^stopped: interrupted" "$log" || fail "SIG$1: no 'stopped: interrupted'"
  grep -q "model_kind: passive" "$out" || fail "SIG$1: the file does not say its kind"
  "$bin/evaluate" --model "$out" --trajectory "$tmp/long.trc" --horizons 1 >/dev/null ||
    fail "SIG$1: the model written cannot be evaluated"
}
interrupt INT 130
interrupt TERM 143
echo "identify defaults: OK"
