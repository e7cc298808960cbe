#!/usr/bin/env bash
# Crash and restart (docs/reliability.md): simulator_node streams a small model, estimator_node
# identifies it with ~autosave_period_sec 0.5. While it runs, check_model_file reads the autosave
# in a loop: it must parse every time (written atomically). When the autosave is within 0.5 %
# of the truth the estimator is killed with SIGKILL; the autosave still parses. Restarted with
# ~initial_model = the autosave, its first estimate (a low generation) is already within 1 % of
# the truth: it resumed. The default engine starts from an equation-error solution that is exact
# on this noiseless scene, so a start from scratch is close too and cannot show what the autosave
# brings: the comparison runs with ~preset paper (no such start), where a start from scratch is
# far off at its first estimate and a resumed one is not.
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
source "$here/scripts/env.sh"
bin="$here/.ws/devel/lib/motion_model_estimation"
tmp=$(mktemp -d)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  for p in "${pids[@]}"; do wait "$p" 2>/dev/null || true; done
  [ -n "${MME_KEEP_TMP:-}" ] && echo "kept $tmp" || rm -rf "$tmp"
}
trap cleanup EXIT

# shellcheck disable=SC1091
source "$here/scripts/free_port.sh"
port=$(free_port test_crash_restart) || exit 1
export ROS_MASTER_URI=http://127.0.0.1:$port ROS_HOME="$tmp/ros_home"
roscore -p "$port" >"$tmp/roscore.log" 2>&1 &
pids+=($!)
for _ in $(seq 100); do rosparam get /rosdistro >/dev/null 2>&1 && break; sleep 0.2; done
rosparam get /rosdistro >/dev/null

# The paper's object (15 masses, 10 spring types, 20 free parameters): simulator_node streams
# the scene, the estimator starts from the scene's model file (free parameters without values).
mkdir -p "$tmp/models"
"$bin/simulate" --scene paper_object --frames 3 --out "$tmp/unused.trc" --truth-out "$tmp/truth.yaml"
"$bin/check_model_file" "$tmp/truth.yaml" --print >"$tmp/truth.values"
[ "$(wc -l <"$tmp/truth.values")" -eq 20 ]
autosave="$tmp/models/autosave.yaml"

start_simulator() {
  "$bin/simulator_node" __name:=simulator _scene:=paper_object >>"$tmp/simulator.log" 2>&1 &
  sim_pid=$!
  pids+=("$sim_pid")
}
common=(_model:="$here/config/models/paper_object.yaml" _model_dir:="$tmp/models"
        _window_frames:=100 _population:=60 _generations_per_update:=5 _seed:=3)
start_estimator() {  # start_estimator LOG [extra params]; sets est_pid
  local log=$1; shift
  "$bin/estimator_node" __name:=estimator "${common[@]}" "$@" >"$log" 2>&1 &
  est_pid=$!
  pids+=("$est_pid")
}
# first_estimate FILE: waits for the first ~estimate echoed (CSV) into FILE; prints
# "generation max_relative_error" against the truth.
first_estimate() {
  for _ in $(seq 300); do [ "$(wc -l <"$1")" -ge 2 ] && break; sleep 0.1; done
  [ "$(wc -l <"$1")" -ge 2 ] || { echo "no estimate in $1" >&2; return 1; }
  awk -F, -v truth="$tmp/truth.values" '
    BEGIN { while ((getline line < truth) > 0) { split(line, f, " "); t[f[1]] = f[2] } }
    NR == 1 { for (i = 1; i <= NF; ++i) col[$i] = i; next }
    NR == 2 { n = 0; while (("field.parameter_names" n) in col) ++n
              worst = 0
              for (k = 0; k < n; ++k) {
                name = $(col["field.parameter_names" k]); v = $(col["field.values" k])
                if (!(name in t)) { print "unknown parameter " name > "/dev/stderr"; exit 1 }
                e = (v - t[name]) / t[name]; if (e < 0) e = -e; if (e > worst) worst = e }
              printf "%d %.6f\n", $(col["field.generation"]), worst }' "$1"
}

# 1. Identify with autosave every 0.5 s; read the autosave in a loop meanwhile.
start_simulator
start_estimator "$tmp/run1.log" _autosave_path:=autosave.yaml _autosave_period_sec:=0.5
(
  ok=0 bad=0
  while [ ! -e "$tmp/stop_checker" ]; do
    if [ -e "$autosave" ]; then
      if "$bin/check_model_file" "$autosave" 2>>"$tmp/checker.err"; then ok=$((ok + 1)); else bad=$((bad + 1)); fi
      echo "$ok $bad" >"$tmp/checker.count"
    fi
    sleep 0.05
  done
) &
checker=$!
pids+=("$checker")
converged=0
for _ in $(seq 240); do
  sleep 0.5
  kill -0 "$est_pid" || { echo "FAIL: estimator_node died"; cat "$tmp/run1.log"; exit 1; }
  [ -e "$autosave" ] || continue
  if "$bin/check_model_file" "$autosave" --compare "$tmp/truth.yaml" --tolerance 0.005 >"$tmp/cmp" 2>&1; then
    converged=1; break
  fi
