// The problem instances of bench_peers (declared in instances.h): each simulates its data from a
// known truth so that every method is judged against the same parameters.
#include "instances.h"

#include <algorithm>

#include "motion_model_estimation/scenes/random_object.h"
#include "motion_model_estimation/scenes/scenes.h"

namespace peers {

using bench::Problem;

Problem paperProblem(int frames) {
  const mme::Scene scene = mme::makeScene("paper_object");
  mme::State state;
  const mme::Trajectory data =
      bench::simulateWindow(scene.model, frames, scene.model.frame_rate_hz, 0, &state);
  return bench::makeProblem("paper_object", scene.model, scene.model.substeps, data, state);
}

Problem clothProblem() {
  const mme::Scene scene = mme::makeScene("provot_cloth");
  mme::State state;
  const mme::Trajectory& data = scene.reference_data;
  for (int i = 0; i < data.numMarkers(); ++i) {
    state.x_m.push_back(data.position(0, i));
    state.v_mps.push_back(Eigen::Vector3d::Zero());
  }
  return bench::makeProblem("provot_cloth", scene.model, scene.model.substeps, data, state);
}

Problem fluidProblem(int first, int frames) {
  const mme::Scene scene = mme::makeScene("fluid_jet");
  mme::State state;
  const mme::Trajectory data =
      bench::simulateWindow(scene.model, first + frames, scene.model.frame_rate_hz, first, &state);
  return bench::makeProblem("fluid_jet_reduced", scene.model, scene.model.substeps, data, state);
}

Problem cableProblem(int cables, int frames, uint64_t seed) {
  const mme::Model truth = bench::makeCableObject(10, cables, 15, 31, 100.0, seed);
  mme::State state;
  const mme::Trajectory data = bench::simulateWindow(truth, frames, 100.0, 0, &state);
  return bench::makeProblem("cable_object", truth, 1, data, state);
}

Problem randomProblem(int unknowns, int frames, uint64_t seed) {
  mme::RandomObjectSpec spec;
  spec.bond_types = std::max(1, unknowns / 2);
  spec.particles = std::max(8, spec.bond_types + spec.bond_types / 2);
  spec.bonds = 2 * spec.bond_types + spec.particles / 2;
  spec.frame_rate_hz = 100.0;
  spec.seed = seed;
  const mme::Model truth = mme::makeRandomObject(spec);
  mme::State state;
  const mme::Trajectory data = bench::simulateWindow(truth, frames, 100.0, 0, &state);
  return bench::makeProblem("random_object", truth, 1, data, state);
}

Problem mapProblem(const std::string& axis, double value, int seed, int frames) {
  if (axis == "unknowns") return randomProblem(static_cast<int>(value), frames, 3000 + seed);
  if (axis == "conditional") return cableProblem(static_cast<int>(value), frames, 4000 + seed);
  const mme::Scene scene = mme::makeScene("paper_object");
  mme::Model truth = scene.model;
  if (axis == "omega_h") {
    // Frame rate set so that omega_max * h = value; the data come from the same model with 20
    // substeps per frame (the "real", finely integrated motion); identification uses one step
    // per frame, like the paper.
    truth.frame_rate_hz = bench::stiffestOmega(truth) / value;
    truth.substeps = 20;
  }
  mme::State state;
  mme::Trajectory data = bench::simulateWindow(truth, frames, truth.frame_rate_hz, 0, &state);
  if (axis == "occlusion") bench::occludeRandomly(&data, value, 2000 + seed);
  const mme::Trajectory noiseless = data;  // same occlusion pattern (the Cramer-Rao bound's data)
  if (axis == "noise") mme::addGaussianNoise(&data, value, 1000 + seed);
  Problem p = bench::makeProblem("paper_object", truth, 1, data, state);
  if (axis == "spread") p.start_spread = value;
  if (axis == "noise" && value > 0.0) {
    p.noise_std_m = value;
    p.noiseless_data = noiseless;
  }
  return p;
}

}  // namespace peers
