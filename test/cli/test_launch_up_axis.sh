#!/usr/bin/env bash
# replay.launch's up_axis rule (decided in the launch file, handed to view.launch's `display`
# frame): auto (the default) turns a .trc capture y up (OpenSim's convention, any case of the
# extension) and anything else (a bag, a .c3d file) z up; an explicit up_axis overrides it. Read
# from the command roslaunch would run for the display_frame node (roslaunch --args: no master).
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
# shellcheck disable=SC1091
source "$here/scripts/env.sh"

rotation() {  # rotation ARGS... : the display frame's rotation for replay.launch ARGS
  roslaunch --args display_frame motion_model_estimation replay.launch model:=/m.yaml rviz:=true "$@" |
    grep -o 'rotation: {[^}]*}'
}
y_up='rotation: {x: 0.70710678, w: 0.70710678}'
z_up='rotation: {w: 1.0}'
x_up='rotation: {y: -0.70710678, w: 0.70710678}'
check() {  # check EXPECTED ARGS...
  local expected=$1; shift
  local got; got=$(rotation "$@")
  [ "$got" = "$expected" ] || { echo "FAIL: $*: got '$got', expected '$expected'"; exit 1; }
  echo "ok: $* -> $got"
}
check "$y_up" bag:=/data/walk.trc
check "$y_up" bag:=/data/WALK.TRC
check "$z_up" bag:=/data/walk.c3d
check "$z_up" bag:=/data/walk.bag
check "$z_up" bag:=/data/walk.trc up_axis:=z
check "$x_up" bag:=/data/walk.bag up_axis:=x
