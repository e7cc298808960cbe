// rostest: estimator_node survives bad MarkerFrame input and counts it. This node publishes the
// paper_object motion as MarkerFrame, with bad frames mixed in:
//   NaN positions (3 markers)           accepted, the samples masked as occluded
//   names / positions of unequal length rejected by the node
//   occluded of another length          rejected by the node
//   unknown marker names only           rejected by the node
//   time going backwards (50 ms)        rejected by the estimator (rejected_time)
//   a duplicated frame (same message)   rejected by the estimator (rejected_time)
// Pass: the counters of ~stats match exactly what was sent (and the update-gap fields are
// there), ~estimate keeps coming afterwards and still converges to the truth (1 %): masked
// NaNs do not poison the window.
#include <cstdio>
#include <limits>
#include <map>
#include <sstream>

#include <std_msgs/String.h>
#include <visualization_msgs/MarkerArray.h>

#include "test_estimator_common.h"
#include "master_check.h"

namespace {

using namespace mmetest;

std::mutex g_stats_mutex;
std::map<std::string, double> g_stats;
std::atomic<int> g_marker_arrays{0};

void onStats(const std_msgs::String::ConstPtr& msg) {
  std::map<std::string, double> fields = parseStatsLine(msg->data);
  std::lock_guard<std::mutex> lock(g_stats_mutex);
  g_stats = std::move(fields);
}

void onMarkerArray(const visualization_msgs::MarkerArray::ConstPtr&) { ++g_marker_arrays; }

std::map<std::string, double> stats() {
  std::lock_guard<std::mutex> lock(g_stats_mutex);
  return g_stats;
}

class Feed {
 public:
  explicit Feed(ros::NodeHandle& nh) : stream_("paper_object"), t0_(ros::Time::now()) {
    pub_ = nh.advertise<MarkerFrame>("markers", 1000);
  }
  ros::Publisher& pub() { return pub_; }
  ros::Time stampOf(uint32_t k) const { return t0_ + ros::Duration(k / stream_.frameRateHz()); }
  /// The next frame of the motion, as published (advances the motion).
  MarkerFrame next() {
    MarkerFrame m = makeMarkerFrame(stream_.names(), stream_.positions(), k_, stampOf(k_), "world");
    stream_.next();
    ++k_;
    return m;
  }
  /// What the next frame would be, without advancing (for frames that are rejected).
  MarkerFrame peek() const {
    return makeMarkerFrame(stream_.names(), stream_.positions(), k_, stampOf(k_), "world");
  }
  void publish(const MarkerFrame& m) {
    pub_.publish(m);
    ros::WallDuration(0.004).sleep();  // ~250 Hz
  }
  void good(int n) {
    for (int i = 0; i < n && ros::ok(); ++i) {
      last_good_ = next();
      publish(last_good_);
      ++sent_good_;
    }
  }
  const MarkerFrame& lastGood() const { return last_good_; }
  int sentGood() const { return sent_good_; }

