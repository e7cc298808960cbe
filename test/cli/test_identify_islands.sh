#!/usr/bin/env bash
# identify --islands: three islands in one process write the same model for 1 and 2 threads and
# as processes (--island-processes), a dead island's process ends the run with an error naming
# it, the run prints the per-island evaluations and accepted immigrants, and recovers
# paper_object; bad island options give exit 2 with a reason naming the option. MME_BIN_DIR
# runs it on another build's tools (e.g. the core-only build) instead of the workspace's.
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
if [ -n "${MME_BIN_DIR:-}" ]; then
  bin=$MME_BIN_DIR
else
  source "$here/scripts/env.sh"
  bin="$here/.ws/devel/lib/motion_model_estimation"
fi
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fail() { echo "test_identify_islands: $*" >&2; exit 1; }

"$bin/simulate" --scene paper_object --frames 40 --out "$tmp/data.trc" --truth-out "$tmp/truth.yaml" >/dev/null
sed -E 's/\{value: [^,]*, free: true/{free: true/' "$tmp/truth.yaml" >"$tmp/free.yaml"
run() {
  "$bin/identify" --model "$tmp/free.yaml" --trajectory "$tmp/data.trc" --population 30 --islands 3 \
    --migration-period 5 --migrants 2 "$@"
}
run --out "$tmp/one.yaml" --threads 1 >"$tmp/one.log" || fail "islands run failed: $(tail -3 "$tmp/one.log")"
run --out "$tmp/two.yaml" --threads 2 --quiet >"$tmp/two.log"
cmp <(grep -v wall_time_s "$tmp/one.yaml") <(grep -v wall_time_s "$tmp/two.yaml") ||
  fail "--islands 3 wrote different models for 1 and 2 threads"
run --out "$tmp/procs.yaml" --threads 1 --island-processes >"$tmp/procs.log" ||
  fail "--island-processes run failed: $(tail -3 "$tmp/procs.log")"
cmp <(grep -v wall_time_s "$tmp/one.yaml") <(grep -v wall_time_s "$tmp/procs.yaml") ||
  fail "--island-processes wrote another model than the islands as threads"
grep -q "^identify: 3 islands of population 30 in processes of their own" "$tmp/procs.log" ||
  fail "no processes line at the start"
# An island's process that dies (the test hook kills island 1 at its second generation): a
# non-zero exit with a line naming the island, within a bounded time (no hang).
set +e
MME_TEST_ISLAND_DIES=1 timeout 300 "$bin/identify" --model "$tmp/free.yaml" --trajectory "$tmp/data.trc" \
  --population 30 --islands 3 --island-processes --out "$tmp/dead.yaml" >/dev/null 2>"$tmp/dead.err"
code=$?
set -e
[ "$code" -ne 0 ] && [ "$code" -ne 124 ] || fail "a dead island's run exited $code (124: it hung)"
grep -q "^identify: error: island 1 (process [0-9]*) was killed by signal 9" "$tmp/dead.err" ||
  fail "no line naming the dead island: $(cat "$tmp/dead.err")"
[ ! -e "$tmp/dead.yaml" ] || fail "a run whose island died wrote a model"
grep -q "^identify: 3 islands of population 30 in this process (migration every 5 generations, 2 migrant(s) each, broadcast)" \
  "$tmp/one.log" || fail "no islands line at the start"
grep -E -q "^islands: 3, [1-9][0-9]* migration\(s\), best island [0-2]; per island evaluations \(immigrants accepted\):( [0-9]+ \([0-9]+\)){3}$" \
  "$tmp/one.log" || fail "no per-island line: $(grep '^islands' "$tmp/one.log")"
values() { grep -o 'value: [^,}]*' "$1" | awk '{print $2}'; }
paste <(values "$tmp/truth.yaml") <(values "$tmp/one.yaml") | awk '
  { e = ($2 - $1) / $1; if (e < 0) e = -e; if (e > worst) worst = e; n++ }
  END { printf "identify --islands 3: max relative error %.3g over %d parameters\n", worst, n;
        exit !(n == 20 && worst < 1e-6) }'

# Bad values: exit 2, one line naming the option.
bad() {
  local expect=$1; shift
  set +e
  "$bin/identify" --model "$tmp/free.yaml" --trajectory "$tmp/data.trc" --out "$tmp/bad.yaml" "$@" \
    >/dev/null 2>"$tmp/bad.err"
  local code=$?
  set -e
  [ "$code" -eq 2 ] || fail "identify $* exited $code, expected 2"
  grep -q -- "$expect" "$tmp/bad.err" || fail "identify $*: no '$expect' in: $(cat "$tmp/bad.err")"
}
bad "--islands" --islands 0
bad "--islands" --islands many
bad "--migration-period" --islands 2 --migration-period 0
bad "--migrants" --islands 2 --migrants 0
bad "need --islands N" --migrants 3
bad "need --islands N" --migration-period 4
bad "need --islands N" --island-processes
echo "test_identify_islands: ok"
