// Building a model in code: the few steps every builder repeats (a parameter with a value, a
// free one with bounds, a particle, a bond type, a bond), written once for the built-in scenes,
// structure selection's candidates, the benchmarks and the tests.
#pragma once

#include <string>
#include <utility>

#include <Eigen/Core>

#include "motion_model_estimation/core/model.h"

namespace mme {

/// A parameter given in the model with `value` (a free one's first guess), without bounds.
Param valueParam(double value, bool free = false);
/// A free parameter with `value` as its first guess and search bounds [min, max].
Param boundedParam(double value, double min, double max);

/// What a particle is besides its position (a constructor, so that `{name, mass_kg}` leaves the
/// rest at its default).
struct ParticleOptions {
  ParticleOptions(std::string particle_name = "", double particle_mass_kg = 1.0,
                  const Eigen::Vector3d& initial_velocity_mps = Eigen::Vector3d::Zero(),
                  bool is_fixed = false, std::string group_name = "")
      : name(std::move(particle_name)), mass_kg(particle_mass_kg),
        velocity_mps(initial_velocity_mps), fixed(is_fixed), group(std::move(group_name)) {}
  std::string name;  ///< empty: "p<index>"
  double mass_kg;
  Eigen::Vector3d velocity_mps;
  bool fixed;
  std::string group;
};
/// Appends a particle at `position_m`; returns its index.
int addParticle(Model* model, const Eigen::Vector3d& position_m, const ParticleOptions& options = {});
/// Appends a bond type; returns its index.
int addBondType(Model* model, BondType type);
/// Appends a bond of type `type` joining particles a, b, c (-1: unused); returns its index.
int addBond(Model* model, int type, int a, int b = -1, int c = -1);

}  // namespace mme
