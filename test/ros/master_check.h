// The rostest nodes (test/ros/*.cpp) need a ROS master, which rostest starts: run by hand
// without one, roscpp retries its first registration for ever ("Failed to contact master ...
// Retrying..."). Their main() asks first and ends with a message saying how to run them.
#pragma once

#include <ros/ros.h>

#include <cstdio>

namespace mmetest {

/// True when the master at ROS_MASTER_URI answers (call after ros::init); otherwise prints why
/// this node cannot run and how to run it, and returns false.
inline bool masterAnswers() {
  if (ros::master::check()) return true;
  std::fprintf(stderr,
               "%s: no ROS master answers at %s; this test runs under rostest, which starts one: "
               "`scripts/test`, `catkin_make run_tests`, or `rostest motion_model_estimation "
               "<its .test file in test/ros>`\n",
               ros::this_node::getName().c_str(), ros::master::getURI().c_str());
  return false;
}

}  // namespace mmetest
