// The island model between estimator_nodes on one master (launch/islands.launch on the test bag),
// judged from the islands' ~stats lines and /rosout:
//   mode exchange:     both islands send migrants and receive the other's, none refused, some
//                      accepted;
//   mode incompatible: islands with different model files refuse each other's migrants, with
//                      the warning naming the first differing parameter (param expected_warning);
//   mode kill:         after the exchange, island 2 is killed; island 1 keeps updating and
//                      emigrating, and receives nothing more (it ignores its own migrants). Its
//                      update rate with the live and the dead peer is printed.
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>

#include <cstdio>
#include <cstdlib>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "master_check.h"
#include "test_estimator_common.h"

namespace {

using mmetest::parseStatsLine;
using mmetest::StatsWatcher;
using Fields = std::map<std::string, double>;

double field(const Fields& f, const std::string& key) {
  const auto it = f.find(key);
  return it == f.end() ? -1.0 : it->second;
}

/// The warnings of /rosout that contain `text` (thread-safe).
class RosoutWatcher {
 public:
  RosoutWatcher(ros::NodeHandle& nh, std::string text) : text_(std::move(text)) {
    sub_ = nh.subscribe<rosgraph_msgs::Log>("/rosout", 100, [this](const rosgraph_msgs::Log::ConstPtr& m) {
      if (m->level < rosgraph_msgs::Log::WARN || m->msg.find(text_) == std::string::npos) return;
      std::lock_guard<std::mutex> lock(mutex_);
      lines_.push_back(m->name + ": " + m->msg);
    });
  }
  std::vector<std::string> lines() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return lines_;
  }

 private:
  std::string text_;
  ros::Subscriber sub_;
  mutable std::mutex mutex_;
  std::vector<std::string> lines_;
};

struct Islands {
  ros::NodeHandle nh, pnh{"~"};
  StatsWatcher one{nh, "/island_1/estimator/stats"};
  StatsWatcher two{nh, "/island_2/estimator/stats"};
  double timeout_s = pnh.param("timeout_s", 60.0);
};

bool exchanged(const std::string& line) {
  const Fields f = parseStatsLine(line);
  return field(f, "migrants_sent") > 0 && field(f, "migrants_received") > 0;
}

TEST(EstimatorIslands, Exchange) {
  Islands s;
  ASSERT_TRUE(s.one.waitFor(exchanged, s.timeout_s)) << "island 1: " << s.one.line();
  ASSERT_TRUE(s.two.waitFor(exchanged, 10.0)) << "island 2: " << s.two.line();
  const auto accepted = [](const std::string& line) {
    return field(parseStatsLine(line), "migrants_accepted") > 0;
  };
  EXPECT_TRUE(s.one.waitFor(accepted, 20.0) || s.two.waitFor(accepted, 1.0))
      << "no migrant entered either population:\n" << s.one.line() << "\n" << s.two.line();
  for (const StatsWatcher* w : {&s.one, &s.two}) {
    const Fields f = parseStatsLine(w->line());
    EXPECT_EQ(field(f, "migrants_refused"), 0.0) << w->line();
    EXPECT_GT(field(f, "migrant_batches_from_peers"), 0.0) << w->line();
    std::printf("island stats: %s\n", w->line().c_str());
  }
}

TEST(EstimatorIslands, Incompatible) {
  Islands s;
  const std::string expected = s.pnh.param("expected_warning", std::string());
  RosoutWatcher warnings(s.nh, "refused");
  const auto refused = [](const std::string& line) {
    return field(parseStatsLine(line), "migrants_refused") > 0;
  };
  ASSERT_TRUE(s.one.waitFor(refused, s.timeout_s)) << "island 1: " << s.one.line();
  ASSERT_TRUE(s.two.waitFor(refused, 10.0)) << "island 2: " << s.two.line();
  for (const StatsWatcher* w : {&s.one, &s.two}) {
    const Fields f = parseStatsLine(w->line());
    EXPECT_EQ(field(f, "migrants_received"), 0.0) << w->line();
    EXPECT_EQ(field(f, "migrants_accepted"), 0.0) << w->line();
    EXPECT_GT(field(f, "migrants_sent"), 0.0) << w->line();
  }
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(10.0);
  bool named = false;
  while (!named && ros::WallTime::now() < deadline) {
    for (const std::string& line : warnings.lines()) named = named || line.find(expected) != std::string::npos;
    ros::WallDuration(0.1).sleep();
  }
  std::string seen;
  for (const std::string& line : warnings.lines()) seen += line + "\n";
  EXPECT_TRUE(named) << "no warning naming '" << expected << "'; seen:\n" << seen;
  std::printf("warnings:\n%s", seen.c_str());
}

/// Updates per second of an island over `seconds`, from its ~stats "updates" field.
double updateRate(const StatsWatcher& w, double seconds) {
  const double before = field(parseStatsLine(w.line()), "updates");
  const ros::WallTime start = ros::WallTime::now();
  ros::WallDuration(seconds).sleep();
  const double after = field(parseStatsLine(w.line()), "updates");
  return (after - before) / (ros::WallTime::now() - start).toSec();
}

TEST(EstimatorIslands, KillOne) {
  Islands s;
  ASSERT_TRUE(s.one.waitFor(exchanged, s.timeout_s)) << "island 1: " << s.one.line();
  ASSERT_TRUE(s.two.waitFor(exchanged, 10.0)) << "island 2: " << s.two.line();
  const double rate_with_peer = updateRate(s.one, 5.0);
  ASSERT_EQ(std::system("rosnode kill /island_2/estimator"), 0);
  ros::WallDuration(2.0).sleep();  // batches already on their way arrive
  const Fields at_kill = parseStatsLine(s.one.line());
  const double rate_dead_peer = updateRate(s.one, 5.0);
  ros::WallDuration(3.0).sleep();
  const Fields later = parseStatsLine(s.one.line());
  std::printf("island 1 updates/s: %.2f with a live peer, %.2f after the peer was killed\n",
              rate_with_peer, rate_dead_peer);
  EXPECT_GT(field(later, "updates"), field(at_kill, "updates")) << s.one.line();
  EXPECT_GT(field(later, "migrants_sent"), field(at_kill, "migrants_sent")) << s.one.line();
  // Still emigrating, never receiving: its own migrants come back on the topic and are ignored.
  EXPECT_EQ(field(later, "migrant_batches_from_peers"), field(at_kill, "migrant_batches_from_peers"))
      << s.one.line();
}

}  // namespace

int main(int argc, char** argv) { return mmetest::runRosTests(argc, argv, "test_estimator_islands"); }
