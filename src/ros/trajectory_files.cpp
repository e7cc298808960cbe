#include "motion_model_estimation/ros/trajectory_files.h"

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/io/trajectory_io.h"
#include "motion_model_estimation/io/trc.h"
#include "motion_model_estimation/ros/bag_io.h"

namespace mme {

Trajectory readTrajectory(const std::string& path, const std::string& topic,
                          std::vector<std::string>* warnings) {
  Trajectory data = fileExtension(path) == ".bag" ? readBag(path, topic)
                                                  : readTrajectoryFile(path, warnings);
  if (data.numFrames() == 0) throw InputError(path + ": no frames");
  return data;
}

void writeTrajectory(const std::string& path, const Trajectory& trajectory,
                     const TrajectoryWriteOptions& options) {
  const std::string ext = fileExtension(path);
  if (ext == ".trc") {
    writeTrc(path, trajectory, options.units);
  } else if (ext == ".bag") {
    if (options.topic.empty()) throw InputError(path + ": the bag's topic is empty");
    writeBag(path, options.topic, options.frame_id, trajectory);
  } else {
    throw InputError(path + ": cannot write '" + ext + "' files (write .trc or .bag)");
  }
}

}  // namespace mme
