// rostest: estimator_node identifies a built-in scene and converges to its true parameters.
// The input comes from elsewhere in the launch (simulator_node, a bag: ~input external) or is
// published by this node from the scene's simulated motion in one of the node's input forms:
//   markers     MarkerFrame in the model frame ("world")
//   pointcloud  sensor_msgs/PointCloud2, float32 x/y/z in particle order
//   vicon       vicon_bridge/Markers (ShapeShifter, millimetres)
//   mocap       MarkerFrame in frame "mocap", with a static tf2 transform mocap -> world
//               broadcast by this node (positions expressed in mocap)
// Pass: `consecutive` successive ~estimate messages computed on a full window
// (`expected_window_frames`) with every free parameter within `tolerance` (relative) of the
// truth, within `timeout_s` of wall time. And the node's ~markers "observed" particles (the
// newest frame of its window, in "world") are the scene's world positions of one frame of its
// motion within 1e-5 m: the input was converted (units, order, frame), not only consistent.
// (paper_object has no gravity, so its spring forces are invariant under a rigid transform:
// without this check an ignored tf2 transform would still converge to the truth.)
// With ~check_predictions: once converged, ~stats carries the model's prediction figures on the
// window (predict<K>_<P>_mm) and the identified model predicts 10 frames ahead at least twice as
// well as the constant-velocity guess, its rollout bounded.
#include <geometry_msgs/TransformStamped.h>
#include <std_msgs/String.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <visualization_msgs/MarkerArray.h>

#include <atomic>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

#include "test_estimator_common.h"
#include "master_check.h"

namespace {

using namespace mmetest;

/// The pose of the "mocap" frame in "world": a rotation about a skew axis and an offset, so
/// every coordinate changes.
Eigen::Isometry3d mocapInWorld() {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translate(Eigen::Vector3d(1.5, -0.7, 0.4));
  pose.rotate(Eigen::AngleAxisd(0.9, Eigen::Vector3d(0.3, -0.5, 0.8).normalized()));
  return pose;
}

class Streamer {
 public:
  Streamer(ros::NodeHandle& nh, const std::string& scene, const std::string& input,
           double rate_hz)
      : stream_(scene), input_(input), rate_hz_(rate_hz) {
    if (input_ == "markers" || input_ == "mocap")
      markers_pub_ = nh.advertise<MarkerFrame>("markers", 200);
    else if (input_ == "pointcloud")
      cloud_pub_ = nh.advertise<sensor_msgs::PointCloud2>("markers", 200);
    else if (input_ == "vicon")
      vicon_pub_ = std::make_unique<ViconPublisher>(nh, "markers");
    if (input_ == "mocap") {
      const Eigen::Isometry3d pose = mocapInWorld();
      geometry_msgs::TransformStamped tf;
      tf.header.stamp = ros::Time::now();
      tf.header.frame_id = "world";
      tf.child_frame_id = "mocap";
      tf.transform.translation.x = pose.translation().x();
      tf.transform.translation.y = pose.translation().y();
      tf.transform.translation.z = pose.translation().z();
      const Eigen::Quaterniond q(pose.rotation());
      tf.transform.rotation.x = q.x();
      tf.transform.rotation.y = q.y();
      tf.transform.rotation.z = q.z();
      tf.transform.rotation.w = q.w();
      broadcaster_.sendTransform(tf);
    }
  }
  ~Streamer() { stop(); }

  bool waitForEstimator(double timeout_s) const {
    if (markers_pub_) return waitForSubscriber(markers_pub_, timeout_s);
    if (cloud_pub_) return waitForSubscriber(cloud_pub_, timeout_s);
    return waitForSubscriber(*vicon_pub_, timeout_s);
  }
  void start() {
    thread_ = std::thread([this] { loop(); });
  }
  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  uint32_t published() const { return published_; }

 private:
  void loop() {
    const ros::Time t0 = ros::Time::now();
    const Eigen::Isometry3d world_to_mocap = mocapInWorld().inverse();
    ros::WallRate rate(rate_hz_);
    for (uint32_t k = 0; !stop_ && ros::ok(); ++k) {
      // Capture time at the scene's own frame rate, whatever the publishing pace.
      const ros::Time stamp = t0 + ros::Duration(k / stream_.frameRateHz());
      std::vector<Eigen::Vector3d> x = stream_.positions();
      if (input_ == "markers") {
        markers_pub_.publish(makeMarkerFrame(stream_.names(), x, k, stamp, "world"));
      } else if (input_ == "mocap") {
        for (Eigen::Vector3d& p : x) p = world_to_mocap * p;
        markers_pub_.publish(makeMarkerFrame(stream_.names(), x, k, stamp, "mocap"));
      } else if (input_ == "pointcloud") {
        cloud_pub_.publish(makePointCloud(x, stamp, "world"));
      } else {
        vicon_pub_->publish(stream_.names(), x, k, stamp, "world");
      }
      ++published_;
      stream_.next();
      rate.sleep();
    }
  }

