// Builds the rviz MarkerArray of the estimator: observed and predicted particles, the long
// reconstruction (the paper's Fig. 2), bonds coloured by strain or local cost, a status text.
// Namespaces and ids are fixed, so each publication replaces the previous one in rviz.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <ros/time.h>
#include <visualization_msgs/MarkerArray.h>

namespace mme {

struct MarkerScene {
  std::string frame_id;
  ros::Time stamp;
  double particle_diameter_m = 0.02;
  std::vector<Eigen::Vector3d> observed;        ///< latest observed frame
  std::vector<uint8_t> observed_occluded;
  std::vector<Eigen::Vector3d> predicted;       ///< one-step prediction of that frame (may be empty)
  std::vector<Eigen::Vector3d> reconstructed;   ///< long reconstruction at that frame (may be empty)
  std::vector<std::vector<Eigen::Vector3d>> reconstruction_trails;  ///< per particle path
  std::vector<std::pair<int, int>> bonds;       ///< particle index pairs
  std::vector<double> bond_values;              ///< colour value per bond, mapped from [lo, hi]
  double bond_value_lo = -0.1;
  double bond_value_hi = 0.1;
  std::string text;
};

/// Stable namespaces: "observed", "predicted", "reconstruction" (ids 0, 1), "bonds", "status".
visualization_msgs::MarkerArray buildMarkers(const MarkerScene& scene);

}  // namespace mme
