// Trajectory files of every kind the tools take, chosen by extension: TRC and C3D (io/, no ROS)
// and rosbags of MarkerFrame (bag_io.h). What `identify`, `evaluate`, `simulate` and `convert`
// read and write through.
#pragma once

#include <string>
#include <vector>

#include "motion_model_estimation/core/trajectory.h"

namespace mme {

/// Reads `path`: .trc, .c3d (readTrajectoryFile) or .bag (readBag, MarkerFrame on `topic`; empty
/// = the only MarkerFrame topic). The readers' warnings are appended to `warnings` when given.
/// Throws InputError naming the file on unreadable input or a file without frames.
Trajectory readTrajectory(const std::string& path, const std::string& topic,
                          std::vector<std::string>* warnings = nullptr);

struct TrajectoryWriteOptions {
  std::string topic = "markers";  ///< bag: the MarkerFrame topic
  std::string frame_id = "world";  ///< bag: header.frame_id of every frame
  std::string units = "mm";        ///< TRC: mm, cm or m
};

/// Writes `trajectory` to `path` by its extension, atomically: .trc (occluded samples as empty
/// fields, times and frame numbers kept) or .bag (one MarkerFrame per frame, stamped with its
/// time; occluded samples flagged). Throws InputError on another extension, bad units or a
/// failed write.
void writeTrajectory(const std::string& path, const Trajectory& trajectory,
                     const TrajectoryWriteOptions& options = {});

}  // namespace mme
