// Topic, service and frame names of the ROS layer in one place (SPEC sections 5 and 6).
#pragma once

namespace mme {
namespace names {
constexpr const char* kMarkersIn = "markers";          ///< MarkerFrame / PointCloud2 / vicon input
constexpr const char* kEstimate = "estimate";          ///< ~estimate (ModelEstimate)
constexpr const char* kVisualization = "markers";      ///< ~markers (MarkerArray), private ns
constexpr const char* kReset = "reset";                ///< ~reset (std_srvs/Trigger)
constexpr const char* kExportModel = "export_model";   ///< ~export_model (ExportModel)
constexpr const char* kLoadModel = "load_model";       ///< ~load_model (LoadModel)
constexpr const char* kMarkerFrameType = "motion_model_estimation/MarkerFrame";
constexpr const char* kViconMarkersType = "vicon_bridge/Markers";
}  // namespace names
}  // namespace mme
