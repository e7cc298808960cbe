// estimator_node: online identification (see config/estimator.yaml for its parameters).
#include <ros/ros.h>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/ros/estimator_node.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "estimator_node");
  ros::NodeHandle nh, pnh("~");
  try {
    mme::EstimatorNode node(nh, pnh, mme::readEstimatorOptions(pnh));
    node.run();
  } catch (const mme::InputError& e) {
    ROS_FATAL("estimator_node: %s", e.what());
    return 2;
  }
  return 0;
}
