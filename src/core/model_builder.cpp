#include "motion_model_estimation/core/model_builder.h"

#include <utility>

namespace mme {

Param valueParam(double value, bool free) {
  Param p;
  p.value = value;
  p.present = p.has_value = true;
  p.free = free;
  return p;
}

Param boundedParam(double value, double min, double max) {
  Param p = valueParam(value, true);
  p.min = min;
  p.max = max;
  p.has_min = p.has_max = true;
  return p;
}

int addParticle(Model* model, const Eigen::Vector3d& position_m, const ParticleOptions& options) {
  Particle p;
  p.name = options.name.empty() ? "p" + std::to_string(model->particles.size()) : options.name;
  p.mass_kg = options.mass_kg;
  p.position_m = position_m;
  p.velocity_mps = options.velocity_mps;
  p.fixed = options.fixed;
  p.group = options.group;
  model->particles.push_back(p);
  return static_cast<int>(model->particles.size()) - 1;
}

int addBondType(Model* model, BondType type) {
  model->bond_types.push_back(std::move(type));
  return static_cast<int>(model->bond_types.size()) - 1;
}

int addBond(Model* model, int type, int a, int b, int c) {
  Bond bond;
  bond.type = type;
  bond.particles = {{a, b, c}};
  model->bonds.push_back(bond);
  return static_cast<int>(model->bonds.size()) - 1;
}

}  // namespace mme
