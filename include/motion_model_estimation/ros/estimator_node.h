// The online estimator's ROS wiring (SPEC section 6): inputs (MarkerFrame, PointCloud2,
// vicon_bridge/Markers, a bag), tf2 into ~fixed_frame, a worker thread running the
// OnlineEstimator, ~estimate, ~markers, ~stats and the services. Domain logic lives in ROS-free
// units: the estimator (identification/), marker-name mapping, the visualisation snapshot,
// clock-jump, update-gap and latency statistics and the ~stats line (live/).
#pragma once

#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>
#include <topic_tools/shape_shifter.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "motion_model_estimation/ExportModel.h"
#include "motion_model_estimation/LoadModel.h"
#include "motion_model_estimation/MarkerFrame.h"
#include "motion_model_estimation/identification/online/online_estimator.h"
#include "motion_model_estimation/live/clock_jump_detector.h"
#include "motion_model_estimation/live/estimator_node_options.h"
#include "motion_model_estimation/live/latency_stats.h"
#include "motion_model_estimation/live/marker_name_map.h"
#include "motion_model_estimation/live/muscle_job.h"
#include "motion_model_estimation/live/prediction_monitor.h"
#include "motion_model_estimation/live/structure_job.h"
#include "motion_model_estimation/live/update_gap_stats.h"
#include "motion_model_estimation/live/visualisation_snapshot.h"
#include "motion_model_estimation/ros/island_link.h"
#include "motion_model_estimation/ros/marker_builder.h"

namespace mme {

/// Reads and validates every private param (readEstimatorNodeOptions on the parameter server).
/// Throws InputError naming the bad param.
EstimatorNodeOptions readEstimatorOptions(const ros::NodeHandle& pnh);

class EstimatorNode {
 public:
  /// Loads the model, advertises and subscribes. Throws InputError on bad params or model.
  EstimatorNode(ros::NodeHandle nh, ros::NodeHandle pnh, const EstimatorNodeOptions& options);
  ~EstimatorNode();
  /// Runs until shutdown (AsyncSpinner + worker thread + optional bag feeder).
  void run();

 private:
  void onMarkerFrame(const motion_model_estimation::MarkerFrame::ConstPtr& msg);
  void onPointCloud(const sensor_msgs::PointCloud2::ConstPtr& msg);
  void onVicon(const topic_tools::ShapeShifter::ConstPtr& msg);
  /// Common path: names (empty = model order), transform, mask, add to the estimator.
  /// `arrival`: when the frame's callback started (the latency benchmark's origin).
  void addObservation(const ros::Time& stamp, const std::string& frame_id,
                      const std::vector<std::string>& names,
                      std::vector<Eigen::Vector3d> positions_m, std::vector<uint8_t> occluded,
                      std::chrono::steady_clock::time_point arrival);
  void reject(const std::string& why);
  void workerLoop();
  /// Gives `model` (a structure chosen, or the selection's first level) to the estimator and
  /// drops the muscles fitted on the previous one; false (logged) when the estimator refuses it.
  bool useStructure(const Model& model);
  /// Names the calling thread and gives it ~background_nice (threads beside the worker).
  void startBackgroundThread(const char* name) const;
  void connectRos();  ///< advertise, subscribe, start the timers
  /// ~select_structure: chooses the structure when requested and the window is full, then
  /// hands the model to the estimator and writes the report.
  void structureLoop();
  /// ~sensor_muscles: once the passive model is estimated (and its structure chosen), adds
  /// sensor muscles on the window, then refits their linear part each period (MuscleJob keeps
  /// them; the estimator goes on with the passive model).
  void muscleLoop();
  /// The estimator's current model with the kept muscles laid on it (the passive one when none)
  /// and `window` with its particles (anchors added, occluded); what is judged, drawn, exported.
  Model shownModel(Trajectory* window = nullptr) const;
  void bagLoop();
  void onPublishTimer(const ros::WallTimerEvent&);
  /// ~markers thread: rebuilds the rviz markers as soon as a frame is accepted (latest frame
  /// wins when several arrived meanwhile) and when the estimate changes; records the latency
  /// from the frame's arrival to the publication of the markers built from it.
  void markersLoop();
  bool publishMarkers(const Estimate& estimate);  ///< false: nothing to show yet
  void onAutosaveTimer(const ros::WallTimerEvent&);
  void onStatsTimer(const ros::WallTimerEvent&);  ///< ~stats (std_msgs/String, formatStats)
  std::string exportYaml(const Estimate& estimate) const;
  bool onReset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  bool onExport(motion_model_estimation::ExportModel::Request& req,
                motion_model_estimation::ExportModel::Response& res);
  bool onLoad(motion_model_estimation::LoadModel::Request& req,
              motion_model_estimation::LoadModel::Response& res);

  ros::NodeHandle nh_, pnh_;
  EstimatorNodeOptions options_;
  std::unique_ptr<OnlineEstimator> estimator_;
  std::string fixed_frame_;
  MarkerStyle marker_style_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  ros::Subscriber input_sub_;
  ros::Publisher estimate_pub_, markers_pub_, stats_pub_;
  ros::ServiceServer reset_srv_, export_srv_, load_srv_;
  ros::WallTimer publish_timer_, autosave_timer_, stats_timer_;
  std::string autosave_target_;  // confined absolute path, "" = off
  std::thread worker_, bag_thread_, markers_thread_, structure_thread_, muscle_thread_;
  std::unique_ptr<MuscleJob> muscles_;  // null unless ~sensor_muscles
  std::unique_ptr<StructureJob> structure_;  // null unless ~select_structure
  std::string structure_report_target_;      // confined absolute path
  // Marker thread hand-off (markersLoop): the newest accepted frame's arrival and a counter.
  std::mutex markers_mutex_;
  std::condition_variable markers_cv_;
  uint64_t frames_accepted_seq_ = 0, frames_rendered_seq_ = 0;
  bool markers_estimate_changed_ = false;
  std::chrono::steady_clock::time_point newest_arrival_;
  std::atomic<bool> stop_{false};
  /// A structure chosen by the selection (or its first level) is in the estimator: the muscles
  /// may be fitted on it.
  std::atomic<bool> structure_in_use_{false};
  std::atomic<uint64_t> rejected_{0};
  std::atomic<uint32_t> last_published_generation_{0};  // timer and services: two threads
  // Statistics (thread-safe units): arrival -> ~markers latency, gaps between updates, jumps.
  LatencyStats latency_stats_;
  UpdateGapStats update_stats_;
  ClockJumpDetector clock_jumps_;
  std::unique_ptr<PredictionMonitor> predictions_;  // null when ~prediction_period_sec is 0
  // The input path (names_ -> estimator -> clock_jumps_) against ~load_model's replacement.
  std::mutex input_mutex_;
  MarkerNameMap names_;
  // ~islands/enabled; declared after estimator_, so destroyed (unsubscribed) before it.
  std::unique_ptr<IslandLink> islands_;
};

}  // namespace mme
