// What the live node shows of the identification (the content of ~markers), without ROS: the
// latest observed frame, its one-step prediction from the two frames before it, the long
// reconstruction from the window start with each particle's trail (the paper's Fig. 2), the
// spring bonds with a colour value (strain or local cost) and a status text. The ROS layer's
// marker_builder only converts it into a MarkerArray.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/identification/online/online_estimator.h"

namespace mme {

/// What a bond's colour value is (~color_bonds_by).
enum class BondColouring {
  kStrain,     ///< length / rest length - 1 in the latest observed frame, shown over [-0.1, 0.1]
  kLocalCost,  ///< mean of its two particles' local costs [m^2], shown over [0, the largest]
};

/// "strain" or "local_cost"; false (and *colouring untouched) for anything else.
bool parseBondColouring(const std::string& text, BondColouring* colouring);
const char* bondColouringName(BondColouring colouring);

struct VisualisationSnapshot {
  double stamp_s = 0.0;                        ///< [s] input time of the latest observed frame
  std::vector<Eigen::Vector3d> observed;       ///< [m] latest observed frame, particle order
  std::vector<uint8_t> observed_occluded;      ///< 1 = occluded in it
  /// 1 = a fixed particle hidden in every frame of the window: a point of the model without a
  /// marker (the sensor muscles' anchors, 20 body extents away), not drawn as a particle.
  std::vector<uint8_t> model_only;
  std::vector<Eigen::Vector3d> predicted;      ///< [m] its one-step prediction (may be empty)
  std::vector<Eigen::Vector3d> reconstructed;  ///< [m] long reconstruction there (may be empty)
  std::vector<std::vector<Eigen::Vector3d>> reconstruction_trails;  ///< per particle path [m]
  std::vector<std::pair<int, int>> bonds;      ///< particle index pairs of the spring bonds
  std::vector<double> bond_values;             ///< colour value per bond, mapped from [lo, hi]
  double bond_value_lo = -0.1;
  double bond_value_hi = 0.1;
  std::string text;  ///< "generation G  cost C m^2  stable|UNSTABLE"
};

/// The snapshot of `window` (the estimator's window, particles as markers) under `model` (the
/// current best model) and `estimate` (generation, cost, stability, local costs). The
/// prediction needs 3 frames, the reconstruction a window start without occlusion; each is
/// left empty when it cannot be made. Nothing (std::nullopt) when the window has fewer than 2
/// frames or other markers than the model's particles.
std::optional<VisualisationSnapshot> makeVisualisationSnapshot(const Model& model,
                                                               const Trajectory& window,
                                                               const Estimate& estimate,
                                                               BondColouring colouring);

}  // namespace mme
