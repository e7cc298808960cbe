#include "motion_model_estimation/ros/conversions.h"

#include <algorithm>
#include <cmath>

#include <sensor_msgs/point_cloud2_iterator.h>

#include "motion_model_estimation/live/marker_name_map.h"

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

std::string fromMarkerFrame(const motion_model_estimation::MarkerFrame& msg, ObservedPoints* points) {
  if (msg.names.size() != msg.positions.size() ||
      (!msg.occluded.empty() && msg.occluded.size() != msg.positions.size()))
    return MarkerNameMap::kLengthsDiffer;
  points->positions_m.resize(msg.positions.size());
  points->occluded.assign(msg.positions.size(), 0);
  for (size_t i = 0; i < msg.positions.size(); ++i) {
    points->positions_m[i] = Eigen::Vector3d(msg.positions[i].x, msg.positions[i].y, msg.positions[i].z);
    points->occluded[i] = !msg.occluded.empty() && msg.occluded[i];
  }
  return "";
}

std::string fromPointCloud(const sensor_msgs::PointCloud2& msg, ObservedPoints* points) {
  const size_t n = static_cast<size_t>(msg.width) * msg.height;
  bool has_xyz = false;
  for (const auto& f : msg.fields) has_xyz = has_xyz || f.name == "x";
  if (!has_xyz || msg.point_step == 0 || msg.data.size() < n * msg.point_step)
    return "PointCloud2 without x/y/z fields or with truncated data";
  points->positions_m.clear();
  points->occluded.clear();
  try {
    sensor_msgs::PointCloud2ConstIterator<float> it(msg, "x");
    for (size_t i = 0; i < n; ++i, ++it) {
      points->positions_m.emplace_back(it[0], it[1], it[2]);
      points->occluded.push_back(!points->positions_m.back().allFinite());
    }
  } catch (const std::exception& e) {
    return std::string("PointCloud2: ") + e.what();
  }
  return "";
}

Eigen::Isometry3d fromTransform(const geometry_msgs::Transform& transform) {
  const auto& q = transform.rotation;
  const auto& t = transform.translation;
  return Eigen::Isometry3d(Eigen::Translation3d(t.x, t.y, t.z) * Eigen::Quaterniond(q.w, q.x, q.y, q.z));
}

motion_model_estimation::ModelEstimate toModelEstimateMsg(const Estimate& e, const std::string& frame_id,
                                                          const ros::Time& stamp) {
  motion_model_estimation::ModelEstimate msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = frame_id;
  msg.generation = e.generation;
  msg.evaluations = e.evaluations;
  msg.global_cost = e.global_cost;
  msg.window_frames = e.window_frames;
  msg.parameter_names = e.parameter_names;
  msg.values = e.values;
  msg.std_devs = e.std_devs;
  msg.stable = e.stable;
  msg.estimator = estimatorName(e.estimator);
  for (ParameterFlag flag : e.parameter_flags) msg.parameter_flags.push_back(parameterFlagName(flag));
  msg.noise_std_m = e.noise_std_m;
  return msg;
}

motion_model_estimation::Migrants toMigrantsMsg(const MigrantBatch& batch, const ros::Time& stamp) {
  motion_model_estimation::Migrants msg;
  msg.header.stamp = stamp;
  msg.island_id = batch.island_id;
  msg.seed = batch.seed;
  msg.generation = batch.generation;
  msg.parameter_names = batch.parameter_names;
  msg.migrant_count = static_cast<uint32_t>(batch.individuals.size());
  for (const Individual& ind : batch.individuals) {
    msg.genes.insert(msg.genes.end(), ind.genes.begin(), ind.genes.end());
    msg.mutabilities.insert(msg.mutabilities.end(), ind.mutability.begin(), ind.mutability.end());
    msg.costs.push_back(ind.cost);
  }
  msg.window_start.fromSec(std::max(0.0, batch.window_start_time_s));
  msg.window_end.fromSec(std::max(0.0, batch.window_end_time_s));
  return msg;
}

std::string fromMigrantsMsg(const motion_model_estimation::Migrants& msg, MigrantBatch* batch) {
  *batch = MigrantBatch();
  batch->island_id = msg.island_id;
  batch->seed = msg.seed;
  batch->generation = msg.generation;
  batch->parameter_names = msg.parameter_names;
  batch->window_start_time_s = msg.window_start.toSec();
  batch->window_end_time_s = msg.window_end.toSec();
  return unflattenMigrants(msg.migrant_count, msg.genes, msg.mutabilities, msg.costs, batch);
}

}  // namespace mme