done
[ "$converged" = 1 ] || { echo "FAIL: no autosave within 0.5 % of the truth in 120 s"; cat "$tmp/cmp"; exit 1; }
echo "converged: autosave $(cat "$tmp/cmp"), generation $(sed -n 's/^ *generations: //p' "$autosave")"
# More autosaves while the checker reads, until it has read at least 10 times (on a loaded
# machine a read takes longer than an autosave period; at most 60 s).
for _ in $(seq 300); do
  read -r ok _ <"$tmp/checker.count" 2>/dev/null || ok=0
  [ "${ok:-0}" -ge 10 ] && break
  sleep 0.2
done
sleep 0.6  # at least one more autosave written while being read
kill -9 "$est_pid"
wait "$est_pid" 2>/dev/null || true
touch "$tmp/stop_checker"
wait "$checker" 2>/dev/null || true
read -r ok bad <"$tmp/checker.count"
echo "autosave read $ok times while being rewritten: $bad failures"
[ "$bad" -eq 0 ] || { echo "FAIL: the autosave did not parse"; cat "$tmp/checker.err"; exit 1; }
[ "$ok" -ge 10 ] || { echo "FAIL: too few reads ($ok)"; exit 1; }
"$bin/check_model_file" "$autosave" --compare "$tmp/truth.yaml" --tolerance 0.005
cp "$autosave" "$tmp/saved.yaml"

kill -INT "$sim_pid"; wait "$sim_pid" 2>/dev/null || true

# first_run NAME [params]: starts the estimator, subscribes to its ~estimate, then starts the
# stream, so that the very first estimate is caught; prints "generation max_relative_error".
first_run() {
  local name=$1; shift
  start_estimator "$tmp/$name.log" _update_rate_hz:=100.0 "$@"
  for _ in $(seq 100); do grep -q /estimator/reset <<<"$(rosservice list 2>/dev/null || true)" && break; sleep 0.2; done
  rostopic echo -n 1 -p /estimator/estimate >"$tmp/$name.csv" 2>/dev/null &
  pids+=($!)
  for _ in $(seq 100); do
    rostopic info /estimator/estimate 2>/dev/null | sed -n '/Subscribers/,$p' | grep -q rostopic && break
    sleep 0.2
  done
  start_simulator
  first_estimate "$tmp/$name.csv"
  kill -INT "$est_pid" "$sim_pid"; wait "$est_pid" "$sim_pid" 2>/dev/null || true
}

# 2. Restart from the autosave: the first estimate is already close to the truth (default engine,
#    then the paper's preset).
first_run resumed _initial_model:="$tmp/saved.yaml" >"$tmp/resumed.result"
read -r gen err <"$tmp/resumed.result"
grep -q "resuming from" "$tmp/resumed.log" || { echo "FAIL: did not resume"; cat "$tmp/resumed.log"; exit 1; }
echo "resumed: first estimate at generation $gen, max relative error $err"
awk -v g="$gen" -v e="$err" 'BEGIN { exit !(g <= 100 && e <= 0.01) }' ||
  { echo "FAIL: resumed (default engine) first estimate at generation $gen, error $err"; exit 1; }

first_run resumed_paper _initial_model:="$tmp/saved.yaml" _preset:=paper >"$tmp/resumed_paper.result"
read -r genp errp <"$tmp/resumed_paper.result"
grep -q "resuming from" "$tmp/resumed_paper.log" || { echo "FAIL: did not resume"; cat "$tmp/resumed_paper.log"; exit 1; }
echo "resumed, paper preset: first estimate at generation $genp, max relative error $errp"

# 3. For comparison, a start from scratch with the paper's preset: its first estimate is far off.
first_run scratch_paper _initial_model:="$tmp/models/none.yaml" _preset:=paper >"$tmp/scratch.result"
read -r gen0 err0 <"$tmp/scratch.result"
echo "from scratch, paper preset: first estimate at generation $gen0, max relative error $err0"

awk -v g="$genp" -v e="$errp" -v e0="$err0" 'BEGIN { exit !(g <= 100 && e <= 0.01 && e0 > 0.05 && e0 > 5 * e) }' ||
  { echo "FAIL: resumed (gen $genp, err $errp) vs scratch (err $err0), paper preset"; exit 1; }
echo "crash-restart ok"
