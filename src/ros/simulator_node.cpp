// simulator_node: streams a model's or scene's motion as MarkerFrame (see config/simulator.yaml).
#include <ros/ros.h>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/ros/param_utils.h"
#include "motion_model_estimation/ros/simulator_publisher.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "simulator_node");
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  mme::SimulatorPublisherOptions options;
  std::string bad;
  const bool types_ok = mme::readParam(pnh, "model", &options.model_path, &bad) &&
                        mme::readParam(pnh, "scene", &options.scene, &bad) &&
                        mme::readParam(pnh, "frame_id", &options.frame_id, &bad) &&
                        mme::readParam(pnh, "rate_scale", &options.rate_scale, &bad) &&
                        mme::readParam(pnh, "noise_std_m", &options.noise_std_m, &bad) &&
                        mme::readParam(pnh, "seed", &options.seed, &bad) &&
                        mme::readParam(pnh, "max_frames", &options.max_frames, &bad) &&
                        mme::readParam(pnh, "frame_rate_hz", &options.frame_rate_hz, &bad) &&
                        mme::readParam(pnh, "step_param", &options.step_param, &bad) &&
                        mme::readParam(pnh, "step_factor", &options.step_factor, &bad) &&
                        mme::readParam(pnh, "step_after_frames", &options.step_after_frames, &bad);
  if (types_ok) bad = mme::validateOptions(options);
  if (!bad.empty()) {
    ROS_FATAL("simulator_node: %s", bad.c_str());
    return 2;
  }
  try {
    mme::SimulatorPublisher publisher(nh, options);
    publisher.spin();
  } catch (const mme::InputError& e) {
    ROS_FATAL("simulator_node: %s", e.what());
    return 2;
  }
  return 0;
}
