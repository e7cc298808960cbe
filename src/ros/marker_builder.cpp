#include "motion_model_estimation/ros/marker_builder.h"

#include <algorithm>

namespace mme {

namespace {

visualization_msgs::Marker base(const std_msgs::Header& header, const char* ns, int id,
                                int type) {
  visualization_msgs::Marker m;
  m.header = header;
  m.ns = ns;
  m.id = id;
  m.type = type;
  m.action = visualization_msgs::Marker::ADD;
  m.pose.orientation.w = 1.0;
  m.frame_locked = false;
  return m;
}

geometry_msgs::Point toPoint(const Eigen::Vector3d& v) {
  geometry_msgs::Point p;
  p.x = v.x();
  p.y = v.y();
  p.z = v.z();
  return p;
}

std_msgs::ColorRGBA rgba(float r, float g, float b, float a) {
  std_msgs::ColorRGBA c;
  c.r = r;
  c.g = g;
  c.b = b;
  c.a = a;
  return c;
}

/// Blue (lo) - white (middle) - red (hi).
std_msgs::ColorRGBA diverging(double v, double lo, double hi) {
  const double t = hi > lo ? std::min(1.0, std::max(0.0, (v - lo) / (hi - lo))) : 0.5;
  if (t < 0.5) {
    const float u = static_cast<float>(t * 2.0);
    return rgba(u, u, 1.0f, 1.0f);
  }
  const float u = static_cast<float>((1.0 - t) * 2.0);
  return rgba(1.0f, u, u, 1.0f);
}

}  // namespace

visualization_msgs::MarkerArray buildMarkers(const VisualisationSnapshot& s,
                                             const MarkerStyle& style) {
  using visualization_msgs::Marker;
  visualization_msgs::MarkerArray out;
  const double d = style.particle_diameter_m;
  std_msgs::Header header;
  header.frame_id = style.frame_id;
  header.stamp.fromSec(s.stamp_s);

  Marker observed = base(header, "observed", 0, Marker::SPHERE_LIST);
  observed.scale.x = observed.scale.y = observed.scale.z = d;
  observed.color = rgba(0.1f, 0.8f, 0.1f, 1.0f);
  for (size_t i = 0; i < s.observed.size(); ++i)
    if (i >= s.observed_occluded.size() || !s.observed_occluded[i])
      observed.points.push_back(toPoint(s.observed[i]));
  out.markers.push_back(observed);

  Marker predicted = base(header, "predicted", 0, Marker::SPHERE_LIST);
  predicted.scale.x = predicted.scale.y = predicted.scale.z = 0.7 * d;
  predicted.color = rgba(1.0f, 0.6f, 0.0f, 0.9f);
  // A point of the model without a marker (an anchor far off the body) is not drawn: it would
  // stand metres away and stretch rviz's view.
  const auto drawn = [&](size_t i) { return i >= s.model_only.size() || !s.model_only[i]; };
  for (size_t i = 0; i < s.predicted.size(); ++i)
    if (drawn(i)) predicted.points.push_back(toPoint(s.predicted[i]));
  out.markers.push_back(predicted);

  Marker recon = base(header, "reconstruction", 0, Marker::SPHERE_LIST);
  recon.scale.x = recon.scale.y = recon.scale.z = 0.7 * d;
  recon.color = rgba(0.2f, 0.4f, 1.0f, 0.9f);
  for (size_t i = 0; i < s.reconstructed.size(); ++i)
    if (drawn(i)) recon.points.push_back(toPoint(s.reconstructed[i]));
  out.markers.push_back(recon);

  Marker trails = base(header, "reconstruction", 1, Marker::LINE_LIST);
  trails.scale.x = 0.15 * d;
  trails.color = rgba(0.2f, 0.4f, 1.0f, 0.4f);
  for (size_t i = 0; i < s.reconstruction_trails.size(); ++i) {
    if (!drawn(i)) continue;
    const auto& path = s.reconstruction_trails[i];
    for (size_t k = 1; k < path.size(); ++k) {
      trails.points.push_back(toPoint(path[k - 1]));
      trails.points.push_back(toPoint(path[k]));
    }
  }
  out.markers.push_back(trails);

  Marker bonds = base(header, "bonds", 0, Marker::LINE_LIST);
  bonds.scale.x = 0.2 * d;
  bonds.color = rgba(1.0f, 1.0f, 1.0f, 1.0f);
  for (size_t b = 0; b < s.bonds.size(); ++b) {
    const int i = s.bonds[b].first, j = s.bonds[b].second;
    if (i < 0 || j < 0 || i >= static_cast<int>(s.observed.size()) ||
        j >= static_cast<int>(s.observed.size()))
      continue;
    const bool hidden = (i < static_cast<int>(s.observed_occluded.size()) && s.observed_occluded[i]) ||
                        (j < static_cast<int>(s.observed_occluded.size()) && s.observed_occluded[j]);
    if (hidden) continue;
    const std_msgs::ColorRGBA c =
        b < s.bond_values.size() ? diverging(s.bond_values[b], s.bond_value_lo, s.bond_value_hi)
                                 : rgba(0.8f, 0.8f, 0.8f, 1.0f);
    bonds.points.push_back(toPoint(s.observed[i]));
    bonds.points.push_back(toPoint(s.observed[j]));
    bonds.colors.push_back(c);
    bonds.colors.push_back(c);
  }
  out.markers.push_back(bonds);

  Marker text = base(header, "status", 0, Marker::TEXT_VIEW_FACING);
  text.scale.z = 2.0 * d;
  text.color = rgba(1.0f, 1.0f, 1.0f, 1.0f);
  text.text = s.text;
  // Above the seen markers: an occluded sample holds no position (the window keeps 0, 0, 0
  // there), and a particle without a marker (an anchor) is never seen.
  Eigen::Vector3d top = Eigen::Vector3d::Zero();
  bool any = false;
  for (size_t i = 0; i < s.observed.size(); ++i) {
    if (i < s.observed_occluded.size() && s.observed_occluded[i]) continue;
    top = any ? top.cwiseMax(s.observed[i]) : s.observed[i];
    any = true;
  }
  text.pose.position = toPoint(top + Eigen::Vector3d(0, 0, 4.0 * d));
  out.markers.push_back(text);
  return out;
}

}  // namespace mme
