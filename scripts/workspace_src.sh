# shellcheck shell=bash
# Sourced by scripts/build: the package's entry in the catkin workspace's src/.
#   workspace_src REPOSITORY_ROOT WORKSPACE_SRC_DIR
# makes WORKSPACE_SRC_DIR/motion_model_estimation a directory of relative links to the
# repository's top-level entries (the git-tracked and untracked-but-not-ignored ones; every entry
# but .ws and .git without git), and removes the links to entries that are gone.
# Not one link to the repository root: the workspace lies inside the repository (.ws/), and
# rosrun searches the package directory with `find -L`, which would run through the link back to
# an ancestor (two "find: File system loop detected" lines before every rosrun) and find every
# tool a second time under .ws/devel. Links to the entries keep .ws out of the package directory,
# so rosrun finds exactly one copy of each tool (the devel space's).
workspace_src() {
  local repo=$1 src=$2 pkg name target
  pkg="$src/motion_model_estimation"
  mkdir -p "$src"
  [ -L "$pkg" ] && rm -f "$pkg"  # the former layout: one link to the repository root
  mkdir -p "$pkg"
  local names
  if git -C "$repo" rev-parse --show-toplevel >/dev/null 2>&1; then
    names=$(git -C "$repo" ls-files --cached --others --exclude-standard | cut -d/ -f1 | sort -u)
  else
    names=$(cd "$repo" && find . -mindepth 1 -maxdepth 1 ! -name .ws ! -name .git -printf '%f\n' | sort)
  fi
  local rel
  rel=$(realpath --relative-to="$pkg" "$repo")
  for name in $names; do
    [ -e "$repo/$name" ] || continue  # deleted but still in git's index
    target="$rel/$name"
    [ "$(readlink "$pkg/$name" 2>/dev/null)" = "$target" ] || ln -sfn "$target" "$pkg/$name"
  done
  for name in "$pkg"/* "$pkg"/.[!.]*; do
    [ -L "$name" ] || continue
    if [ ! -e "$name" ] || ! grep -qxF "$(basename "$name")" <<<"$names"; then rm -f "$name"; fi
  done
}
