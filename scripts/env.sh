# Sourced by the scripts: PATH without pyenv, the workspace's setup, ROS logs inside .ws/.
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
export ROS_HOME="$here/.ws/ros_home"
mkdir -p "$ROS_HOME"
# shellcheck disable=SC1091
set +u; source "$here/.ws/devel/setup.bash"; set -u
# shellcheck disable=SC1091
source "$here/scripts/ros_network.sh"
