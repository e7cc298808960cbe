#include "sensor_layout.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <string>
#include <utility>

#include "fit_budget.h"
#include "motion_model_estimation/core/error.h"

namespace mme::sensor_muscles {

namespace {

std::vector<PairStats> pairStatistics(const Model& model, const Trajectory& data) {
  const int n = static_cast<int>(model.particles.size());
  std::vector<PairStats> pairs;
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) {
      if (model.particles[a].fixed && model.particles[b].fixed) continue;
      const MarkerDistance d = markerDistance(data, a, b);
      if (d.seen_frames == 0) continue;
      pairs.push_back({a, b, d.mean_m, d.std_m, d.seen_frames});
    }
  return pairs;
}

/// The `count` well-seen pairs without an anchor whose distance varies most.
std::vector<PairStats> mostVaryingPairs(const std::vector<PairStats>& pairs, int well_seen,
                                        const std::vector<char>& anchor, int count) {
  std::vector<PairStats> ranked;
  for (const PairStats& p : pairs)
    if (p.seen >= well_seen && !anchor[p.a] && !anchor[p.b]) ranked.push_back(p);
  std::stable_sort(ranked.begin(), ranked.end(),
                   [](const PairStats& x, const PairStats& y) { return x.std_m > y.std_m; });
  if (static_cast<int>(ranked.size()) > count) ranked.resize(count);
  return ranked;
}

/// Particle i's well-seen partners without an anchor, nearest (mean distance) first.
std::vector<std::pair<double, int>> nearestPartners(const std::vector<PairStats>& pairs, int i, int well_seen,
                                                    const std::vector<char>& anchor) {
  std::vector<std::pair<double, int>> near;
  for (const PairStats& p : pairs)
    if (p.seen >= well_seen && (p.a == i || p.b == i) && !anchor[p.a] && !anchor[p.b])
      near.push_back({p.mean_m, p.a == i ? p.b : p.a});
  std::sort(near.begin(), near.end());
  return near;
}

/// Adds the muscles to a layout, one per pair.
class MusclePairs {
 public:
  MusclePairs(const std::vector<PairStats>& pairs, const std::vector<char>& anchor,
              AnchorStiffness anchor_stiffness, Layout* layout)
      : pairs_(pairs), anchor_(anchor), anchor_stiffness_(anchor_stiffness), layout_(layout) {}

  /// A muscle between a and b, unless it is there already or the pair has no length.
  void add(int a, int b) {
    if (a == b) return;
    if (a > b) std::swap(a, b);
    if (taken_.count({a, b})) return;
    const PairStats* p = stats(a, b);
    if (!p || !(p->mean_m > 0.0)) return;
    taken_.insert({a, b});
    layout_->muscles.push_back(*p);
    layout_->no_own_stiffness.push_back((anchor_[a] || anchor_[b]) &&
                                        anchor_stiffness_ == AnchorStiffness::kNone);
  }

 private:
  const PairStats* stats(int a, int b) const {
    if (a > b) std::swap(a, b);
    for (const PairStats& p : pairs_)
      if (p.a == a && p.b == b) return &p;
    return nullptr;
  }

  const std::vector<PairStats>& pairs_;
  const std::vector<char>& anchor_;
  AnchorStiffness anchor_stiffness_;
  Layout* layout_;
  std::set<std::pair<int, int>> taken_;
};

}  // namespace

size_t unknownsOf(const Layout& layout) {
  return layout.muscles.size() * (2 * layout.sensors.size() + 3);
}

Layout chooseLayout(const Model& passive, const Trajectory& data, const std::vector<char>& anchor,
                    const SensorMuscleOptions& o) {
  const std::vector<PairStats> pairs = pairStatistics(passive, data);
  const int well_seen = static_cast<int>(std::ceil(o.min_seen_share * data.numFrames()));
  Layout layout;
  layout.sensors = mostVaryingPairs(pairs, well_seen, anchor, o.sensors);
  // Muscles: the model's two-particle bonds with an elongation, the sensor pairs, every particle
  // to its nearest neighbours and to each anchor; one muscle per pair.
  MusclePairs muscles(pairs, anchor, o.anchor_stiffness, &layout);
  for (const Bond& bond : passive.bonds)
    if (bondKindInfo(passive.bond_types[bond.type].kind).has_elongation)
      muscles.add(bond.particles[0], bond.particles[1]);
  for (const PairStats& p : layout.sensors) muscles.add(p.a, p.b);
  const int n = static_cast<int>(passive.particles.size());
  for (int i = 0; i < n; ++i) {
    if (passive.particles[i].fixed) continue;
    const std::vector<std::pair<double, int>> near = nearestPartners(pairs, i, well_seen, anchor);
    for (int k = 0; k < o.neighbours && k < static_cast<int>(near.size()); ++k) muscles.add(i, near[k].second);
    for (int a = 0; a < n; ++a)
      if (anchor[a]) muscles.add(i, a);
  }
  return layout;
}

Layout chooseLayoutWithinUnknowns(const Model& passive, const Trajectory& data,
                                  const std::vector<char>& anchor, const SensorMuscleOptions& o) {
  Layout layout = chooseLayout(passive, data, anchor, o);
  if (layout.sensors.empty())
    throw InputError("sensor muscles: no pair of particles is seen together in " +
                     std::to_string(static_cast<int>(100 * o.min_seen_share)) + " % of the frames");
  if (layout.muscles.empty()) throw InputError("sensor muscles: no pair of particles to put a muscle on");
  // A body too large for max_unknowns reads fewer sensors (the most varying pairs are kept):
  // each muscle then has fewer unknowns, and the sensor pairs' own muscles go with them.
  while (unknownsOf(layout) > o.max_unknowns && layout.sensors.size() > 1) {
    const size_t per_muscle = o.max_unknowns / layout.muscles.size();
    SensorMuscleOptions fewer = o;
    fewer.sensors = static_cast<int>(std::max<size_t>(
        1, std::min(layout.sensors.size() - 1, per_muscle > 3 ? (per_muscle - 3) / 2 : 1)));
    char line[200];
    std::snprintf(line, sizeof(line),
                  "sensor muscles: %zu muscles reading %zu sensors are %zu unknowns, more than %zu: "
                  "%d sensors", layout.muscles.size(), layout.sensors.size(), unknownsOf(layout),
                  o.max_unknowns, fewer.sensors);
    say(o, line);
    layout = chooseLayout(passive, data, anchor, fewer);
  }
  const size_t unknowns = unknownsOf(layout);
  if (unknowns > o.max_unknowns)
    throw InputError("sensor muscles: " + std::to_string(layout.muscles.size()) + " muscles reading " +
                     std::to_string(layout.sensors.size()) + " sensor(s) are " + std::to_string(unknowns) +
                     " unknowns, more than " + std::to_string(o.max_unknowns) +
                     " (two dense matrices of that size): fewer neighbours, or no anchors");
  return layout;
}

}  // namespace mme::sensor_muscles
