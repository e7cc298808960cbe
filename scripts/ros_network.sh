# Sourced by scripts/env.sh and by `scripts/test --sanitize` (which uses its own workspace).
# ROS nodes advertise themselves by host name. Where the machine's name does not resolve (a
# fresh container or chroot without it in /etc/hosts), every node on this machine is reached
# through localhost instead; an explicit ROS_HOSTNAME or ROS_IP is left alone.
if [ -z "${ROS_HOSTNAME:-}" ] && [ -z "${ROS_IP:-}" ] && ! getent hosts "$(uname -n)" >/dev/null 2>&1; then
  export ROS_HOSTNAME=localhost
fi
getent hosts localhost >/dev/null 2>&1 ||
  echo "ros_network.sh: warning: 'localhost' does not resolve (no /etc/hosts?): roslaunch," \
       "rostest and roscore will fail; add '127.0.0.1 localhost' to /etc/hosts" >&2
