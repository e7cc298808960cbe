#!/usr/bin/env bash
# The README's quick start is true: it sits on the first screen (its section within the first 15
# lines, its commands in one block of four lines), its identify and evaluate lines run as written
# (through rosrun, on a capture named walk.trc in the current directory) and each prints the next
# command; identify's rviz line is the README's replay.launch line with $PWD expanded, and every
# argument of that line is an argument of launch/replay.launch.
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
source "$here/scripts/env.sh"
bin="$here/.ws/devel/lib/motion_model_estimation"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

readme="$here/README.md"
section=$(grep -n "^## Quick start" "$readme" | head -n 1 | cut -d: -f1)
[ -n "$section" ] && [ "$section" -le 15 ] || fail "no '## Quick start' within the README's first 15 lines"
# The first fenced block after the heading.
awk -v s="$section" 'NR > s && /^```/ { if (inside) exit; inside = 1; next } inside' "$readme" >"$tmp/block"
[ "$(wc -l <"$tmp/block")" -eq 4 ] || fail "the quick start is not four commands:"$'\n'"$(cat "$tmp/block")"
grep -q "^scripts/setup && source scripts/env.sh$" "$tmp/block" || fail "the quick start does not begin with the set-up"
identify_line=$(grep "^rosrun motion_model_estimation identify " "$tmp/block") || fail "no identify line"
evaluate_line=$(grep "^rosrun motion_model_estimation evaluate " "$tmp/block") || fail "no evaluate line"
replay_line=$(grep "^roslaunch motion_model_estimation replay.launch " "$tmp/block") || fail "no replay line"

# A capture of 300 frames named as in the README (millimetres, as most TRC files are).
cd "$tmp"
"$bin/simulate" --scene paper_object --frames 300 --units mm --out walk.trc >/dev/null
eval "$identify_line" >identify.log 2>identify.err || fail "the README's identify line: $(cat identify.err)"
grep -q "^identify: wrote a passive model" identify.log || fail "identify says not which model it wrote"
next=$(grep "^identify: next: " identify.log) || fail "identify prints no next step"
# The next steps identify prints are the README's two next lines.
echo "$next" | grep -q -F "evaluate --model walk.yaml --trajectory walk.trc --first-frame 240 --history 20;" ||
  fail "identify's evaluate step is not the README's: $next"
expanded=$(eval echo "\"${replay_line}\"")
[ "${next##*see it in rviz: }" = "$expanded" ] ||
  fail "identify's rviz step is not the README's:"$'\n'"${next##*see it in rviz: }"$'\n'"$expanded"
eval "$evaluate_line" >evaluate.log 2>evaluate.err || fail "the README's evaluate line: $(cat evaluate.err)"
grep -q "^rollout of .* frames from the first start: bounded" evaluate.log || fail "evaluate: $(cat evaluate.log)"
grep -q -F "evaluate: next: see it in rviz: $expanded" evaluate.log || fail "evaluate's next step: $(tail -n 1 evaluate.log)"

# Every name:=value of the replay line is an argument replay.launch declares.
for arg in $(echo "$replay_line" | grep -o '[a-z_]*:=' | tr -d ':='); do
  grep -q "<arg name=\"$arg\"" "$here/launch/replay.launch" || fail "replay.launch has no argument '$arg'"
done
echo "README quick start: ok"
