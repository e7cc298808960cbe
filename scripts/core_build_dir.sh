# Sourced by scripts/bench and test/cli/test_core_build.sh: the plain-CMake (MME_CORE_ONLY) build
# directory both share, so that the core is compiled once for the peer benchmark and the ROS-free
# tools: ${XDG_CACHE_HOME:-~/.cache}/motion_model_estimation/core-<repository directory name>-
# <hash of its path>, or $MME_CORE_BUILD when set. Outside the repository for the sanitizer
# workspace's reason (scripts/test): rosrun searches the package directory with `find -L` and
# would find a second copy of every tool built there.
#   core_build_dir REPOSITORY_ROOT   prints the directory (fails when neither XDG_CACHE_HOME nor
#                                    HOME is set and MME_CORE_BUILD is not)
core_build_dir() {
  if [ -n "${MME_CORE_BUILD:-}" ]; then echo "$MME_CORE_BUILD"; return 0; fi
  local cache=${XDG_CACHE_HOME:-}
  if [ -z "$cache" ]; then
    [ -n "${HOME:-}" ] || { echo "neither XDG_CACHE_HOME nor HOME is set: set MME_CORE_BUILD to a directory for the core build" >&2; return 1; }
    cache=$HOME/.cache
  fi
  echo "$cache/motion_model_estimation/core-$(basename "$1")-$(printf '%s' "$1" | sha1sum | cut -c1-8)"
}
