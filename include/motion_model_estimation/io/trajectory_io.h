// Trajectory files by extension (.trc, .c3d) for tools; bags live in the ROS layer.
#pragma once

#include <string>

#include "motion_model_estimation/core/trajectory.h"

namespace mme {

/// ".trc" / ".c3d" (case-insensitive) -> reader; other extensions throw InputError.
Trajectory readTrajectoryFile(const std::string& path);
/// Lower-case extension including the dot ("" when none).
std::string fileExtension(const std::string& path);

}  // namespace mme
