// Messages <-> core values: the only place that knows the messages' layouts (MarkerFrame,
// PointCloud2, tf's Transform, ModelEstimate), so that the node only wires topics to the core.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <geometry_msgs/Transform.h>
#include <ros/time.h>
#include <sensor_msgs/PointCloud2.h>

#include "motion_model_estimation/MarkerFrame.h"
#include "motion_model_estimation/Migrants.h"
#include "motion_model_estimation/ModelEstimate.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/identification/online/migrants.h"
#include "motion_model_estimation/identification/online/online_estimator.h"

namespace mme {

/// Frame t of a trajectory as a MarkerFrame.
motion_model_estimation::MarkerFrame toMarkerFrameMsg(const Trajectory& trajectory, int t, const std::string& frame_id,
                             const ros::Time& stamp);
/// Appends a MarkerFrame to a trajectory whose marker_names are set. Returns an empty string on
/// success, else why the frame was rejected (names differ, arrays of unequal length, NaN
/// handled as occluded is not a rejection).
std::string appendMarkerFrame(const motion_model_estimation::MarkerFrame& msg, Trajectory* trajectory);

/// One frame's points in the order they arrived [m], with their occlusion flags.
struct ObservedPoints {
  std::vector<Eigen::Vector3d> positions_m;
  std::vector<uint8_t> occluded;  ///< 1 = occluded
};

/// A MarkerFrame's points (names as they are: the caller maps them). Returns "" or, when the
/// arrays' lengths differ, why the frame is refused.
std::string fromMarkerFrame(const motion_model_estimation::MarkerFrame& msg, ObservedPoints* points);
/// A PointCloud2's x/y/z (float32) in point order; a non-finite point is occluded. Returns "" or
/// why the cloud is refused (no x field, truncated data, a field layout the iterator rejects).
std::string fromPointCloud(const sensor_msgs::PointCloud2& msg, ObservedPoints* points);
/// tf's transform as a pose.
Eigen::Isometry3d fromTransform(const geometry_msgs::Transform& transform);
/// The estimate as ~estimate publishes it (enums as their names).
motion_model_estimation::ModelEstimate toModelEstimateMsg(const Estimate& estimate,
                                                          const std::string& frame_id,
                                                          const ros::Time& stamp);

/// An island's emigrants as a Migrants message (genes, mutabilities and costs flattened
/// migrant by migrant), stamped `stamp` (the send time).
motion_model_estimation::Migrants toMigrantsMsg(const MigrantBatch& batch, const ros::Time& stamp);
/// A Migrants message as a batch. Returns "" or, when the arrays' lengths do not agree with
/// migrant_count and the parameter names, why the message is refused (unflattenMigrants: the
/// batch then holds no individuals).
std::string fromMigrantsMsg(const motion_model_estimation::Migrants& msg, MigrantBatch* batch);

}  // namespace mme
