#include "motion_model_estimation/ros/estimator_node.h"

#include <geometry_msgs/TransformStamped.h>
#include <std_msgs/String.h>

#include <sys/stat.h>

#include <Eigen/Geometry>
#include <cerrno>
#include <cstdlib>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>

#include "motion_model_estimation/ModelEstimate.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/io/model_yaml.h"
#include "motion_model_estimation/io/path_confinement.h"
#include "motion_model_estimation/io/trajectory_io.h"
#include "motion_model_estimation/live/estimator_stats.h"
#include "motion_model_estimation/live/muscle_refit.h"
#include "motion_model_estimation/live/replay_pacing.h"
#include "motion_model_estimation/live/thread_times.h"
#include "motion_model_estimation/pipeline/result_metadata.h"
#include "motion_model_estimation/ros/bag_io.h"
#include "motion_model_estimation/ros/conversions.h"
#include "motion_model_estimation/ros/names.h"
#include "motion_model_estimation/ros/param_utils.h"
#include "motion_model_estimation/ros/vicon_markers.h"

namespace mme {

namespace {

/// The parameter server as a ParameterSource: a param set with the wrong type is an error
/// naming it (readParam), an unset one keeps the documented default.
class RosParameterSource : public ParameterSource {
 public:
  explicit RosParameterSource(const ros::NodeHandle& pnh) : pnh_(pnh) {}
  bool get(const std::string& name, std::string* value) const override { return read(name, value); }
  bool get(const std::string& name, double* value) const override { return read(name, value); }
  bool get(const std::string& name, int* value) const override { return read(name, value); }
  bool get(const std::string& name, bool* value) const override { return read(name, value); }

