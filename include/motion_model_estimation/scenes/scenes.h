// Built-in scenes of SPEC section 8: models with true parameters and free flags set.
#pragma once

#include <string>
#include <vector>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"

namespace mme {

struct Scene {
  Model model;                 ///< true values; free flags = what identification should find
  int default_frames = 100;    ///< frames `simulate` writes when asked for the scene's default
  /// Data set used by identification benchmarks: for most scenes empty (simulate the model);
  /// for provot_cloth the single equilibrium frame.
  Trajectory reference_data;
};

std::vector<std::string> sceneNames();
/// Throws InputError listing the known names when `name` is unknown.
Scene makeScene(const std::string& name);

}  // namespace mme
