// Where the sensor muscles go: the sensor pairs (the most varying distances) and the muscles'
// pairs (the model's bonds, the sensors, each particle's nearest neighbours and the anchors).
#pragma once

#include <cstddef>
#include <vector>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/identification/muscles/sensor_muscles.h"

namespace mme::sensor_muscles {

/// A pair of particles and its distance over the frames where both are seen.
struct PairStats {
  int a = -1, b = -1;
  double mean_m = 0.0, std_m = 0.0;
  int seen = 0;
};

/// Where the sensors and muscles go.
struct Layout {
  std::vector<PairStats> sensors, muscles;
  /// Per muscle: its own stiffness is held at 0 (a muscle to an anchor, with
  /// SensorMuscleOptions::anchor_stiffness kNone).
  std::vector<char> no_own_stiffness;
};

/// The linear unknowns of a layout: muscles x (2 sensors + 3).
size_t unknownsOf(const Layout& layout);

/// Sensors and muscles; `anchor` flags the particles addAnchors added (no sensor, no neighbour).
Layout chooseLayout(const Model& passive, const Trajectory& data, const std::vector<char>& anchor,
                    const SensorMuscleOptions& o);

/// chooseLayout within SensorMuscleOptions::max_unknowns: a layout above it reads fewer sensors
/// (the most varying pairs kept). Throws InputError when no sensor or muscle can be placed, or
/// when one sensor is still too many.
Layout chooseLayoutWithinUnknowns(const Model& passive, const Trajectory& data,
                                  const std::vector<char>& anchor, const SensorMuscleOptions& o);

}  // namespace mme::sensor_muscles