 private:
  template <typename T>
  bool read(const std::string& name, T* value) const {
    std::string error;
    if (!readParam(pnh_, name, value, &error)) throw InputError(error);
    return pnh_.hasParam(name);
  }
  const ros::NodeHandle& pnh_;
};

/// [s] on the monotonic clock: update gaps must not follow wall-clock or sim-time jumps.
double steadyNowS() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

}  // namespace

EstimatorNodeOptions readEstimatorOptions(const ros::NodeHandle& pnh) {
  return readEstimatorNodeOptions(RosParameterSource(pnh));
}

EstimatorNode::EstimatorNode(ros::NodeHandle nh, ros::NodeHandle pnh,
                             const EstimatorNodeOptions& options)
    : nh_(nh), pnh_(pnh), options_(options), tf_listener_(tf_buffer_) {
  Model model = loadModelFile(options_.model_path);
  OnlineEstimatorOptions estimator_options = options_.estimator;
  if (!options_.initial_model.empty()) {
    struct stat st;
    if (::stat(options_.initial_model.c_str(), &st) == 0) {
      // A saved model (e.g. the autosave of a previous run): same structure, values to resume.
      model = loadModelFile(options_.initial_model);
      estimator_options.resume_from_model_values = true;
      ROS_INFO("estimator_node: resuming from %s", options_.initial_model.c_str());
    } else {
      ROS_INFO("estimator_node: ~initial_model %s does not exist yet; starting from ~model",
               options_.initial_model.c_str());
    }
  }
  if (::mkdir(options_.model_dir.c_str(), 0755) != 0 && errno != EEXIST)
    throw InputError("~model_dir '" + options_.model_dir + "' cannot be created");
  if (!options_.autosave_path.empty()) {
    std::string error;
    autosave_target_ = confinePath(options_.model_dir, options_.autosave_path, true, &error);
    if (autosave_target_.empty()) throw InputError("~autosave_path: " + error);
  }
  if (options_.select_structure) {
    std::string error;
    structure_report_target_ = confinePath(options_.model_dir, options_.structure_report_path, true, &error);
    if (structure_report_target_.empty()) throw InputError("~structure_report_path: " + error);
    PipelineOptions so;
    so.identify.es.threads = estimator_options.es.threads;
    so.identify.max_wall_time_s = options_.structure_max_time_s;
    so.say = [](const std::string& line) { ROS_INFO("estimator_node: %s", line.c_str()); };
    // A resumed model has its structure: the selection then waits for ~reset.
    const bool resumed = estimator_options.resume_from_model_values;
    structure_ = std::make_unique<StructureJob>(model, so, estimator_options.window_frames, !resumed);
    estimator_options.wait_for_structure = true;
  }
  if (options_.sensor_muscles) {
    MuscleJobOptions mo = options_.muscles;
    mo.say = [](const std::string& line) { ROS_INFO("estimator_node: %s", line.c_str()); };
    if (refittableMuscleTypes(model) > 0)
      ROS_WARN("estimator_node: ~sensor_muscles: the model has muscles already; none are added");
    else
      muscles_ = std::make_unique<MuscleJob>(mo);
  }
  estimator_options.on_background_thread_start = [this] { startBackgroundThread("mme_refine"); };
  estimator_ = std::make_unique<OnlineEstimator>(model, estimator_options);
  if (!estimator_options.estimate_values)
    ROS_INFO("estimator_node: ~estimate_values is false: the model of %s is shown as it is, its "
             "values are never changed",
             (estimator_options.resume_from_model_values ? options_.initial_model : options_.model_path).c_str());
  names_.setParticles(estimator_->particleNames());
  fixed_frame_ = options_.fixed_frame.empty() ? model.frame_id : options_.fixed_frame;
  marker_style_.frame_id = fixed_frame_;
  marker_style_.particle_diameter_m = options_.particle_diameter_m;
  connectRos();
  if (options_.islands.enabled) {
    IslandLinkOptions islands = options_.islands;
    if (islands.island_id.empty()) islands.island_id = ros::this_node::getName();
    try {
      islands_ = std::make_unique<IslandLink>(nh_, islands, estimator_.get());
    } catch (const ros::InvalidNameException& e) {
      throw InputError("~migration_topic '" + islands.migration_topic + "': " + e.what());
    }
    ROS_INFO("estimator_node: island '%s': %d migrants every %d generations on %s",
             islands.island_id.c_str(), islands.migrants, islands.migration_period_generations,
             islands.migration_topic.c_str());
  }
  ROS_INFO("estimator_node: %zu particles, %zu free parameters, window %d frames, population %d, "
           "input %s%s", model.particles.size(), freeParameters(model).size(),
           options_.estimator.window_frames, options_.estimator.es.population,
           options_.bag.empty() ? inputTypeName(options_.input_type) : "bag ",
           options_.bag.c_str());
}

/// The node's topics, services and timers (the estimator and the background jobs exist by now).
void EstimatorNode::connectRos() {
  estimate_pub_ = pnh_.advertise<motion_model_estimation::ModelEstimate>(names::kEstimate, 10);
  markers_pub_ = pnh_.advertise<visualization_msgs::MarkerArray>(names::kVisualization, 2);
  stats_pub_ = pnh_.advertise<std_msgs::String>("stats", 1, true);  // latched, 1 Hz
  reset_srv_ = pnh_.advertiseService(names::kReset, &EstimatorNode::onReset, this);
  export_srv_ = pnh_.advertiseService(names::kExportModel, &EstimatorNode::onExport, this);
  load_srv_ = pnh_.advertiseService(names::kLoadModel, &EstimatorNode::onLoad, this);
  if (options_.bag.empty()) {
    switch (options_.input_type) {
      case InputType::kMarkers:
        input_sub_ = nh_.subscribe(names::kMarkersIn, 200, &EstimatorNode::onMarkerFrame, this);
        break;
      case InputType::kPointCloud:
        input_sub_ = nh_.subscribe(names::kMarkersIn, 200, &EstimatorNode::onPointCloud, this);
        break;
      case InputType::kVicon:
        input_sub_ = nh_.subscribe(names::kMarkersIn, 200, &EstimatorNode::onVicon, this);
        break;
    }
  }
  publish_timer_ = nh_.createWallTimer(ros::WallDuration(1.0 / options_.update_rate_hz),
                                       &EstimatorNode::onPublishTimer, this);
  if (!autosave_target_.empty())
    autosave_timer_ = nh_.createWallTimer(ros::WallDuration(options_.autosave_period_sec),
                                          &EstimatorNode::onAutosaveTimer, this);
  if (options_.prediction_period_sec > 0.0)
    predictions_ = std::make_unique<PredictionMonitor>(std::vector<int>{1, 5, 10},
                                                       options_.prediction_period_sec);
  stats_timer_ = nh_.createWallTimer(ros::WallDuration(1.0), &EstimatorNode::onStatsTimer, this);
}

EstimatorNode::~EstimatorNode() {
  stop_ = true;
  if (muscles_) muscles_->cancel();
  markers_cv_.notify_all();
  if (worker_.joinable()) worker_.join();
  if (markers_thread_.joinable()) markers_thread_.join();
  if (bag_thread_.joinable()) bag_thread_.join();
  if (structure_thread_.joinable()) structure_thread_.join();
  if (muscle_thread_.joinable()) muscle_thread_.join();
}

void EstimatorNode::startBackgroundThread(const char* name) const {
  nameCallingThread(name);
  if (options_.background_nice <= 0) return;
  const std::string error = lowerCallingThreadPriority(options_.background_nice);
  if (!error.empty())
    ROS_WARN_ONCE("estimator_node: ~background_nice: the background threads keep the worker's "
                  "priority (%s)", error.c_str());
}

void EstimatorNode::reject(const std::string& why) {
  ++rejected_;
  ROS_WARN_THROTTLE(2.0, "estimator_node: frame skipped: %s (%llu skipped so far)", why.c_str(),
                    static_cast<unsigned long long>(rejected_.load()));
}

void EstimatorNode::onMarkerFrame(const motion_model_estimation::MarkerFrame::ConstPtr& msg) {
  const auto arrival = std::chrono::steady_clock::now();
  ObservedPoints points;
  const std::string why = fromMarkerFrame(*msg, &points);
  if (!why.empty()) return reject(why);
  addObservation(msg->header.stamp, msg->header.frame_id, msg->names, std::move(points.positions_m),
                 std::move(points.occluded), arrival);
}

void EstimatorNode::onPointCloud(const sensor_msgs::PointCloud2::ConstPtr& msg) {
  const auto arrival = std::chrono::steady_clock::now();
  ObservedPoints points;
  const std::string why = fromPointCloud(*msg, &points);
  if (!why.empty()) return reject(why);
  addObservation(msg->header.stamp, msg->header.frame_id, {}, std::move(points.positions_m),
                 std::move(points.occluded), arrival);
}

void EstimatorNode::onVicon(const topic_tools::ShapeShifter::ConstPtr& msg) {
  const auto arrival = std::chrono::steady_clock::now();
  if (msg->getDataType() != names::kViconMarkersType) {
    reject("expected vicon_bridge/Markers, got " + msg->getDataType());
    return;
  }
  std::vector<uint8_t> bytes(msg->size());
  ros::serialization::OStream stream(bytes.data(), static_cast<uint32_t>(bytes.size()));
  msg->write(stream);
  ViconMarkers m;
  std::string error;
  if (!decodeViconMarkers(bytes.data(), bytes.size(), options_.vicon_qualify_with_subject, &m,
                          &error)) {
    reject(error);
    return;
  }
  ros::Time stamp;
  stamp.fromSec(m.stamp_s);
  addObservation(stamp, m.frame_id, m.names, std::move(m.positions_m), std::move(m.occluded),
                 arrival);
}

void EstimatorNode::addObservation(const ros::Time& stamp, const std::string& frame_id,
                                   const std::vector<std::string>& names,
                                   std::vector<Eigen::Vector3d> positions_m,
                                   std::vector<uint8_t> occluded,
                                   std::chrono::steady_clock::time_point arrival) {
  // Bring the points into the fixed frame.
  if (!frame_id.empty() && frame_id != fixed_frame_) {
    geometry_msgs::TransformStamped tf;
    try {
      tf = tf_buffer_.lookupTransform(fixed_frame_, frame_id, stamp,
                                      ros::Duration(options_.tf_timeout_sec));
    } catch (const std::exception& e) {
      reject("no transform " + frame_id + " -> " + fixed_frame_ + ": " + e.what());
      return;
    }
    const Eigen::Isometry3d pose = fromTransform(tf.transform);
    for (Eigen::Vector3d& x : positions_m) x = pose * x;
  }
  {
    // Held through addFrame: a model loaded meanwhile cannot slip between the mapping, the
    // frame and the clock-jump bookkeeping.
    std::lock_guard<std::mutex> lock(input_mutex_);
    // Map input order to the model's particle order.
    const MappedFrame frame = names_.map(names, std::move(positions_m), std::move(occluded));
    if (!frame.warning.empty()) ROS_WARN("estimator_node: %s", frame.warning.c_str());
    if (!frame.rejection.empty()) {
      reject(frame.rejection);
      return;
    }
    const double time_s = stamp.toSec();
    const std::string why = estimator_->addFrame(time_s, frame.positions_m, frame.occluded);
    if (!why.empty()) {
      reject(why);
      return;
    }
    if (const std::optional<double> jump_s = clock_jumps_.onAcceptedFrame(time_s)) {
      // OnlineEstimator::addFrame started a new window (the identified model lives on).
      ROS_WARN_THROTTLE(5.0, "estimator_node: %s",
                        ClockJumpDetector::warning(*jump_s, clock_jumps_.jumps()).c_str());
    }
  }
  {
    std::lock_guard<std::mutex> lock(markers_mutex_);
    ++frames_accepted_seq_;
    newest_arrival_ = arrival;
  }
  markers_cv_.notify_one();
}

void EstimatorNode::onStatsTimer(const ros::WallTimerEvent&) {
  EstimatorStats stats;
  stats.input = estimator_->counters();
  stats.rejected = rejected_;
  stats.clock_jumps = clock_jumps_.jumps();
  stats.updates = update_stats_.summary(steadyNowS());
  stats.latency = latency_stats_.summary();
  stats.output_error_rejections = estimator_->estimate().output_error_rejections;
  if (islands_) stats.islands = islands_->stats();
  if (predictions_) {
    const double now_s = steadyNowS();
    Trajectory window;
    if (predictions_->due(now_s) && estimator_->estimate().valid &&
        !predictions_->evaluate(now_s, shownModel(&window), window))
      ROS_WARN_THROTTLE(60.0, "estimator_node: no prediction figures on this window: %s",
                        predictions_->lastError().c_str());
    stats.prediction = predictions_->report();
  }
  if (structure_) {
    stats.structure = structure_->status();
    stats.structure_selections = structure_->selections();
    stats.structure_cut = structure_->lastCut();
    if (structure_->state() == StructureJob::State::kFailed) stats.structure_error = structure_->lastError();
  }
  if (muscles_) {
    stats.muscles = muscles_->status();
    stats.muscle_count = muscles_->muscles();
    stats.muscle_refits = muscles_->refits();
    stats.muscle_refits_adopted = muscles_->refitsAdopted();
    stats.muscle_refit_ms = muscles_->lastRefitMs();
  }
  std_msgs::String msg;
  msg.data = formatStats(stats);
  stats_pub_.publish(msg);
}

void EstimatorNode::workerLoop() {
  nameCallingThread("mme_worker");
  // Where the time between two updates goes, on the worker's own clock: reported in ~stats for
  // the longest gap, and in a warning for every gap over kSlowGapS.
  constexpr double kSlowGapS = 0.5;
  ThreadTimes gap_start_times = callingThreadTimes();
  double gap_start_s = steadyNowS(), in_update_s = 0.0;
  while (!stop_ && ros::ok()) {
    bool updated = false;
    const double update_start_s = steadyNowS();
    try {
      updated = estimator_->update();
    } catch (const std::exception& e) {
      ROS_ERROR_THROTTLE(5.0, "estimator_node: update failed: %s", e.what());
    }
    const double now_s = steadyNowS();
    in_update_s += now_s - update_start_s;
    if (updated) {
      const ThreadTimes times = callingThreadTimes();
      UpdateGapBreakdown where;
      where.in_update_s = in_update_s;
      where.on_cpu_s = times.on_cpu_s - gap_start_times.on_cpu_s;
      where.waiting_s = times.waiting_s - gap_start_times.waiting_s;
      where.known = times.waiting_known;
      update_stats_.onUpdate(now_s, where);
      const double gap_s = now_s - gap_start_s;
      if (gap_s > kSlowGapS && update_stats_.updates() > 1)
        ROS_WARN("estimator_node: %.3f s between estimate updates: %.3f s in update() (the last "
                 "one %.3f s), the worker %.3f s on a core and %.3f s waiting for one%s",
                 gap_s, in_update_s, now_s - update_start_s, where.on_cpu_s, where.waiting_s,
                 where.known ? "" : " (not measured)");
      gap_start_times = times;
      gap_start_s = now_s;
      in_update_s = 0.0;
      if (islands_) islands_->afterUpdate();
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
}

void EstimatorNode::structureLoop() {
  startBackgroundThread("mme_structure");
  while (!stop_ && ros::ok()) {
    const Trajectory window = structure_->pending() ? estimator_->window() : Trajectory();
    if (window.numFrames() < structure_->minFrames()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      continue;
    }
    ROS_INFO("estimator_node: choosing the structure on a window of %d frames", window.numFrames());
    // The first level is put to use at once (the estimator and the muscles start on it) while
    // the later levels are judged; the final choice replaces it only when it is another structure.
    bool first_in_use = false;
    const auto first_level = [this, &first_in_use](const Model& model, const std::string& level) {
      first_in_use = useStructure(model);
      if (first_in_use)
        ROS_INFO("estimator_node: structure '%s' in use while the selection judges the later levels",
                 level.c_str());
    };
    const std::optional<StructureResult> r = structure_->runIfDue(window, first_level);
    if (!r) {
      if (structure_->state() == StructureJob::State::kFailed)
        ROS_ERROR("estimator_node: structure selection failed: %s (the next ~reset tries again)",
                  structure_->lastError().c_str());
      continue;
    }
    ROS_INFO("estimator_node: structure chosen:\n%s", formatStructureReport(*r).c_str());
    try {
      writeFileAtomically(structure_report_target_, structureReportCsv(*r));
    } catch (const std::exception& e) {
      ROS_ERROR("estimator_node: the structure report could not be written: %s", e.what());
    }
    if (first_in_use && StructureJob::choseFirstLevel(*r)) {
      ROS_INFO("estimator_node: the chosen structure is the one in use since its first level");
      continue;
    }
    useStructure(r->model);
  }
}

bool EstimatorNode::useStructure(const Model& model) {
  try {
    std::lock_guard<std::mutex> lock(input_mutex_);
    estimator_->replaceModel(model);  // same particles: the window stays
    if (muscles_) muscles_->forget();  // fitted on the old structure
  } catch (const std::exception& e) {
    ROS_ERROR("estimator_node: the chosen structure was refused: %s", e.what());
    return false;
  }
  last_published_generation_ = 0;
  structure_in_use_ = true;
  return true;
}

namespace {
/// Generations of the passive search before the muscles are fitted on its values.
constexpr uint32_t kMuscleMinGenerations = 20;
}  // namespace

void EstimatorNode::muscleLoop() {
  startBackgroundThread("mme_muscles");
  while (!stop_ && ros::ok()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    if (structure_ && !structure_in_use_) continue;
    const Estimate e = estimator_->estimate();
    if (!e.valid) continue;
    const Model passive = estimator_->currentModel();
    const Trajectory window = estimator_->window();
    if (window.numMarkers() != static_cast<int>(passive.particles.size())) continue;
    const double now_s = steadyNowS();
    if (muscles_->state() == MuscleJob::State::kFitted) {
      muscles_->refitIfDue(passive, window, now_s);
      continue;
    }
    if (e.generation < kMuscleMinGenerations) continue;
    const MuscleJob::State before = muscles_->state();
    if (muscles_->fitIfDue(passive, window, now_s)) {
      ROS_INFO("estimator_node: sensor muscles added in %.1f s: %s", muscles_->lastFitS(),
               muscles_->lastMessage().c_str());
    } else if (muscles_->state() != before && (muscles_->state() == MuscleJob::State::kNotKept ||
                                                muscles_->state() == MuscleJob::State::kFailed)) {
      ROS_WARN("estimator_node: no sensor muscles (%s); tried again on a later window",
               muscles_->lastMessage().c_str());
    }
  }
}

Model EstimatorNode::shownModel(Trajectory* window) const {
  Model model = estimator_->currentModel();
  if (window) *window = estimator_->window();
  if (!muscles_) return model;
  std::optional<Model> with = muscles_->withMuscles(model);
  if (!with) return model;
  if (window) *window = MuscleJob::asModelParticles(*window, *with);
  return std::move(*with);
}

void EstimatorNode::bagLoop() {
  nameCallingThread("mme_bag");
  Trajectory bag;
  try {
    // A capture file is replayed as its bag would be (convert's): same frames, times and gaps.
    const std::string extension = fileExtension(options_.bag);
    if (extension == ".trc" || extension == ".c3d") {
      std::vector<std::string> warnings;
      bag = readTrajectoryFile(options_.bag, &warnings);
      for (const std::string& warning : warnings)
        ROS_WARN("estimator_node: %s: %s", options_.bag.c_str(), warning.c_str());
    } else {
      bag = readBag(options_.bag, options_.bag_topic);
    }
  } catch (const InputError& e) {
    ROS_FATAL("estimator_node: ~bag: %s", e.what());
    ros::shutdown();
    return;
  }
  ROS_INFO("estimator_node: replaying %d frames of %s", bag.numFrames(), options_.bag.c_str());
  const int n = bag.numMarkers();
  const ReplayPacing pacing(options_.bag_rate, bag.times_s[0], options_.estimator.min_frames);
  const auto wall_start = std::chrono::steady_clock::now();
  for (int t = 0; t < bag.numFrames() && !stop_ && ros::ok(); ++t) {
    if (const std::optional<double> due_s = pacing.dueAfterS(bag.times_s[t]))
      std::this_thread::sleep_until(wall_start + std::chrono::duration<double>(*due_s));
    std::vector<Eigen::Vector3d> x(bag.positions_m.begin() + t * n,
                                   bag.positions_m.begin() + (t + 1) * n);
    std::vector<uint8_t> occ(bag.occluded.begin() + t * n, bag.occluded.begin() + (t + 1) * n);
    ros::Time stamp;
    stamp.fromSec(bag.times_s[t]);
    const uint64_t before = update_stats_.updates();
    addObservation(stamp, "", bag.marker_names, std::move(x), std::move(occ),
                   std::chrono::steady_clock::now());
    if (!pacing.waitsForUpdate(t + 1)) continue;
    while (update_stats_.updates() == before && !stop_ && ros::ok() &&
           !ReplayPacing::structureReleases(structure_.get(), t + 1))
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  ROS_INFO("estimator_node: bag replay finished; identification goes on on the last window");
}

void EstimatorNode::onPublishTimer(const ros::WallTimerEvent&) {
  const Estimate e = estimator_->estimate();
  if (!e.valid) return;
  if (e.generation != last_published_generation_) {
    last_published_generation_ = e.generation;
    estimate_pub_.publish(toModelEstimateMsg(e, fixed_frame_, ros::Time::now()));
  }
  if (options_.publish_markers) {
    {
      std::lock_guard<std::mutex> lock(markers_mutex_);
      markers_estimate_changed_ = true;
    }
    markers_cv_.notify_one();
  }
}

void EstimatorNode::markersLoop() {
  startBackgroundThread("mme_markers");
  while (!stop_ && ros::ok()) {
    uint64_t seq = 0;
    bool new_frame = false;
    std::chrono::steady_clock::time_point arrival;
    {
      std::unique_lock<std::mutex> lock(markers_mutex_);
      markers_cv_.wait_for(lock, std::chrono::milliseconds(100), [this] {
        return stop_ || frames_accepted_seq_ != frames_rendered_seq_ || markers_estimate_changed_;
      });
      if (stop_) break;
      new_frame = frames_accepted_seq_ != frames_rendered_seq_;
      if (!new_frame && !markers_estimate_changed_) continue;
      seq = frames_accepted_seq_;
      arrival = newest_arrival_;
      frames_rendered_seq_ = seq;
      markers_estimate_changed_ = false;
    }
    if (!options_.publish_markers || markers_pub_.getNumSubscribers() == 0) continue;
    const Estimate e = estimator_->estimate();
    if (!e.valid) continue;
    if (!publishMarkers(e)) continue;
    if (!new_frame) continue;
    latency_stats_.add(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - arrival)
            .count());
  }
}

bool EstimatorNode::publishMarkers(const Estimate& e) {
  Trajectory window;
  const Model model = shownModel(&window);
  const std::optional<VisualisationSnapshot> snapshot =
      makeVisualisationSnapshot(model, window, e, options_.color_bonds_by);
  if (!snapshot) return false;
  VisualisationSnapshot scene = *snapshot;
  if (predictions_) {  // the model against the guesses, 10 frames ahead on the window
    const std::optional<PredictionReport> report = predictions_->report();
    const std::string caption =
        report ? predictionCaption(*report, 10, muscles_ ? muscles_->muscles() : 0) : std::string();
    if (!caption.empty()) scene.text += "\n" + caption;
  }
  markers_pub_.publish(buildMarkers(scene, marker_style_));
  return true;
}

bool EstimatorNode::onReset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  estimator_->reset(false);
  last_published_generation_ = 0;
  res.success = true;
  res.message = options_.estimator.estimate_values
                    ? "population cleared; identification restarts on the current window"
                    : "nothing to identify (~estimate_values is false): the model is shown as it is";
  if (structure_) {
    structure_in_use_ = false;  // the muscles wait for the new selection's first level
    structure_->request();
    res.message += "; the structure is chosen again on the next full window";
  }
  return true;
}

std::string EstimatorNode::exportYaml(const Estimate& e) const {
  Model model = shownModel();  // with the sensor muscles when they are kept
  // currentModel() fills in the estimate of its own moment and the worker may have moved on
  // since `e` was taken: write e's values, so that values, generation, cost and std agree.
  const std::vector<ParamRef> refs = freeParameters(model);
  bool same_parameters = e.valid && refs.size() == e.values.size();
  for (size_t k = 0; same_parameters && k < refs.size(); ++k)
    same_parameters = refs[k].name == e.parameter_names[k];
  if (same_parameters) setValues(model, refs, e.values);
  const IdentificationInfo info = identificationInfo(e);
  return modelToYaml(model, same_parameters ? &info : nullptr);
}

void EstimatorNode::onAutosaveTimer(const ros::WallTimerEvent&) {
  const Estimate e = estimator_->estimate();
  if (!e.valid) return;
  try {
    writeFileAtomically(autosave_target_, exportYaml(e));  // temp file + rename: never torn
  } catch (const std::exception& ex) {
    ROS_ERROR_THROTTLE(30.0, "estimator_node: autosave failed: %s", ex.what());
  }
}

bool EstimatorNode::onExport(motion_model_estimation::ExportModel::Request& req,
                             motion_model_estimation::ExportModel::Response& res) {
  try {
    res.yaml = exportYaml(estimator_->estimate());
    if (!req.path.empty()) {
      std::string error;
      const std::string target = confinePath(options_.model_dir, req.path, true, &error);
      if (target.empty()) throw InputError("export refused: " + error);
      writeFileAtomically(target, res.yaml);
      res.message = "model written to " + target;
    } else {
      res.message = "model returned";
    }
    res.success = true;
  } catch (const std::exception& ex) {
    res.success = false;
    res.message = ex.what();
  }
  return true;  // domain errors travel in the response, the call itself succeeds
}

bool EstimatorNode::onLoad(motion_model_estimation::LoadModel::Request& req,
                           motion_model_estimation::LoadModel::Response& res) {
  try {
    std::string error;
    const std::string source = confinePath(options_.model_dir, req.path, false, &error);
    if (source.empty()) throw InputError("load refused: " + error);
    const Model model = loadModelFile(source);
    {
      std::lock_guard<std::mutex> lock(input_mutex_);
      const std::vector<std::string> particles_before = estimator_->particleNames();
      estimator_->replaceModel(model);
      const std::vector<std::string> particles = estimator_->particleNames();
      if (particles != particles_before) clock_jumps_.forgetWindow();  // the window was emptied
      names_.setParticles(particles);
      if (muscles_) muscles_->forget();
    }
    last_published_generation_ = 0;
    res.success = true;
    res.message = "model loaded from " + req.path;
  } catch (const std::exception& ex) {
    res.success = false;
    res.message = ex.what();
  }
  return true;
}

void EstimatorNode::run() {
  ros::AsyncSpinner spinner(2);  // callbacks and services never wait for identification
  spinner.start();
  worker_ = std::thread(&EstimatorNode::workerLoop, this);
  markers_thread_ = std::thread(&EstimatorNode::markersLoop, this);
  if (!options_.bag.empty()) bag_thread_ = std::thread(&EstimatorNode::bagLoop, this);
  if (structure_) structure_thread_ = std::thread(&EstimatorNode::structureLoop, this);
  if (muscles_) muscle_thread_ = std::thread(&EstimatorNode::muscleLoop, this);
  ros::waitForShutdown();
  stop_ = true;
  if (muscles_) muscles_->cancel();
  markers_cv_.notify_all();
  worker_.join();
  markers_thread_.join();
  if (bag_thread_.joinable()) bag_thread_.join();
  if (structure_thread_.joinable()) structure_thread_.join();
  if (muscle_thread_.joinable()) muscle_thread_.join();
  spinner.stop();
}

}  // namespace mme