 private:
  SceneStream stream_;
  ros::Time t0_;
  ros::Publisher pub_;
  uint32_t k_ = 0;
  MarkerFrame last_good_;
  int sent_good_ = 0;
};

TEST(EstimatorNode, SurvivesAndCountsBadInput) {
  ros::NodeHandle nh;
  const Truth truth = sceneTruth("paper_object");
  ros::Subscriber stats_sub = nh.subscribe("estimator/stats", 10, onStats);
  // Someone watches ~markers too: the visualisation is built from windows with masked samples.
  ros::Subscriber viz_sub = nh.subscribe("estimator/markers", 10, onMarkerArray);
  EstimateRecorder recorder(nh, "estimator/estimate");
  Feed feed(nh);
  ASSERT_TRUE(waitForSubscriber(feed.pub(), 15.0)) << "estimator_node did not subscribe";

  // Warm up on good frames until estimates come.
  feed.good(120);
  ASSERT_TRUE(recorder.waitUntil([](const auto& e) { return !e.empty(); }, 10.0))
      << "no estimate from good input";

  int nan_frames = 0, nan_samples = 0, node_rejected = 0, time_rejected = 0;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int round = 0; round < 5 && ros::ok(); ++round) {
    // NaN positions: accepted, masked as occluded.
    MarkerFrame m = feed.next();
    for (int i = 0; i < 3; ++i) m.positions[(round + 4 * i) % m.positions.size()].x = nan;
    feed.publish(m);
    ++nan_frames;
    nan_samples += 3;
    feed.good(5);
    // names and positions of unequal length.
    m = feed.peek();
    m.positions.pop_back();
    feed.publish(m);
    ++node_rejected;
    // occluded of another length than positions.
    m = feed.peek();
    m.occluded.assign(3, 0);
    feed.publish(m);
    ++node_rejected;
    // unknown marker names only.
    m = feed.peek();
    for (std::string& name : m.names) name = "unknown_" + name;
    feed.publish(m);
    ++node_rejected;
    feed.good(5);
    // time going backwards (50 ms: a reordered frame, not a clock jump).
    m = feed.lastGood();
    m.header.stamp -= ros::Duration(0.05);
    feed.publish(m);
    ++time_rejected;
    // a duplicated frame.
    feed.publish(feed.lastGood());
    ++time_rejected;
    feed.good(5);
  }
  const size_t estimates_before = recorder.count();
  // The stream goes on, then stops: the last window (100 frames) still holds NaN frames, and
  // identification goes on on it.
  feed.good(40);

  // Counters: exactly what was sent (nothing lost on the way: the connection existed before).
  const long long want_accepted = feed.sentGood() + nan_frames;
  const long long want_rejected = node_rejected + time_rejected;
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(10.0);
  std::map<std::string, double> s;
  while (ros::ok() && ros::WallTime::now() < deadline) {
    s = stats();
    if (s["accepted"] == want_accepted && s["rejected"] == want_rejected) break;
    ros::WallDuration(0.05).sleep();
  }
  EXPECT_EQ(s["accepted"], want_accepted);
  EXPECT_EQ(s["rejected"], want_rejected);
  EXPECT_EQ(s["rejected_time"], time_rejected);
  EXPECT_EQ(s["rejected_size"], 0);  // unequal arrays are caught before the estimator
  EXPECT_EQ(s["occluded"], nan_samples);
  EXPECT_EQ(s["clock_jumps"], 0);
  // Estimates were updated: the gaps between updates are reported, the run's longest at least
  // the last 10 s's, and the worker never stood still for 10 s.
  EXPECT_GT(s["updates"], 0);
  ASSERT_EQ(s.count("max_update_gap_ms"), 1u);
  ASSERT_EQ(s.count("max_update_gap_10s_ms"), 1u);
  EXPECT_GE(s["max_update_gap_ms"], s["max_update_gap_10s_ms"]);
  EXPECT_LT(s["max_update_gap_ms"], 10000);
  std::printf("[ INFO     ] stats after the bad input: accepted=%.0f rejected=%.0f "
              "rejected_time=%.0f occluded=%.0f\n", s["accepted"], s["rejected"],
              s["rejected_time"], s["occluded"]);

  // Still alive: estimates keep coming and converge to the truth from the mixed window.
  std::string report = "no estimate after the bad input";
  const long converged = waitForConvergence(recorder, truth, 0.01, 25.0, 3, &report,
                                            estimates_before, 100);
  EXPECT_GE(converged, 0) << report;
  std::printf("[ INFO     ] after the bad input: %s\n", report.c_str());
  EstimateRecorder::Entry last;
  ASSERT_TRUE(recorder.last(&last));
  for (double v : last.msg.values) EXPECT_TRUE(std::isfinite(v));
  EXPECT_TRUE(std::isfinite(last.msg.global_cost));
  EXPECT_GT(g_marker_arrays.load(), 0);
}

}  // namespace

int main(int argc, char** argv) { return mmetest::runRosTests(argc, argv, "test_estimator_bad_input"); }
