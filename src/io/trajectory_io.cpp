// Picks the trajectory reader from the file extension, so tools accept any supported format
// through one entry point. Bags are read by the ROS layer (this library has no ROS dependency).

#include "motion_model_estimation/io/trajectory_io.h"

#include <algorithm>
#include <cctype>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/io/c3d.h"
#include "motion_model_estimation/io/trc.h"

namespace mme {

std::string fileExtension(const std::string& path) {
  // Only the last path component counts: "runs.v2/data" has no extension.
  const size_t slash = path.find_last_of('/');
  const size_t name_start = slash == std::string::npos ? 0 : slash + 1;
  const size_t dot = path.find_last_of('.');
  // A leading dot marks a hidden file (".bashrc"), not an extension.
  if (dot == std::string::npos || dot <= name_start) return "";
  std::string ext = path.substr(dot);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

Trajectory readTrajectoryFile(const std::string& path, std::vector<std::string>* warnings) {
  const std::string ext = fileExtension(path);
  if (ext == ".trc") return readTrc(path, warnings);
  if (ext == ".c3d") return readC3d(path);
  throw InputError(path + ": unsupported trajectory file extension '" + ext +
                   "' (expected .trc, .c3d, or .bag via the ROS tools)");
}

}  // namespace mme
