# Sourced by every script and test that starts its own ROS master (scripts/demo, soak,
# screenshot; test/cli/test_crash_restart.sh, test_estimator_bad_input.sh,
# test_estimator_params.sh), so that they all pick its port the same way:
#   source "$here/scripts/free_port.sh"
#   port=$(free_port demo) || exit 1
#
# free_port [WHO]: prints a TCP port of 20000-60000 on which nothing listens at 127.0.0.1
# (50 random tries; a refused connection means the port is free). When every try answers it
# says so on stderr, prefixed with WHO (e.g. the script's name), and returns 1.
# A port found free can still be taken before the master binds it; the random pick keeps two
# runs that start together from choosing the same one.
free_port() {
  local who=${1:-free_port} p
  for p in $(shuf -i 20000-60000 -n 50); do
    if ! (exec 3<>"/dev/tcp/127.0.0.1/$p") 2>/dev/null; then
      echo "$p"
      return 0
    fi
  done
  echo "$who: no free port for the ROS master (50 random ports of 20000-60000 on 127.0.0.1 were all in use)" >&2
  return 1
}
