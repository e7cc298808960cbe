// What the built-in scenes share (scenes.cpp, walker.cpp): their bounds convention, gravity,
// and the walker's maker. Internal to src/scenes/.
#pragma once

#include <Eigen/Core>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/model_builder.h"
#include "motion_model_estimation/scenes/scenes.h"

namespace mme {
namespace scene_parts {

constexpr double kPi = 3.14159265358979323846;

/// Positive magnitude (stiffness, damping, ...): bounds [truth/10, truth*10].
inline Param freeMagnitude(double value) { return boundedParam(value, value / 10.0, value * 10.0); }
/// Length (rest length, distance): bounds [truth/2, truth*2].
inline Param freeLength(double value) { return boundedParam(value, value / 2.0, value * 2.0); }

inline void setGravity(Model* model, const Eigen::Vector3d& g) {
  for (int k = 0; k < 3; ++k) model->gravity_mps2[k] = valueParam(g[k]);
}

/// The walker (walker.cpp).
Scene makeWalker();

}  // namespace scene_parts
}  // namespace mme
