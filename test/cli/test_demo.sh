#!/usr/bin/env bash
# The README's demo command: demo.launch headless on paper_object, the identified model exported
# through ~export_model and compared with the truth. After 15 s of live stream every one of the
# 20 parameters must be within 1 % (it is usually exact to 1e-8 %).
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
log=$(mktemp); trap 'rm -f "$log"' EXIT
"$here/scripts/demo" --seconds 15 >"$log" 2>&1 || { cat "$log"; echo "scripts/demo failed"; exit 1; }
cat "$log"
line=$(grep '^compare: 20 parameters' "$log") || { echo "no comparison of 20 parameters"; exit 1; }
max=$(echo "$line" | sed 's/.*max \([0-9.eE+-]*\) %.*/\1/')
awk -v m="$max" 'BEGIN { exit !(m + 0 < 1.0) }' || { echo "max error $max % >= 1 %"; exit 1; }
echo "test_demo: max error $max %"
