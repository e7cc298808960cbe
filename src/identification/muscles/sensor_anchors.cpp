#include "sensor_anchors.h"

#include <algorithm>
#include <cstdio>
#include <limits>
#include <set>
#include <string>
#include <utility>

#include <Eigen/Core>

#include "fit_budget.h"
#include "motion_model_estimation/core/error.h"

namespace mme {

namespace sensor_muscles {

namespace {

/// The free particles' mean position over the data and their bounding box's diagonal [m].
struct DataBox {
  Eigen::Vector3d centre_m = Eigen::Vector3d::Zero();
  double diagonal_m = 0.0;
};

DataBox freeParticlesBox(const Model& model, const Trajectory& data) {
  const int n = static_cast<int>(model.particles.size()), frames = data.numFrames();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  long seen = 0;
  for (int t = 0; t < frames; ++t)
    for (int i = 0; i < n; ++i)
      if (!model.particles[i].fixed && !data.isOccluded(t, i)) {
        const Eigen::Vector3d& x = data.position(t, i);
        sum += x;
        lo = lo.cwiseMin(x);
        hi = hi.cwiseMax(x);
        ++seen;
      }
  if (seen == 0) throw InputError("sensor muscles: no free particle is ever seen");
  return {sum / static_cast<double>(seen), (hi - lo).norm()};
}

/// Appends the three fixed anchor particles (unique names anchor_x, _y, _z) at
/// centre + distance along each axis; returns their positions.
std::vector<Eigen::Vector3d> appendAnchorParticles(Model* model, const Eigen::Vector3d& centre_m,
                                                   double distance_m) {
  std::set<std::string> names;
  for (const Particle& p : model->particles) names.insert(p.name);
  std::vector<Eigen::Vector3d> at;
  for (int k = 0; k < 3; ++k) {
    Particle p;
    p.name = std::string("anchor_") + "xyz"[k];
    while (names.count(p.name)) p.name += "_";
    names.insert(p.name);
    p.fixed = true;
    p.position_m = centre_m + distance_m * Eigen::Vector3d::Unit(k);
    model->particles.push_back(p);
    at.push_back(p.position_m);
  }
  return at;
}

/// The data with the anchors' markers appended (named `anchor_names`, at `at`, seen in every frame).
Trajectory withAnchorMarkers(const Trajectory& data, const std::vector<std::string>& anchor_names,
                             const std::vector<Eigen::Vector3d>& at) {
  const int n = data.numMarkers(), frames = data.numFrames();
  Trajectory out;
  out.marker_names = data.marker_names;
  out.frame_rate_hz = data.frame_rate_hz;
  for (const std::string& name : anchor_names) out.marker_names.push_back(name);
  out.resize(frames);
  out.times_s = data.times_s;
  out.frame_numbers = data.frame_numbers;
  const int m = out.numMarkers();
  for (int t = 0; t < frames; ++t) {
    for (int i = 0; i < n; ++i) {
      out.position(t, i) = data.position(t, i);
      out.occluded[static_cast<size_t>(t) * m + i] = data.occluded[static_cast<size_t>(t) * n + i];
    }
    for (size_t k = 0; k < at.size(); ++k) {
      out.position(t, n + static_cast<int>(k)) = at[k];
      out.occluded[static_cast<size_t>(t) * m + n + k] = 0;
    }
  }
  return out;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

}  // namespace

std::vector<char> addAnchors(Model* model, Trajectory* data, double extents) {
  const int n = static_cast<int>(model->particles.size());
  const DataBox box = freeParticlesBox(*model, *data);
  const double distance_m = extents * std::max(box.diagonal_m, 1e-3);
  const std::vector<Eigen::Vector3d> at = appendAnchorParticles(model, box.centre_m, distance_m);
  std::vector<std::string> names;
  for (int k = 0; k < 3; ++k) names.push_back(model->particles[n + k].name);
  *data = withAnchorMarkers(*data, names, at);
  std::vector<char> anchor(n + 3, 0);
  for (int k = 0; k < 3; ++k) anchor[n + k] = 1;
  return anchor;
}

SensorMuscleOptions resolveAnchorStiffness(const Model& passive, double body_travel,
                                           const SensorMuscleOptions& o) {
  SensorMuscleOptions resolved = o;
  if (o.anchor_stiffness != AnchorStiffness::kAuto) return resolved;
  const bool tied = std::any_of(passive.particles.begin(), passive.particles.end(),
                                [](const Particle& p) { return p.fixed; });
  resolved.anchor_stiffness = !tied && body_travel >= o.travel_body_sizes ? AnchorStiffness::kNone
                                                                               : AnchorStiffness::kFitted;
  if (o.progress) {
    char line[240];
    std::snprintf(line, sizeof(line), "sensor muscles: the body travels %.2f body sizes over the data%s: "
                  "anchor muscles %s", body_travel, tied ? " (and the model ties it to the world)" : "",
                  resolved.anchor_stiffness == AnchorStiffness::kNone
                  ? "without a stiffness of their own" : "with a stiffness of their own");
    o.progress(line);
  }
  return resolved;
}

}  // namespace sensor_muscles

double bodyTravel(const Model& model, const Trajectory& data) {
  const int n = std::min(static_cast<int>(model.particles.size()), data.numMarkers());
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<Eigen::Vector3d> lo(n, Eigen::Vector3d::Constant(inf)), hi(n, Eigen::Vector3d::Constant(-inf));
  std::vector<double> sizes;
  for (int t = 0; t < data.numFrames(); ++t) {
    Eigen::Vector3d frame_lo = Eigen::Vector3d::Constant(inf), frame_hi = Eigen::Vector3d::Constant(-inf);
    int seen = 0;
    for (int i = 0; i < n; ++i) {
      if (model.particles[i].fixed || data.isOccluded(t, i)) continue;
      const Eigen::Vector3d x = data.position(t, i);
      lo[i] = lo[i].cwiseMin(x);
      hi[i] = hi[i].cwiseMax(x);
      frame_lo = frame_lo.cwiseMin(x);
      frame_hi = frame_hi.cwiseMax(x);
      ++seen;
    }
    if (seen >= 2) sizes.push_back((frame_hi - frame_lo).norm());
  }
  std::vector<double> ranges;
  for (int i = 0; i < n; ++i)
    if (hi[i].x() >= lo[i].x()) ranges.push_back((hi[i] - lo[i]).norm());
  const double size = sensor_muscles::median(sizes);
  return size > 0.0 ? sensor_muscles::median(ranges) / size : 0.0;
}

}  // namespace mme
