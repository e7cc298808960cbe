#include "muscle_model_build.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/muscle.h"

namespace mme::sensor_muscles {

namespace {

/// Names not yet taken in the model: a name taken gets underscores appended.
class UniqueNames {
 public:
  explicit UniqueNames(const Model& model) {
    for (const BondType& type : model.bond_types) types_.insert(type.name);
    for (const Bond& bond : model.bonds)
      if (!bond.name.empty()) bonds_.insert(bond.name);
  }
  std::string type(const std::string& name) { return take(&types_, name); }
  std::string bond(const std::string& name) { return take(&bonds_, name); }

 private:
  static std::string take(std::set<std::string>* names, std::string name) {
    while (names->count(name)) name += "_";
    names->insert(name);
    return name;
  }
  std::set<std::string> types_, bonds_;
};

Param fixed(double value) {
  Param p;
  p.present = p.has_value = true;
  p.free = false;
  p.value = value;
  return p;
}

/// A bond of the type just appended between the pair's particles.
Bond pairBond(const Model& model, const PairStats& pair) {
  Bond bond;
  bond.type = static_cast<int>(model.bond_types.size()) - 1;
  bond.particles = {{pair.a, pair.b, -1}};
  return bond;
}

/// The sensors a selection keeps (every one without a selection).
std::vector<int> keptSensors(int sensors, const GroupSelection* selection) {
  std::vector<int> kept;
  for (int s = 0; s < sensors; ++s)
    if (!selection || !selection->dropsSensor(s)) kept.push_back(s);
  return kept;
}

/// Appends the bonds of the `kept` sensors (springs of zero stiffness); returns their indices.
std::vector<int> addSensorBonds(const Layout& layout, const std::vector<int>& kept, UniqueNames* names,
                                Model* model) {
  std::vector<int> sensor_bonds;
  for (int s : kept) {
    const PairStats& pair = layout.sensors[s];
    const std::string stem = "sensor_" + model->particles[pair.a].name + "_" + model->particles[pair.b].name;
    BondType type;
    type.name = names->type(stem);
    type.kind = BondKind::kSpring;
    type.param(kStiffness) = fixed(0.0);
    type.param(kRestLength) = fixed(pair.mean_m);
    model->bond_types.push_back(type);
    Bond bond = pairBond(*model, pair);
    bond.name = names->bond(stem);
    model->bonds.push_back(bond);
    sensor_bonds.push_back(static_cast<int>(model->bonds.size()) - 1);
  }
  return sensor_bonds;
}

/// Each muscle's largest linear activation |y| over the data's frames [1, t_end).
std::vector<double> largestActivations(const MuscleEquations& eq, const Eigen::VectorXd& theta, int t_end) {
  const int s = eq.sensors(), k = eq.perMuscle();
  std::vector<double> largest(eq.muscles(), 0.0);
  for (int t = 1; t < std::min(t_end, eq.data().numFrames()); ++t) {
    Eigen::VectorXd z;
    if (!eq.sensorInputs(eq.dataFrames(t), &z)) continue;
    const Eigen::VectorXd scaled = z.cwiseQuotient(eq.inputScales());
    for (int m = 0; m < eq.muscles(); ++m) {
      const double y = theta.segment(m * k, 2 * s).dot(scaled) + theta(m * k + 2 * s);
      largest[m] = std::max(largest[m], std::abs(y));
    }
  }
  return largest;
}

/// Muscle m's type: theta's block unscaled, the network's weights divided by the gain, reading
/// the `kept` sensors.
BondType muscleType(const MuscleEquations& eq, int m, const Eigen::VectorXd& theta, double gain,
                    double activation_time_s, const std::vector<int>& kept, const std::string& name) {
  const int s = eq.sensors(), k = eq.perMuscle();
  const Eigen::VectorXd th = theta.segment(m * k, k);
  BondType type;
  type.name = name;
  type.kind = BondKind::kMuscle;
  type.param(kStiffness) = fixed(th(2 * s + 1) / eq.elongationScaleM(m));
  type.param(kRestLength) = fixed(eq.layout().muscles[m].mean_m);
  type.param(kDamping) = fixed(th(2 * s + 2) / eq.speedScaleMps(m));
  type.param(kGain) = fixed(gain);
  if (activation_time_s > 0.0) type.param(kActivationTime) = fixed(activation_time_s);
  const int inputs = static_cast<int>(kept.size());
  type.network_inputs = inputs;
  type.network_hidden = 0;
  type.network.assign(muscleNetworkSize(inputs, 0), Param{});
  for (int q = 0; q < inputs; ++q)
    for (int j : {kept[q], s + kept[q]})
      type.network[j < s ? q : inputs + q] = fixed(th(j) / eq.inputScale(j) / gain);
  type.network[2 * inputs] = fixed(th(2 * s) / gain);
  return type;
}

}  // namespace

Model buildMuscleModel(const MuscleEquations& eq, const Eigen::VectorXd& theta, double margin, int t_end,
                       double activation_time_s, const GroupSelection* selection) {
  Model model = eq.passive();
  UniqueNames names(model);
  const std::vector<int> kept = keptSensors(eq.sensors(), selection);
  const std::vector<int> sensor_bonds = addSensorBonds(eq.layout(), kept, &names, &model);
  // Each muscle's largest linear activation over the fitted frames sets its gain.
  const std::vector<double> largest = largestActivations(eq, theta, t_end);
  for (int m = 0; m < eq.muscles(); ++m) {
    if (selection && selection->dropsMuscle(m)) continue;
    const PairStats& pair = eq.layout().muscles[m];
    const double gain = largest[m] > 0.0 ? margin * largest[m] : 1.0;
    const std::string name =
        names.type("muscle_" + model.particles[pair.a].name + "_" + model.particles[pair.b].name);
    model.bond_types.push_back(muscleType(eq, m, theta, gain, activation_time_s, kept, name));
    Bond bond = pairBond(model, pair);
    bond.inputs = sensor_bonds;
    model.bonds.push_back(bond);
  }
  const std::string problem = validateModel(model);
  if (!problem.empty()) throw InputError("sensor muscles: " + problem);
  return model;
}

}  // namespace mme::sensor_muscles
