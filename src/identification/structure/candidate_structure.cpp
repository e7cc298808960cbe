// Candidate generation for structure selection (candidate_structure.h): the pairs, triples and
// drags a level starts from, and the bonds that carry them into a model, one type each.
#include "candidate_structure.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <string>

#include "motion_model_estimation/core/forces.h"
#include "motion_model_estimation/core/model_builder.h"

namespace mme {
namespace structure {

namespace {

/// Mean and relative spread of a pair's distance over the frames where both are seen.
struct PairStats {
  double mean_m = 0.0;
  double relative_std = 0.0;
  bool seen = false;
};

/// The distance statistics of every pair seen together in 3 frames or more (symmetric).
std::vector<std::vector<PairStats>> pairStatistics(const Trajectory& data, int particles) {
  const int n = particles;
  std::vector<std::vector<PairStats>> stats(n, std::vector<PairStats>(n));
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) {
      const MarkerDistance d = markerDistance(data, a, b);
      if (d.seen_frames < 3) continue;
      PairStats& s = stats[a][b];
      s.seen = true;
      s.mean_m = d.mean_m;
      s.relative_std = s.mean_m > 0.0 ? d.std_m / s.mean_m : 0.0;
      stats[b][a] = s;
    }
  return stats;
}

/// The two-particle pairs `model` already bonds (sorted).
std::set<std::pair<int, int>> bondedPairs(const Model& model) {
  std::set<std::pair<int, int>> bonded;
  for (const Bond& b : model.bonds)
    if (kindArity(model.bond_types[b.type].kind) == 2)
      bonded.insert(std::minmax(b.particles[0], b.particles[1]));
  return bonded;
}

/// The `most` shortest of `chosen` (mean distance), sorted by particles.
std::vector<std::pair<int, int>> shortestPairs(const std::set<std::pair<int, int>>& chosen,
                                               const std::vector<std::vector<PairStats>>& stats,
                                               int most) {
  std::vector<std::pair<double, std::pair<int, int>>> by_length;
  for (const auto& p : chosen) by_length.push_back({stats[p.first][p.second].mean_m, p});
  std::sort(by_length.begin(), by_length.end());
  if (static_cast<int>(by_length.size()) > most) by_length.resize(most);
  std::vector<std::pair<int, int>> pairs;
  for (const auto& e : by_length) pairs.push_back(e.second);
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

/// Mean distance of markers a and b over the frames where both are seen; infinite when never.
double meanDistanceM(const Trajectory& data, int a, int b) {
  double sum = 0.0;
  int count = 0;
  for (int t = 0; t < data.numFrames(); ++t)
    if (!data.isOccluded(t, a) && !data.isOccluded(t, b)) {
      sum += (data.position(t, a) - data.position(t, b)).norm();
      ++count;
    }
  return count > 0 ? sum / count : std::numeric_limits<double>::infinity();
}

/// Each vertex's `nearest` candidate partners (mean distance): a chain's neighbours.
std::vector<std::vector<int>> nearestPartners(const Trajectory& data, int particles,
                                              const std::vector<std::pair<int, int>>& pairs,
                                              int nearest) {
  std::vector<std::vector<std::pair<double, int>>> by_distance(particles);
  for (const auto& p : pairs) {
    const double d = meanDistanceM(data, p.first, p.second);
    by_distance[p.first].push_back({d, p.second});
    by_distance[p.second].push_back({d, p.first});
  }
  std::vector<std::vector<int>> partners(particles);
  for (int v = 0; v < particles; ++v) {
    std::sort(by_distance[v].begin(), by_distance[v].end());
    for (int k = 0; k < nearest && k < static_cast<int>(by_distance[v].size()); ++k)
      partners[v].push_back(by_distance[v][k].second);
  }
  return partners;
}

/// The sum of the angle at v of (a, v, c) over the frames where all three are seen, and
/// their count.
std::pair<double, int> angleSum(const Trajectory& data, int a, int v, int c) {
  double sum = 0.0;
  int count = 0;
  for (int t = 0; t < data.numFrames(); ++t) {
    if (data.isOccluded(t, a) || data.isOccluded(t, v) || data.isOccluded(t, c)) continue;
    sum += flexionAngle(data.position(t, a), data.position(t, v), data.position(t, c));
    ++count;
  }
  return {sum, count};
}

/// A bond of `type` (appended to `model` as a type of its own) on `particles`.
void appendOwnTypeBond(Model* model, BondType type, const std::array<int, 3>& particles) {
  Bond bond;
  bond.type = static_cast<int>(model->bond_types.size());
  bond.particles = particles;
  model->bond_types.push_back(type);
  model->bonds.push_back(bond);
}

}  // namespace


std::vector<std::pair<int, int>> candidatePairs(const Model& model, const Trajectory& data,
                                                const StructureOptions& options) {
  const int n = static_cast<int>(model.particles.size());
  const std::set<std::pair<int, int>> bonded = bondedPairs(model);
  const std::vector<std::vector<PairStats>> stats = pairStatistics(data, n);
  const auto usable = [&](int a, int b) {
    return a != b && stats[a][b].seen && stats[a][b].mean_m > 0.0 &&
           !(model.particles[a].fixed && model.particles[b].fixed) &&
           !bonded.count(std::minmax(a, b));
  };
  std::set<std::pair<int, int>> chosen;
  for (int a = 0; a < n; ++a) {
    std::vector<std::pair<double, int>> near;
    for (int b = 0; b < n; ++b)
      if (usable(a, b)) near.push_back({stats[a][b].mean_m, b});
    std::sort(near.begin(), near.end());
    for (int k = 0; k < options.neighbours && k < static_cast<int>(near.size()); ++k)
      chosen.insert(std::minmax(a, near[k].second));
  }
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b)
      if (usable(a, b) && stats[a][b].relative_std < options.rigid_relative_std) chosen.insert({a, b});
  return shortestPairs(chosen, stats, options.max_candidates);
}

int addCandidateBonds(Model* model, const std::vector<std::pair<int, int>>& pairs,
                      const Trajectory& data, bool dampers) {
  const int first = static_cast<int>(model->bond_types.size());
  for (const auto& p : pairs) {
    BondType type;
    type.name = "b_" + model->particles[p.first].name + "_" + model->particles[p.second].name;
    type.kind = BondKind::kSpring;
    double length = 0.0;
    int count = 0;
    for (int t = 0; t < data.numFrames(); ++t)
      if (!data.isOccluded(t, p.first) && !data.isOccluded(t, p.second)) {
        length += (data.position(t, p.first) - data.position(t, p.second)).norm();
        ++count;
      }
    type.param(kStiffness) = valueParam(1.0, true);
    type.param(kRestLength) = valueParam(count > 0 ? length / count : 0.1, true);
    if (dampers) type.param(kDamping) = valueParam(0.1, true);
    appendOwnTypeBond(model, type, {{p.first, p.second, -1}});
  }
  return first;
}

std::vector<std::array<int, 3>> candidateTriples(const Model& model, const Trajectory& data,
                                                 const std::vector<std::pair<int, int>>& pairs,
                                                 int nearest, double min_angle_rad, int most) {
  const int n = static_cast<int>(model.particles.size());
  const std::vector<std::vector<int>> partners = nearestPartners(data, n, pairs, nearest);
  std::vector<std::pair<double, std::array<int, 3>>> found;
  for (int v = 0; v < n; ++v) {
    if (model.particles[v].fixed) continue;
    const std::vector<int>& near = partners[v];
    for (size_t i = 0; i < near.size(); ++i)
      for (size_t j = i + 1; j < near.size(); ++j) {
        const int a = std::min(near[i], near[j]), c = std::max(near[i], near[j]);
        const std::pair<double, int> angle = angleSum(data, a, v, c);
        const double sum = angle.first;
        const int count = angle.second;
        if (count < 3 || sum / count < min_angle_rad) continue;
        found.push_back({-sum / count, {{a, v, c}}});
      }
  }
  std::sort(found.begin(), found.end());
  if (static_cast<int>(found.size()) > most) found.resize(most);
  std::vector<std::array<int, 3>> triples;
  for (const auto& f : found) triples.push_back(f.second);
  std::sort(triples.begin(), triples.end());
  return triples;
}

void addCandidateFlexions(Model* model, const std::vector<std::array<int, 3>>& triples,
                          const Trajectory& data, bool dampers) {
  for (const auto& tr : triples) {
    BondType type;
    type.name = "f_" + model->particles[tr[0]].name + "_" + model->particles[tr[1]].name + "_" +
                model->particles[tr[2]].name;
    type.kind = BondKind::kFlexion;
    double angle = 0.0;
    int count = 0;
    for (int t = 0; t < data.numFrames(); ++t)
      if (!data.isOccluded(t, tr[0]) && !data.isOccluded(t, tr[1]) && !data.isOccluded(t, tr[2])) {
        angle += flexionAngle(data.position(t, tr[0]), data.position(t, tr[1]), data.position(t, tr[2]));
        ++count;
      }
    type.param(kStiffness) = valueParam(1e-3, true);
    type.param(kRestAngle) = valueParam(count > 0 ? angle / count : 3.0, true);
    if (dampers) type.param(kDamping) = valueParam(1e-4, true);
    appendOwnTypeBond(model, type, {{tr[0], tr[1], tr[2]}});
  }
}

void addCandidateViscosities(Model* model) {
  for (size_t i = 0; i < model->particles.size(); ++i) {
    if (model->particles[i].fixed) continue;
    BondType type;
    type.name = "v_" + model->particles[i].name;
    type.kind = BondKind::kViscosity;
    type.param(kViscosity) = valueParam(0.01, true);
    appendOwnTypeBond(model, type, {{static_cast<int>(i), -1, -1}});
  }
}

}  // namespace structure
}  // namespace mme
