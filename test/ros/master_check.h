// The rostest nodes (test/ros/*.cpp) need a ROS master, which rostest starts: run by hand
// without one, roscpp retries its first registration for ever ("Failed to contact master ...
// Retrying..."). Their main() asks first and ends with a message saying how to run them.
#pragma once

#include <gtest/gtest.h>
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

/// A rostest node's whole main(): gtest and ROS initialised as `node_name`, the master checked
/// (2 when none answers), the tests run with one spinner thread serving the callbacks.
inline int runRosTests(int argc, char** argv, const char* node_name) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, node_name);
  if (!masterAnswers()) return 2;
  ros::NodeHandle nh;  // keeps the node alive for the spinner
  ros::AsyncSpinner spinner(1);
  spinner.start();
  const int rc = RUN_ALL_TESTS();
  spinner.stop();
  return rc;
}

}  // namespace mmetest
