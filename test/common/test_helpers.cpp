#include "test_helpers.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/scenes/scenes.h"
#include "motion_model_estimation/core/stiffness.h"

namespace mme {
namespace test {

int addParticle(Model* model, const Eigen::Vector3d& x, double mass_kg, bool fixed,
                const std::string& group, const Eigen::Vector3d& v) {
  return mme::addParticle(model, x, {"", mass_kg, v, fixed, group});
}

int addType(Model* model, const std::string& name, BondKind kind,
            std::initializer_list<std::pair<ParamId, double>> params, bool free) {
  BondType t;
  t.name = name;
  t.kind = kind;
  for (const auto& p : params) t.param(p.first) = valueParam(p.second, free);
  model->bond_types.push_back(t);
  return static_cast<int>(model->bond_types.size()) - 1;
}

std::string nameBond(Model* model, int bond, const std::string& name) {
  model->bonds.at(bond).name = name;
  return name;
}

int addMuscleType(Model* model, const std::string& name, double stiffness, double rest_length,
                  double damping, double gain, int inputs, int hidden,
                  const std::vector<double>& network, bool free) {
  const int t = addType(model, name, BondKind::kMuscle,
                        {{kStiffness, stiffness}, {kRestLength, rest_length}, {kDamping, damping},
                         {kGain, gain}},
                        free);
  BondType& type = model->bond_types[t];
  type.network_inputs = inputs;
  type.network_hidden = hidden;
  for (double v : network) type.network.push_back(valueParam(v, free));
  return t;
}

void addMuscle(Model* model, int type, int a, int b, const std::vector<int>& inputs) {
  addBond(model, type, a, b);
  model->bonds.back().inputs = inputs;
}

Model muscleObject() {
  Model m;
  m.frame_rate_hz = 100;
  for (int k = 0; k < 3; ++k) m.gravity_mps2[k] = valueParam(k == 2 ? -9.81 : 0.0);
  addParticle(&m, Eigen::Vector3d(0, 0, 0), 1.0, true);
  addParticle(&m, Eigen::Vector3d(0.2, 0.0, -0.05), 0.8, false, "", Eigen::Vector3d(0, 0.3, 0));
  addParticle(&m, Eigen::Vector3d(0.25, 0.15, -0.15), 0.6, false, "", Eigen::Vector3d(0.2, 0, 0.1));
  addParticle(&m, Eigen::Vector3d(0.05, 0.1, -0.25), 0.7, false, "", Eigen::Vector3d(-0.1, 0, 0));
  const int s = addType(&m, "s", BondKind::kSpring, {{kStiffness, 60.0}, {kRestLength, 0.2}}, false);
  const int d = addType(&m, "d", BondKind::kSpring,
                        {{kStiffness, 35.0}, {kRestLength, 0.22}, {kDamping, 0.3}}, false);
  addBond(&m, s, 0, 1);
  nameBond(&m, 0, "upper");
  addBond(&m, s, 1, 2);
  nameBond(&m, 1, "lower");
  addBond(&m, d, 2, 3);
  addBond(&m, d, 1, 3);
  addBond(&m, d, 0, 2);
  // Network inputs: elongations of "upper", "lower" [m], then their speeds [m/s].
  const int mu = addMuscleType(&m, "m", 40.0, 0.25, 0.2, 3.0, 2, 0, {30.0, -25.0, 2.0, -1.5, 0.2});
  addMuscle(&m, mu, 0, 3, {0, 1});
  return m;
}

Model smallObject() {
  Model m;
  m.frame_rate_hz = 100;
  const double pos[5][3] = {{0, 0, 0}, {0.2, 0, 0}, {0.1, 0.17, 0}, {0.1, 0.06, 0.16}, {0.3, 0.15, 0.05}};
  for (int i = 0; i < 5; ++i)
    addParticle(&m, Eigen::Vector3d(pos[i][0], pos[i][1], pos[i][2]), 1.0 + 0.25 * i, false, "",
                Eigen::Vector3d(0.05 * ((i * 7) % 3 - 1), 0.04 * ((i * 5) % 3 - 1), 0.03 * (i % 2)));
  const double k[3] = {20.0, 45.0, 80.0}, L[3] = {0.17, 0.22, 0.15};
  for (int t = 0; t < 3; ++t) {
    BondType bt;
    bt.name = "s" + std::to_string(t);
    bt.param(kStiffness) = {k[t], true, true, true, 1.0, 1000.0, true, true};
    bt.param(kRestLength) = {L[t], true, true, true, 0.05, 0.5, true, true};
    m.bond_types.push_back(bt);
  }
  const int bonds[7][3] = {{0, 0, 1}, {0, 1, 2}, {1, 0, 2}, {1, 0, 3}, {2, 1, 3}, {2, 2, 3}, {0, 2, 4}};
  for (const auto& b : bonds) addBond(&m, b[0], b[1], b[2]);
  return m;
}

Model particlesOnly(Model model) {
  model.bonds.clear();
  model.bond_types.clear();
  return model;
}

StiffAtOneSubstep::StiffAtOneSubstep() : truth(makeScene("paper_object").model) {
  std::vector<Eigen::Vector3d> x;
  for (const Particle& p : truth.particles) x.push_back(p.position_m);
  truth.frame_rate_hz = stiffestModeRadPerS(truth, x) / 2.5;
  truth.substeps = 20;
  data = simulateTrajectory(truth, 60, truth.frame_rate_hz);
  addGaussianNoise(&data, 1e-4, 7);
  search = withoutValues(truth);
  search.substeps = 1;
}

Model withoutValues(Model model) {
  for (const ParamRef& r : freeParameters(model)) paramOf(model, r).has_value = false;
  return model;
}

Model withoutBounds(Model model) {
  for (const ParamRef& r : freeParameters(model)) {
    Param& p = paramOf(model, r);
    p.has_min = p.has_max = false;
    p.min = -std::numeric_limits<double>::infinity();
    p.max = std::numeric_limits<double>::infinity();
  }
  return model;
}

SmallObjectFixture::SmallObjectFixture()
    : truth(smallObject()),
      search(withoutValues(truth)),
      data(simulateTrajectory(truth, 60, 100.0)),
      cost(std::make_shared<ShortTermCost>(search, data)),
      true_values(getValues(truth, freeParameters(truth))) {}

double maxRelativeError(const std::vector<double>& a, const std::vector<double>& truth) {
  double e = 0;
  for (size_t k = 0; k < a.size() && k < truth.size(); ++k)
    e = std::max(e, std::abs(a[k] - truth[k]) / std::abs(truth[k]));
  return e;
}

double predictionRms(const PredictionReport& report, int horizon, Predictor predictor) {
  for (const PredictionError& row : report.rows)
    if (row.horizon == horizon && row.predictor == predictor) return row.rms_m;
  ADD_FAILURE() << "no row for horizon " << horizon << ", predictor " << predictorName(predictor);
  return -1.0;
}

}  // namespace test
}  // namespace mme
