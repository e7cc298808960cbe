// Publishes a model's or built-in scene's motion live as MarkerFrame at its frame rate.
#pragma once

#include <ros/ros.h>

#include <cstdint>
#include <random>
#include <string>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/simulator.h"

namespace mme {

/// Options of simulator_node, filled from private params (see config/simulator.yaml).
struct SimulatorPublisherOptions {
  std::string model_path;      ///< ~model: model file (exclusive with scene)
  std::string scene;           ///< ~scene: built-in scene name
  std::string frame_id;        ///< ~frame_id: overrides the model's frame_id when not empty
  double rate_scale = 1.0;     ///< ~rate_scale: publish at rate_scale x the model's frame rate
  double noise_std_m = 0.0;    ///< ~noise_std_m: Gaussian noise on published positions [m]
  int seed = 1;                ///< ~seed: noise seed
  int max_frames = 0;          ///< ~max_frames: stop after this many frames (0 = never)
  double frame_rate_hz = 0.0;  ///< ~frame_rate_hz: needed when the model has none
  /// ~step_param: a parameter ("<bond_type>/<param>" or "gravity/x|y|z") multiplied by
  /// step_factor once step_after_frames frames have been published ("" = no step)
  std::string step_param;
  double step_factor = 1.0;    ///< ~step_factor: multiplier applied at the step
  int step_after_frames = 0;   ///< ~step_after_frames: frames published before the step (>= 1)
};

/// Checks option values; empty string = valid, else the reason naming the parameter.
std::string validateOptions(const SimulatorPublisherOptions& options);

class SimulatorPublisher {
 public:
  /// Loads the model (throws InputError) and advertises `markers`.
  SimulatorPublisher(ros::NodeHandle& nh, const SimulatorPublisherOptions& options);
  /// Publishes until shutdown or max_frames.
  void spin();

 private:
  void publishFrame();
  /// Applies the configured parameter step (once).
  void applyStep();

  SimulatorPublisherOptions options_;
  Model model_;
  Simulator simulator_;
  State state_;
  ros::Publisher publisher_;
  uint32_t frame_number_ = 0;
  std::mt19937_64 rng_;
  ParamRef step_ref_;          ///< resolved ~step_param (bond_type -2 = no step)
};

}  // namespace mme
