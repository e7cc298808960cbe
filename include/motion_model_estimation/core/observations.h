// A trajectory prepared for a cost: checked against the model, its frame rate resolved, and its
// occluded samples filled with finite stand-ins. Every cost starts from this (one copy of the
// set-up each cost needs; the cost's own terms decide which samples they use).
#pragma once

#include <cstdint>
#include <vector>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"

namespace mme {

struct Observations {
  int particles = 0;
  int frames = 0;
  double frame_rate_hz = 0.0;  ///< the model's when > 0, else the trajectory's
  double frame_period_s = 0.0;
  /// frames x 3 x particles, flat: (t, i, c) at (t * particles + i) * 3 + c. An occluded sample
  /// holds the particle's last known position (else its first known, else the model's): finite,
  /// so nothing downstream sees NaN; the terms that would use it are dropped by the cost.
  std::vector<double> positions_m;
  std::vector<uint8_t> occluded;  ///< frames x particles, 1 = not observed

  bool isOccluded(int t, int i) const { return occluded[static_cast<size_t>(t) * particles + i] != 0; }
  const double* position(int t, int i) const {
    return positions_m.data() + (static_cast<size_t>(t) * particles + i) * 3;
  }
};

/// Checks that `trajectory` holds the model's particles as markers (see remapMarkers) with
/// consistent sizes and a frame rate (the model's wins), and fills occluded samples. Throws
/// InputError with a readable reason otherwise. A single frame needs the model's frame rate.
Observations prepareObservations(const Model& model, const Trajectory& trajectory);

}  // namespace mme
