#include "motion_model_estimation/ros/conversions.h"

#include <cmath>

namespace mme {

motion_model_estimation::MarkerFrame toMarkerFrameMsg(const Trajectory& trajectory, int t,
                                                      const std::string& frame_id,
                                                      const ros::Time& stamp) {
  motion_model_estimation::MarkerFrame msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = frame_id;
  msg.frame_number = trajectory.frame_numbers.empty() ? static_cast<uint32_t>(t)
                                                      : trajectory.frame_numbers[t];
  const int n = trajectory.numMarkers();
  msg.names = trajectory.marker_names;
  msg.positions.resize(n);
  bool any_occluded = false;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d& p = trajectory.position(t, i);
    msg.positions[i].x = p.x();
    msg.positions[i].y = p.y();
    msg.positions[i].z = p.z();
    any_occluded = any_occluded || trajectory.isOccluded(t, i);
  }
  if (any_occluded) {  // SPEC: empty = none occluded
    msg.occluded.resize(n);
    for (int i = 0; i < n; ++i) msg.occluded[i] = trajectory.isOccluded(t, i);
  }
  return msg;
}

std::string appendMarkerFrame(const motion_model_estimation::MarkerFrame& msg,
                              Trajectory* trajectory) {
  const size_t n = trajectory->marker_names.size();
  if (msg.names.size() != msg.positions.size())
    return "names and positions differ in length";
  if (!msg.occluded.empty() && msg.occluded.size() != msg.positions.size())
    return "occluded and positions differ in length";
  if (msg.names != trajectory->marker_names) return "marker names differ from the first frame";
  trajectory->times_s.push_back(msg.header.stamp.toSec());
  trajectory->frame_numbers.push_back(msg.frame_number);
  for (size_t i = 0; i < n; ++i) {
    const auto& p = msg.positions[i];
    Eigen::Vector3d x(p.x, p.y, p.z);
    // A NaN or infinite position is a missing sample, not a reason to drop the frame.
    const bool occluded = (!msg.occluded.empty() && msg.occluded[i]) || !x.allFinite();
    trajectory->positions_m.push_back(occluded ? Eigen::Vector3d::Zero() : x);
    trajectory->occluded.push_back(occluded ? 1 : 0);
  }
  return "";
}

}  // namespace mme
