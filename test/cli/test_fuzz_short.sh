#!/usr/bin/env bash
# A short fuzzing run (scripts/fuzz, docs/reliability.md): builds the libFuzzer harnesses
# incrementally in .ws/fuzz-build and runs each ~12 s on its seed corpus; fails on any crash,
# sanitizer report, leak, timeout or out-of-memory. New inputs go to a temporary directory.
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
source "$here/scripts/env.sh"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
"$here/scripts/fuzz" --seconds "${MME_FUZZ_SECONDS:-12}" --work "$tmp"
echo "fuzz short run ok"
