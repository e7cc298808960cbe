#!/usr/bin/env bash
# rosrun from the README's shell (source scripts/env.sh) prints nothing of its own: no
# "find: File system loop detected" line (the workspace's src entry must not lead back to the
# repository, an ancestor of the workspace), and finds exactly one copy of each tool (the devel
# space's), so it never asks which one to run.
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
# shellcheck disable=SC1091
source "$here/scripts/env.sh"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT

rosrun motion_model_estimation identify --help </dev/null >"$tmp/out" 2>"$tmp/err" ||
  { echo "rosrun identify --help failed:"; cat "$tmp/out" "$tmp/err"; exit 1; }
grep -q -- "--trajectory" "$tmp/out" || { echo "no usage from identify --help:"; cat "$tmp/out"; exit 1; }
[ ! -s "$tmp/err" ] || { echo "rosrun printed on stderr:"; cat "$tmp/err"; exit 1; }

# rosrun's own search (its --debug shows it): the catkin libexec/share directories and the
# package directory, with find -L. One executable named identify in all of them.
pkgdir=$(rospack find motion_model_estimation)
mapfile -t dirs < <(catkin_find --without-underlays --libexec --share motion_model_estimation)
find -L "${dirs[@]}" "$pkgdir" -name identify -type f -perm /111 2>"$tmp/find_err" | uniq >"$tmp/found"
[ ! -s "$tmp/find_err" ] || { echo "find over the package reports:"; cat "$tmp/find_err"; exit 1; }
[ "$(wc -l <"$tmp/found")" -eq 1 ] || { echo "rosrun finds more than one identify:"; cat "$tmp/found"; exit 1; }
echo "ok: rosrun identify --help printed nothing on stderr; one identify found ($(cat "$tmp/found"))"
