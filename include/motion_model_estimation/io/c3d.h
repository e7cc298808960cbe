// C3D binary motion-capture files: read (Intel / DEC processor formats, float / integer storage).
#pragma once

#include <string>

#include "motion_model_estimation/core/trajectory.h"

namespace mme {

/// Reads 3-D points of a C3D file. Honours POINT:SCALE (negative = float storage), POINT:UNITS
/// (mm/cm/m -> metres), POINT:LABELS, POINT:RATE; residual < 0 or 0,0,0 = occluded.
/// Throws InputError naming the file on malformed input.
Trajectory readC3d(const std::string& path);

}  // namespace mme
