// Sanity checks on an identified model, in plain words: results that are numbers but look wrong
// (a gravity far from the Earth's, a spring whose rest length is nothing next to the distance
// its markers keep) are said to the user with the likely cause, instead of being written
// silently. Also the units the parameter table prints.
#pragma once

#include <string>
#include <vector>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/identification/structure/structure_selection.h"

namespace mme {

/// The unit of a parameter, from the catalogue (core/bond_kind.h ParamInfo): "N/m", "m",
/// "m/s^2" for gravity; per radian instead of per metre on a flexion; "1" for a muscle's network
/// weights.
std::string parameterUnit(const Model& model, const ParamRef& ref);

/// Every particle weighs 1 kg (the markers' starting model, whose masses are not measured):
/// forces, and so stiffnesses, dampings and gains, are then per kilogram of marker.
bool unitMasses(const Model& model);

/// A free gravity whose magnitude lies outside [kGravityLow, kGravityHigh] m/s^2 is flagged.
constexpr double kGravityLow_mps2 = 9.81 / 2.0;
constexpr double kGravityHigh_mps2 = 9.81 * 2.0;
/// A bond whose rest length is below this share of its markers' median distance is flagged.
constexpr double kTinyRestShare = 0.05;

/// The identified model's implausible figures, one plain sentence each (empty: none): a free
/// gravity far from 9.81 m/s^2 (a units mistake, or a model missing what holds the markers up),
/// and every pair bond whose rest length is below kTinyRestShare of the median distance its two
/// markers keep in `trajectory` (the model's particles as markers).
std::vector<std::string> identifiedModelWarnings(const Model& identified, const Trajectory& trajectory);

/// One line naming every horizon (1, 5, 10 frames) at which a model-free guess predicts the
/// held-out frames better than the chosen structure, with both figures (empty: it wins
/// everywhere): the model then does not capture the motion, however well it fits.
std::vector<std::string> chosenStructureWarnings(const StructureResult& structure);

}  // namespace mme
