// rosbag read/write of MarkerFrame messages (ROS layer).
#pragma once

#include <string>

#include "motion_model_estimation/core/trajectory.h"

namespace mme {

/// Writes every frame as a MarkerFrame on `topic` (stamps from times_s, frame_id as given).
void writeBag(const std::string& path, const std::string& topic, const std::string& frame_id,
              const Trajectory& trajectory);
/// Reads MarkerFrame messages from `topic` (empty = the only MarkerFrame topic). Marker names
/// from the first message; frames whose names differ are skipped. Rate from the median stamp
/// difference. Throws InputError naming the file on a missing topic, wrong type or bad bag.
Trajectory readBag(const std::string& path, const std::string& topic);

}  // namespace mme
