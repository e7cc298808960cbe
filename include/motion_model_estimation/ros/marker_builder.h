// Converts the estimator's VisualisationSnapshot (live/visualisation_snapshot.h, ROS-free) into
// the rviz MarkerArray: observed and predicted particles, the long reconstruction (the paper's
// Fig. 2), bonds coloured by their value, a status text. Namespaces and ids are fixed, so each
// publication replaces the previous one in rviz.
#pragma once

#include <string>

#include <visualization_msgs/MarkerArray.h>

#include "motion_model_estimation/live/visualisation_snapshot.h"

namespace mme {

/// How the snapshot is drawn.
struct MarkerStyle {
  std::string frame_id;              ///< the frame the snapshot's positions are in
  double particle_diameter_m = 0.02;  ///< [m] drawn particle size; lines and text scale with it
};

/// Stable namespaces: "observed", "predicted", "reconstruction" (ids 0, 1), "bonds", "status";
/// stamped with the snapshot's stamp_s.
visualization_msgs::MarkerArray buildMarkers(const VisualisationSnapshot& snapshot,
                                             const MarkerStyle& style);

}  // namespace mme
