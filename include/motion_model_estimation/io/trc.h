// OpenSim TRC marker files (text): read and write.
#pragma once

#include <string>
#include <vector>

#include "motion_model_estimation/core/trajectory.h"

namespace mme {

/// Reads a TRC file; units mm, cm or m converted to metres; empty fields or 0,0,0 = occluded.
/// Throws InputError naming the file and line on malformed input.
/// Problems that still leave usable data (a file with fewer rows than its header's NumFrames,
/// e.g. a cut-off copy) are appended to `warnings` as one line naming the file, when given;
/// the reader itself never prints.
Trajectory readTrc(const std::string& path, std::vector<std::string>* warnings = nullptr);
/// Writes a TRC file in `units` ("mm", "cm" or "m"), occluded samples as empty fields; atomic.
void writeTrc(const std::string& path, const Trajectory& trajectory, const std::string& units = "mm");

}  // namespace mme
