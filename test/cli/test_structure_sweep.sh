#!/usr/bin/env bash
# Structure selection on windows of every real capture and of the crash reproducer (40, 80, 100
# and 240 frames, two offsets each, 2 s per selection): every run ends with a chosen level or a
# clear refusal, none fails, nothing crashes; a window longer than its capture is named. The
# same sweep runs under the sanitizers in `scripts/test --sanitize`; the long one with its
# timings is scripts/sweep-structure.
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
source "$here/scripts/env.sh"
bin="$here/.ws/devel/lib/motion_model_estimation"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT

"$bin/structure_sweep" --max-time-s 2 --lengths 40,80,100,240 --offsets 2 --csv "$tmp/sweep.csv" \
  "$here"/test/data/crash/window_0_99.trc "$here"/test/data/real/*.trc "$here"/test/data/real/*.c3d \
  | tee "$tmp/out.log"
grep -q " 0 failed" "$tmp/out.log"
# Every capture was swept, every run has an outcome, and the reproducer's 240-frame window is
# named as too long for its 100 frames.
for f in window_0_99 arm26_elbow_flex motion_capture_walk subject01_walk1 Sample01_Eb015pi \
         Sample02_dec_real Sample02_pc_int Sample26_Walking_Hybrid_1_1; do
  grep -q "^$f" "$tmp/sweep.csv" || { echo "no run on $f"; exit 1; }
done
! grep -vE '^capture,|,(chosen|refused|skipped),' "$tmp/sweep.csv"
grep -q 'window_0_99.trc,0,240,43,skipped,.*cannot be cut from 100 frames' "$tmp/sweep.csv"
# The reproducer's windows that crashed (80 and 100 frames from its start) now choose a level.
grep -q 'window_0_99.trc,0,80,43,chosen' "$tmp/sweep.csv"
grep -q 'window_0_99.trc,0,100,43,chosen' "$tmp/sweep.csv"
# Bad arguments: exit 2 with the reason.
set +e
"$bin/structure_sweep" --lengths 0 x.trc 2>"$tmp/err"; rc=$?
set -e
[ "$rc" -eq 2 ] && grep -q "not a frame count" "$tmp/err"
echo "structure sweep ok"