  SceneStream stream_;
  std::string input_;
  double rate_hz_;
  ros::Publisher markers_pub_, cloud_pub_;
  std::unique_ptr<ViconPublisher> vicon_pub_;
  tf2_ros::StaticTransformBroadcaster broadcaster_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<uint32_t> published_{0};
};

std::mutex g_observed_mutex;
std::vector<geometry_msgs::Point> g_observed;  // newest ~markers "observed" points
std::string g_observed_frame;

void onMarkerArray(const visualization_msgs::MarkerArray::ConstPtr& msg) {
  for (const visualization_msgs::Marker& m : msg->markers)
    if (m.ns == "observed" && m.id == 0) {
      std::lock_guard<std::mutex> lock(g_observed_mutex);
      g_observed = m.points;
      g_observed_frame = m.header.frame_id;
    }
}

/// Index of the frame of `frames` (world positions per frame) that `points` are, within
/// `tolerance_m` for every particle; -1 when none.
long matchingFrame(const std::vector<std::vector<Eigen::Vector3d>>& frames,
                   const std::vector<geometry_msgs::Point>& points, double tolerance_m) {
  for (size_t f = 0; f < frames.size(); ++f) {
    if (frames[f].size() != points.size()) continue;
    bool same = true;
    for (size_t i = 0; same && i < points.size(); ++i)
      same = (frames[f][i] - Eigen::Vector3d(points[i].x, points[i].y, points[i].z)).norm() <=
             tolerance_m;
    if (same) return static_cast<long>(f);
  }
  return -1;
}

std::mutex g_stats_mutex;
std::map<std::string, double> g_stats;  // the last ~stats line, field by field

void onStats(const std_msgs::String::ConstPtr& msg) {
  std::map<std::string, double> fields = parseStatsLine(msg->data);
  std::lock_guard<std::mutex> lock(g_stats_mutex);
  g_stats = std::move(fields);
}

TEST(EstimatorNode, ConvergesToTheTruth) {
  ros::NodeHandle nh, pnh("~");
  std::string scene = "paper_object", input = "external", topic = "estimator/estimate";
  double tolerance = 0.01, timeout_s = 25.0, rate_hz = 200.0;
  int consecutive = 3, expected_window_frames = 0;
  bool check_predictions = false;
  pnh.getParam("scene", scene);
  pnh.getParam("input", input);
  pnh.getParam("estimate_topic", topic);
  pnh.getParam("tolerance", tolerance);
  pnh.getParam("timeout_s", timeout_s);
  pnh.getParam("publish_rate_hz", rate_hz);
  pnh.getParam("consecutive", consecutive);
  pnh.getParam("expected_window_frames", expected_window_frames);
  pnh.getParam("check_predictions", check_predictions);
  ASSERT_TRUE(input == "external" || input == "markers" || input == "pointcloud" ||
              input == "vicon" || input == "mocap")
      << "~input " << input;

  const Truth truth = sceneTruth(scene);
  ASSERT_FALSE(truth.names.empty());
  EstimateRecorder recorder(nh, topic);
  const std::string markers_topic = topic.substr(0, topic.rfind('/') + 1) + "markers";
  ros::Subscriber markers_sub = nh.subscribe(markers_topic, 5, onMarkerArray);
  ros::Subscriber stats_sub =
      nh.subscribe(topic.substr(0, topic.rfind('/') + 1) + "stats", 5, onStats);
  const ros::WallTime start = ros::WallTime::now();
  std::unique_ptr<Streamer> streamer;
  if (input != "external") {
    streamer = std::make_unique<Streamer>(nh, scene, input, rate_hz);
    ASSERT_TRUE(streamer->waitForEstimator(10.0)) << "estimator_node did not subscribe";
    streamer->start();
  }
  std::string report = "no estimate";
  const long first = waitForConvergence(recorder, truth, tolerance, timeout_s, consecutive,
                                        &report, 0, static_cast<uint32_t>(expected_window_frames));
  const double elapsed_s = (ros::WallTime::now() - start).toSec();
  // The observed particles of ~markers are world positions of a frame of the scene's motion.
  std::vector<std::vector<Eigen::Vector3d>> world_frames;
  {
    SceneStream motion(scene);
    const uint32_t frames = std::max<uint32_t>(
        2000, 2 * (streamer ? streamer->published() : 0) +
                  static_cast<uint32_t>(2.0 * motion.frameRateHz() * elapsed_s));
    for (uint32_t f = 0; f < frames; ++f, motion.next()) world_frames.push_back(motion.positions());
  }
  long observed_frame = -1;
  std::string observed_frame_id;
  std::vector<geometry_msgs::Point> observed;
  const ros::WallTime markers_deadline = ros::WallTime::now() + ros::WallDuration(5.0);
  while (ros::ok() && ros::WallTime::now() < markers_deadline && observed_frame < 0) {
    {
      std::lock_guard<std::mutex> lock(g_observed_mutex);
      observed = g_observed;
      observed_frame_id = g_observed_frame;
    }
    observed_frame = matchingFrame(world_frames, observed, 1e-5);
    if (observed_frame < 0) ros::WallDuration(0.05).sleep();
  }
  if (streamer) streamer->stop();
  EXPECT_GE(observed_frame, 0) << "~markers observed particles (" << observed.size()
                               << " points) are not the world positions of any frame of the "
                               << "scene's first " << world_frames.size() << " frames";
  EXPECT_EQ(observed_frame_id, "world");
  std::printf("[ INFO     ] input %s: %s after %.1f s (%u frames published by the test); "
              "~markers observed = scene frame %ld\n",
              input.c_str(), first >= 0 ? "converged" : "NOT converged", elapsed_s,
              streamer ? streamer->published() : 0u, observed_frame);
  ASSERT_GE(first, 0) << "within " << timeout_s << " s, " << report << "; tolerance "
                      << 100.0 * tolerance << " %";

  const std::vector<EstimateRecorder::Entry> converged = recorder.since(first);
  const ModelEstimate& e = converged.front().msg;
  // The estimate is complete and consistent, not only close.
  ASSERT_EQ(e.parameter_names.size(), truth.names.size());
  EXPECT_EQ(std::set<std::string>(e.parameter_names.begin(), e.parameter_names.end()),
            std::set<std::string>(truth.names.begin(), truth.names.end()));
  ASSERT_EQ(e.values.size(), e.parameter_names.size());
  ASSERT_EQ(e.std_devs.size(), e.parameter_names.size());
  for (size_t k = 0; k < e.values.size(); ++k) {
    EXPECT_NEAR(e.values[k], truth.at(e.parameter_names[k]),
                tolerance * std::fabs(truth.at(e.parameter_names[k])))
        << e.parameter_names[k];
    EXPECT_TRUE(std::isfinite(e.std_devs[k]) && e.std_devs[k] >= 0.0) << e.parameter_names[k];
  }
  EXPECT_TRUE(std::isfinite(e.global_cost) && e.global_cost >= 0.0);
  EXPECT_GT(e.generation, 0u);
  EXPECT_GT(e.evaluations, 0u);
  EXPECT_TRUE(e.stable) << "the true model's long rollout is bounded";
  EXPECT_EQ(e.header.frame_id, "world");
  if (expected_window_frames > 0) {
    EXPECT_EQ(static_cast<int>(e.window_frames), expected_window_frames);
  }
  for (size_t k = 1; k < converged.size(); ++k) {  // no reset happened: generations only grow
    EXPECT_GT(converged[k].msg.generation, converged[k - 1].msg.generation);
  }
  if (!check_predictions) return;
  // The prediction figures are recomputed every ~prediction_period_sec (5 s): within 15 s of
  // convergence one is made with the converged model.
  std::map<std::string, double> s;
  const ros::WallTime stats_deadline = ros::WallTime::now() + ros::WallDuration(15.0);
  bool good = false;
  while (ros::ok() && ros::WallTime::now() < stats_deadline && !good) {
    {
      std::lock_guard<std::mutex> lock(g_stats_mutex);
      s = g_stats;
    }
    good = s.count("predict10_model_mm") && s.count("predict10_constant_velocity_mm") &&
           s["predict10_model_mm"] < 0.5 * s["predict10_constant_velocity_mm"] &&
           s["rollout_bounded"] == 1.0;
    if (!good) ros::WallDuration(0.1).sleep();
  }
  for (const char* key : {"predict1_model_mm", "predict5_model_mm", "predict10_model_mm",
                          "predict10_constant_velocity_mm", "predict10_constant_acceleration_mm",
                          "predict10_gravity_only_mm", "rollout_bounded"})
    EXPECT_EQ(s.count(key), 1u) << key;
  EXPECT_TRUE(good) << "10 frames ahead: model " << s["predict10_model_mm"]
                    << " mm, constant velocity " << s["predict10_constant_velocity_mm"]
                    << " mm, rollout_bounded " << s["rollout_bounded"];
  std::printf("[ INFO     ] ~stats predictions 10 frames ahead: model %.4f mm, constant velocity "
              "%.4f mm, constant acceleration %.4f mm\n", s["predict10_model_mm"],
              s["predict10_constant_velocity_mm"], s["predict10_constant_acceleration_mm"]);
}

}  // namespace

int main(int argc, char** argv) { return mmetest::runRosTests(argc, argv, "test_estimator_convergence"); }
