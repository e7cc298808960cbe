#include "motion_model_estimation/io/trajectory_io.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <limits>
#include <map>
#include <mutex>
#include <utility>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/io/c3d.h"
#include "motion_model_estimation/io/trc.h"

namespace mme {

namespace {

/// The formats added from outside the core, by extension.
class FormatRegistry {
 public:
  static FormatRegistry& instance() {
    static FormatRegistry registry;
    return registry;
  }
  void add(const std::string& extension, TrajectoryFormat format) {
    std::lock_guard<std::mutex> lock(mutex_);
    formats_[extension] = std::move(format);
  }
  /// The format of `extension`, or one with neither function.
  TrajectoryFormat find(const std::string& extension) const {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = formats_.find(extension);
    return it == formats_.end() ? TrajectoryFormat{} : it->second;
  }
  /// "A, B or C": `built_in` and every registered extension with a reader (or a writer).
  std::string names(std::vector<std::string> built_in, bool writers) const {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& [extension, format] : formats_)
      if (writers ? static_cast<bool>(format.write) : static_cast<bool>(format.read))
        built_in.push_back(extension);
    std::string text;
    for (size_t k = 0; k < built_in.size(); ++k)
      text += (k == 0 ? "" : k + 1 == built_in.size() ? " or " : ", ") + built_in[k];
    return text;
  }

 private:
  mutable std::mutex mutex_;
  std::map<std::string, TrajectoryFormat> formats_;
};

/// What a build without the ROS layer lacks, said where the user meets it.
std::string missingFormatHint(const std::string& extension) {
  return extension == ".bag" ? " (rosbags need the ROS build of the tools)" : "";
}

}  // namespace

void registerTrajectoryFormat(const std::string& extension, TrajectoryFormat format) {
  FormatRegistry::instance().add(extension, std::move(format));
}

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
  throw InputError(path + ": unsupported trajectory file extension '" + ext + "' (expected " +
                   FormatRegistry::instance().names({".trc", ".c3d"}, false) + ")" +
                   missingFormatHint(ext));
}

Trajectory readTrajectory(const std::string& path, const std::string& topic,
                          std::vector<std::string>* warnings) {
  const std::string ext = fileExtension(path);
  const TrajectoryFormat format = FormatRegistry::instance().find(ext);
  Trajectory data = format.read ? format.read(path, topic) : readTrajectoryFile(path, warnings);
  if (data.numFrames() == 0) throw InputError(path + ": no frames");
  const std::string spread = implausibleSpreadWarning(path, data);
  if (warnings && !spread.empty()) warnings->push_back(spread);
  return data;
}

std::string implausibleSpreadWarning(const std::string& path, const Trajectory& trajectory) {
  std::vector<double> spreads_m;  // per frame with two markers or more seen
  for (int t = 0; t < trajectory.numFrames(); ++t) {
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d hi = -lo;
    int seen = 0;
    for (int i = 0; i < trajectory.numMarkers(); ++i) {
      if (trajectory.isOccluded(t, i)) continue;
      lo = lo.cwiseMin(trajectory.position(t, i));
      hi = hi.cwiseMax(trajectory.position(t, i));
      ++seen;
    }
    if (seen >= 2) spreads_m.push_back((hi - lo).norm());
  }
  if (spreads_m.empty()) return "";
  std::nth_element(spreads_m.begin(), spreads_m.begin() + spreads_m.size() / 2, spreads_m.end());
  const double spread_m = spreads_m[spreads_m.size() / 2];
  const bool large = spread_m > kImplausibleSpreadHigh_m;
  if (!large && !(spread_m < kImplausibleSpreadLow_m)) return "";
  char figure[64];
  if (large) std::snprintf(figure, sizeof(figure), "%.3g m", spread_m);
  else std::snprintf(figure, sizeof(figure), "%.3g mm", spread_m * 1e3);
  return path + ": the markers span " + figure +
         " (median over frames): a human capture spans 0.1-3 m; " +
         (large ? "is the file in millimetres with a header saying m (or cm)? "
                : "is the file in metres with a header saying mm? ") +
         "Fix the units in its header (TRC: the Units value; C3D: POINT:UNITS), or every length "
         "identified from it is off by the same factor";
}

void writeTrajectory(const std::string& path, const Trajectory& trajectory,
                     const TrajectoryWriteOptions& options) {
  const std::string ext = fileExtension(path);
  if (ext == ".trc") {
    writeTrc(path, trajectory, options.units);
    return;
  }
  const TrajectoryFormat format = FormatRegistry::instance().find(ext);
  if (!format.write)
    throw InputError(path + ": cannot write '" + ext + "' files (write " +
                     FormatRegistry::instance().names({".trc"}, true) + ")" + missingFormatHint(ext));
  format.write(path, trajectory, options);
}

}  // namespace mme
