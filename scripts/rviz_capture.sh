# shellcheck shell=bash disable=SC2154,SC2034
# Sourced by scripts/screenshot and scripts/replay-real: rviz on a virtual X display (Xvfb) and
# the grab of its screen. Each function prints "WHO: reason" on stderr and returns 1 on failure.
#   rviz_capture_deps WHO SETUP       SETUP=1: scripts/setup --screenshot --no-build first (rviz,
#                                     Xvfb, ImageMagick); then checks that they are there
#   xvfb_start WHO WORK               Xvfb on a display it picks itself (-displayfd); exports
#                                     DISPLAY, sets xvfb_pid (logs in WORK)
#   stop_process PID                  SIGINT, up to 20 s for it to end, then SIGTERM (roslaunch)
#   grab_screen WHO OUT WORK          the whole screen into OUT (PNG, written atomically); a blank
#                                     grab (rviz not drawn: next to no variation) fails
# Needs `here` (the repository root) set and, for rviz_capture_deps's rviz check, scripts/env.sh
# sourced. (SC2154/SC2034: `here` comes from the caller, xvfb_pid and DISPLAY go to it.)
xvfb_pid=""

rviz_capture_deps() {
  local who=$1 setup=$2 tool
  if [ "$setup" = 1 ]; then
    "$here/scripts/setup" --screenshot --no-build >&2 || { echo "$who: scripts/setup --screenshot failed" >&2; return 1; }
  fi
  for tool in Xvfb import convert; do
    command -v "$tool" >/dev/null || { echo "$who: $tool not found (scripts/setup --screenshot installs it)" >&2; return 1; }
  done
  rospack find rviz >/dev/null 2>&1 || { echo "$who: rviz not found (scripts/setup --screenshot installs it)" >&2; return 1; }
}

xvfb_start() {
  local who=$1 work=$2
  rm -f "$work/display"
  Xvfb -displayfd 3 -screen 0 1280x800x24 -nolisten tcp 3>"$work/display" >"$work/xvfb.log" 2>&1 &
  xvfb_pid=$!
  for _ in $(seq 50); do [ -s "$work/display" ] && break; sleep 0.1; done
  [ -s "$work/display" ] || { tail -5 "$work/xvfb.log" >&2; echo "$who: Xvfb did not start" >&2; return 1; }
  DISPLAY=":$(head -1 "$work/display")"
  export DISPLAY
}

stop_process() {
  local pid=$1
  [ -n "$pid" ] && kill -0 "$pid" 2>/dev/null || return 0
  kill -INT "$pid" 2>/dev/null || true
  for _ in $(seq 100); do kill -0 "$pid" 2>/dev/null || break; sleep 0.2; done
  kill -TERM "$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
}

grab_screen() {
  local who=$1 out=$2 work=$3 tmp spread
  mkdir -p "$(dirname "$out")"
  tmp="$(cd "$(dirname "$out")" && pwd)/.$(basename "$out").$$.tmp"
  if ! import -display "$DISPLAY" -window root "png:$tmp" 2>"$work/import.log"; then
    cat "$work/import.log" >&2; rm -f "$tmp"
    echo "$who: import could not grab $DISPLAY" >&2; return 1
  fi
  # A blank screen (rviz not drawn, black GL view) has next to no variation.
  spread=$(convert "$tmp" -colorspace gray -format '%[fx:standard_deviation]' info: 2>/dev/null || echo 0)
  if ! awk -v s="$spread" 'BEGIN { exit !(s > 0.02) }'; then
    rm -f "$tmp"; echo "$who: the screen grab is blank (std dev $spread)" >&2; return 1
  fi
  mv -f "$tmp" "$out"
}
