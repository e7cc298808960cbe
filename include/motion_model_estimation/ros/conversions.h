// MarkerFrame <-> core frame conversions: the only place that knows the message layout.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>
#include <ros/time.h>

#include "motion_model_estimation/MarkerFrame.h"
#include "motion_model_estimation/core/trajectory.h"

namespace mme {

/// Frame t of a trajectory as a MarkerFrame.
motion_model_estimation::MarkerFrame toMarkerFrameMsg(const Trajectory& trajectory, int t, const std::string& frame_id,
                             const ros::Time& stamp);
/// Appends a MarkerFrame to a trajectory whose marker_names are set. Returns an empty string on
/// success, else why the frame was rejected (names differ, arrays of unequal length, NaN
/// handled as occluded is not a rejection).
std::string appendMarkerFrame(const motion_model_estimation::MarkerFrame& msg, Trajectory* trajectory);

}  // namespace mme
