#include "motion_model_estimation/ros/bag_format.h"

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/io/trajectory_io.h"
#include "motion_model_estimation/ros/bag_io.h"

namespace mme {

void registerBagFormat() {
  TrajectoryFormat bag;
  bag.read = [](const std::string& path, const std::string& topic) { return readBag(path, topic); };
  bag.write = [](const std::string& path, const Trajectory& trajectory,
                 const TrajectoryWriteOptions& options) {
    if (options.topic.empty()) throw InputError(path + ": the bag's topic is empty");
    writeBag(path, options.topic, options.frame_id, trajectory);
  };
  registerTrajectoryFormat(".bag", bag);
}

}  // namespace mme
