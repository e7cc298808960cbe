// Trajectory files by extension (.trc, .c3d) for tools; bags live in the ROS layer.
#pragma once

#include <string>
#include <vector>

#include "motion_model_estimation/core/trajectory.h"

namespace mme {

/// ".trc" / ".c3d" (case-insensitive) -> reader; other extensions throw InputError.
/// The reader's warnings (see readTrc; readC3d has none: a C3D file cut short is an error) are
/// appended to `warnings` when given, for the caller to show.
Trajectory readTrajectoryFile(const std::string& path,
                              std::vector<std::string>* warnings = nullptr);
/// Lower-case extension including the dot ("" when none).
std::string fileExtension(const std::string& path);

}  // namespace mme
