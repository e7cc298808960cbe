#include "motion_model_estimation/core/observations.h"

#include <cmath>
#include <sstream>

#include "motion_model_estimation/core/error.h"

namespace mme {

Observations prepareObservations(const Model& model, const Trajectory& trajectory) {
  const std::string err = validateModel(model);
  if (!err.empty()) throw InputError("model: " + err);
  const int n = static_cast<int>(model.particles.size());
  const int num_frames = trajectory.numFrames();
  if (trajectory.numMarkers() != n) {
    std::ostringstream e;
    e << "trajectory has " << trajectory.numMarkers() << " markers but the model has " << n
      << " particles (remap the markers to the model's particles first)";
    throw InputError(e.str());
  }
  if (trajectory.positions_m.size() != static_cast<size_t>(n) * num_frames ||
      trajectory.occluded.size() != static_cast<size_t>(n) * num_frames)
    throw InputError("trajectory: positions/occluded do not hold frames x markers samples");
  if (num_frames < 1) throw InputError("trajectory has no frames");
  // A single frame has no time base of its own: the step must come from the model.
  if (num_frames == 1 && !(model.frame_rate_hz > 0.0))
    throw InputError("a single-frame (static equilibrium) data set needs the model's frame_rate_hz");
  const double rate_hz = model.frame_rate_hz > 0.0 ? model.frame_rate_hz : trajectory.frame_rate_hz;
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz))
    throw InputError("no frame rate: set frame_rate_hz in the model or the data");

  Observations o;
  o.particles = n;
  o.frames = num_frames;
  o.frame_rate_hz = rate_hz;
  o.frame_period_s = 1.0 / rate_hz;
  o.occluded.assign(trajectory.occluded.begin(), trajectory.occluded.end());
  const size_t n3 = 3 * static_cast<size_t>(n);
  o.positions_m.assign(n3 * num_frames, 0.0);
  for (int i = 0; i < n; ++i) {
    int first_known = -1;
    for (int t = 0; t < num_frames; ++t)
      if (!trajectory.isOccluded(t, i)) { first_known = t; break; }
    Eigen::Vector3d fill = first_known >= 0 ? trajectory.position(first_known, i)
                                            : model.particles[i].position_m;
    for (int t = 0; t < num_frames; ++t) {
      if (!trajectory.isOccluded(t, i)) fill = trajectory.position(t, i);
      for (int k = 0; k < 3; ++k) o.positions_m[t * n3 + 3 * i + k] = fill[k];
    }
  }
  return o;
}

}  // namespace mme
