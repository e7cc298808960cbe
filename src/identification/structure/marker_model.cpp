#include "motion_model_estimation/identification/structure/marker_model.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "motion_model_estimation/core/error.h"

namespace mme {

Model markerModel(const Trajectory& data, int rigid_pair_bonds) {
  const int n = data.numMarkers(), frames = data.numFrames();
  if (n == 0) throw InputError("no markers to make a model of");
  if (frames == 0) throw InputError("no frames to make a model of");
  Model m;
  m.frame_rate_hz = data.frame_rate_hz;
  for (int i = 0; i < n; ++i) {
    Particle p;
    p.name = data.marker_names[i];
    p.mass_kg = 1.0;
    m.particles.push_back(p);
  }
  for (int c = 0; c < 3; ++c) m.gravity_mps2[c].present = m.gravity_mps2[c].free = true;
  if (rigid_pair_bonds <= 0) return m;

  struct Pair {
    double spread;
    int a, b;
  };
  std::vector<Pair> pairs;
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) {
      double sum = 0, sq = 0;
      int seen = 0;
      for (int t = 0; t < frames; ++t) {
        if (data.isOccluded(t, a) || data.isOccluded(t, b)) continue;
        const double l = (data.position(t, b) - data.position(t, a)).norm();
        sum += l;
        sq += l * l;
        ++seen;
      }
      if (seen < 0.8 * frames || seen < 2) continue;
      const double mean = sum / seen, var = std::max(0.0, sq / seen - mean * mean);
      if (!(mean > 0.0)) continue;
      pairs.push_back({std::sqrt(var) / mean, a, b});
    }
  // Stable: equal spreads keep the (a, b) order, so the model is the same on every platform.
  std::stable_sort(pairs.begin(), pairs.end(),
                   [](const Pair& x, const Pair& y) { return x.spread < y.spread; });
  for (int k = 0; k < rigid_pair_bonds && k < static_cast<int>(pairs.size()); ++k) {
    BondType type;
    type.name = "b" + std::to_string(k);
    type.kind = BondKind::kSpring;
    for (ParamId id : {kStiffness, kRestLength, kDamping}) type.param(id).present = type.param(id).free = true;
    m.bond_types.push_back(type);
    Bond bond;
    bond.type = k;
    bond.particles = {{pairs[k].a, pairs[k].b, -1}};
    m.bonds.push_back(bond);
  }
  return m;
}

}  // namespace mme
