#include "motion_model_estimation/live/visualisation_snapshot.h"

#include <algorithm>
#include <cstdio>

namespace mme {

bool parseBondColouring(const std::string& text, BondColouring* colouring) {
  if (text == "strain") {
    *colouring = BondColouring::kStrain;
  } else if (text == "local_cost") {
    *colouring = BondColouring::kLocalCost;
  } else {
    return false;
  }
  return true;
}

const char* bondColouringName(BondColouring colouring) {
  switch (colouring) {
    case BondColouring::kStrain: return "strain";
    case BondColouring::kLocalCost: return "local_cost";
  }
  return "?";
}

std::optional<VisualisationSnapshot> makeVisualisationSnapshot(const Model& model,
                                                               const Trajectory& window,
                                                               const Estimate& e,
                                                               BondColouring colouring) {
  const int frames = window.numFrames();
  const int n = window.numMarkers();
  // Model and window are read at different moments: a model with other particles loaded in
  // between leaves nothing consistent to show until the next frame.
  if (frames < 2 || static_cast<int>(model.particles.size()) != n) return std::nullopt;
  VisualisationSnapshot scene;
  scene.stamp_s = window.times_s.back();
  for (int i = 0; i < n; ++i) {
    scene.observed.push_back(window.position(frames - 1, i));
    scene.observed_occluded.push_back(window.isOccluded(frames - 1, i));
    bool never_seen = model.particles[i].fixed;
    for (int t = 0; never_seen && t < frames; ++t) never_seen = window.isOccluded(t, i);
    scene.model_only.push_back(never_seen);
  }
  if (frames >= 3) {
    // One-step prediction of the latest frame from the two before it.
    const Trajectory last3 = sliceFrames(window, frames - 3, 3);
    const Trajectory pred = OnlineEstimator::rollout(model, last3, 2);
    if (pred.numFrames() == 2)
      for (int i = 0; i < n; ++i) scene.predicted.push_back(pred.position(1, i));
  }
  // The long reconstruction from the window start (the paper's Fig. 2).
  const Trajectory recon = OnlineEstimator::rollout(model, window, frames - 1);
  if (recon.numFrames() == frames - 1) {
    scene.reconstruction_trails.assign(n, {});
    for (int i = 0; i < n; ++i) {
      scene.reconstructed.push_back(recon.position(frames - 2, i));
      for (int t = 0; t < recon.numFrames(); ++t)
        scene.reconstruction_trails[i].push_back(recon.position(t, i));
    }
  }
  double max_local = 0.0;
  for (double c : e.local_costs) max_local = std::max(max_local, c);
  const int costs = static_cast<int>(e.local_costs.size());
  for (const Bond& b : model.bonds) {
    const BondType& type = model.bond_types[b.type];
    if (!bondKindInfo(type.kind).has_elongation) continue;  // springs and muscles
    const int i = b.particles[0], j = b.particles[1];
    scene.bonds.emplace_back(i, j);
    switch (colouring) {
      case BondColouring::kStrain: {
        const double rest = type.value(kRestLength);
        const double len = (scene.observed[j] - scene.observed[i]).norm();
        scene.bond_values.push_back(rest > 0 ? len / rest - 1.0 : 0.0);
        break;
      }
      case BondColouring::kLocalCost:
        scene.bond_values.push_back(i < costs && j < costs
                                        ? 0.5 * (e.local_costs[i] + e.local_costs[j]) : 0.0);
        break;
    }
  }
  if (colouring == BondColouring::kLocalCost) {
    scene.bond_value_lo = 0.0;
    scene.bond_value_hi = max_local > 0 ? max_local : 1.0;
  }
  char text[160];
  std::snprintf(text, sizeof(text), "generation %u  cost %.3g m^2  %s", e.generation,
                e.global_cost, e.stable ? "stable" : "UNSTABLE");
  scene.text = text;
  return scene;
}

}  // namespace mme
