// Trajectory files of every kind the tools take, chosen by extension, through one entry point:
// TRC and C3D are read here (no ROS), and a layer above may add a format of its own (the ROS
// layer adds rosbags of MarkerFrame, ros/bag_format.h). So the offline tools build with or
// without ROS, and a build without it says plainly which formats it lacks.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "motion_model_estimation/core/trajectory.h"

namespace mme {

/// A coordinate farther than this from the origin [m] is no capture's (1000 km): the readers
/// refuse it naming the file, the frame (TRC: the line) and the marker, instead of letting it
/// reach a search as infinite bounds.
constexpr double kAbsurdCoordinate_m = 1e6;

/// The markers' spread (the median over frames of the diagonal of the visible markers' box) [m]
/// outside which a capture reads as being in the wrong units: a human or an object on a bench
/// spans 0.1-3 m.
constexpr double kImplausibleSpreadHigh_m = 30.0;
constexpr double kImplausibleSpreadLow_m = 0.005;

/// One plain sentence when the markers of `trajectory` (read from `path`) span an implausible
/// size for a capture (a units mistake: millimetres under a header saying m), with the measured
/// figure and the likely fix; "" otherwise (also with fewer than two markers seen together).
std::string implausibleSpreadWarning(const std::string& path, const Trajectory& trajectory);

struct TrajectoryWriteOptions {
  std::string topic = "markers";   ///< bag: the MarkerFrame topic
  std::string frame_id = "world";  ///< bag: header.frame_id of every frame
  std::string units = "mm";        ///< TRC: mm, cm or m
};

/// A file format added from outside the core (by extension, e.g. ".bag"). `read` gets the
/// topic the user named (empty: the file's only one); either function may be empty (the format
/// is then not read, or not written).
struct TrajectoryFormat {
  std::function<Trajectory(const std::string& path, const std::string& topic)> read;
  std::function<void(const std::string& path, const Trajectory& trajectory,
                     const TrajectoryWriteOptions& options)>
      write;
};
/// Adds (or replaces) the format of `extension` (lower case, with the dot). Thread-safe.
void registerTrajectoryFormat(const std::string& extension, TrajectoryFormat format);

/// ".trc" / ".c3d" (case-insensitive) -> reader; other extensions throw InputError.
/// The reader's warnings (see readTrc; readC3d has none: a C3D file cut short is an error) are
/// appended to `warnings` when given, for the caller to show.
Trajectory readTrajectoryFile(const std::string& path,
                              std::vector<std::string>* warnings = nullptr);

/// Reads `path` by its extension: .trc, .c3d, or a registered format (`topic` is passed to it).
/// The readers' warnings are appended to `warnings` when given. Throws InputError naming the
/// file on unreadable input, a file without frames, or an extension this build does not read
/// (the message lists those it reads).
Trajectory readTrajectory(const std::string& path, const std::string& topic,
                          std::vector<std::string>* warnings = nullptr);

/// Writes `trajectory` to `path` by its extension, atomically: .trc (occluded samples as empty
/// fields, times and frame numbers kept) or a registered format. Throws InputError on another
/// extension (naming those this build writes), bad units or a failed write.
void writeTrajectory(const std::string& path, const Trajectory& trajectory,
                     const TrajectoryWriteOptions& options = {});

/// Lower-case extension including the dot ("" when none).
std::string fileExtension(const std::string& path);

}  // namespace mme
