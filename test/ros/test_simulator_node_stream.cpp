// rostest: simulator_node streams a built-in scene as MarkerFrame; checks what arrives.
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <cmath>
#include <mutex>
#include <vector>

#include "motion_model_estimation/MarkerFrame.h"
#include "master_check.h"

namespace {

std::mutex g_mutex;
std::vector<motion_model_estimation::MarkerFrame> g_frames;

void onFrame(const motion_model_estimation::MarkerFrame::ConstPtr& msg) {
  std::lock_guard<std::mutex> lock(g_mutex);
  g_frames.push_back(*msg);
}

TEST(SimulatorNode, StreamsTheSceneAsMovingMarkerFrames) {
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  int expected_markers = 0, wanted_frames = 0;
  ASSERT_TRUE(pnh.getParam("expected_markers", expected_markers));
  ASSERT_TRUE(pnh.getParam("wanted_frames", wanted_frames));
  ros::Subscriber sub = nh.subscribe("markers", 1000, onFrame);
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(30.0);
  while (ros::ok() && ros::WallTime::now() < deadline) {
    ros::spinOnce();
    {
      std::lock_guard<std::mutex> lock(g_mutex);
      if (static_cast<int>(g_frames.size()) >= wanted_frames) break;
    }
    ros::WallDuration(0.005).sleep();
  }
  std::lock_guard<std::mutex> lock(g_mutex);
  ASSERT_GE(static_cast<int>(g_frames.size()), wanted_frames);
  double max_motion_m = 0.0;
  for (size_t f = 0; f < g_frames.size(); ++f) {
    const auto& m = g_frames[f];
    ASSERT_EQ(static_cast<int>(m.names.size()), expected_markers);
    ASSERT_EQ(m.positions.size(), m.names.size());
    EXPECT_TRUE(m.occluded.empty());
    EXPECT_EQ(m.header.frame_id, "world");
    if (f > 0) {
      // Late joiners may miss the first frames, but numbering is consecutive after that.
      EXPECT_EQ(m.frame_number, g_frames[f - 1].frame_number + 1);
      EXPECT_GE(m.header.stamp, g_frames[f - 1].header.stamp);
    }
    for (size_t i = 0; i < m.positions.size(); ++i) {
      ASSERT_TRUE(std::isfinite(m.positions[i].x) && std::isfinite(m.positions[i].y) &&
                  std::isfinite(m.positions[i].z));
      const auto& p0 = g_frames[0].positions[i];
      max_motion_m = std::max(max_motion_m, std::hypot(m.positions[i].x - p0.x,
                                                       m.positions[i].y - p0.y,
                                                       m.positions[i].z - p0.z));
    }
  }
  EXPECT_GT(max_motion_m, 1e-4) << "the scene should move";
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_simulator_node_stream");
  if (!mmetest::masterAnswers()) return 2;
  return RUN_ALL_TESTS();
}
