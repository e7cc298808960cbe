// Trajectory helpers: the observed samples' bounds.
#include <gtest/gtest.h>

#include "motion_model_estimation/core/trajectory.h"

namespace {

TEST(Trajectory, ObservedBoundsSkipOccludedSamples) {
  mme::Trajectory data;
  data.marker_names = {"a", "b"};
  data.frame_rate_hz = 10.0;
  data.resize(3);  // every sample occluded at (0, 0, 0)
  Eigen::Vector3d lo(7, 7, 7), hi(7, 7, 7);
  EXPECT_FALSE(mme::observedBounds(data, &lo, &hi));
  EXPECT_EQ(lo, Eigen::Vector3d(7, 7, 7));  // untouched
  data.position(0, 0) = Eigen::Vector3d(1, 2, 3);
  data.occluded[0] = 0;
  data.position(2, 1) = Eigen::Vector3d(-1, 5, 4);
  data.occluded[5] = 0;
  data.position(1, 1) = Eigen::Vector3d(100, 100, 100);  // occluded: not counted
  ASSERT_TRUE(mme::observedBounds(data, &lo, &hi));
  EXPECT_EQ(lo, Eigen::Vector3d(-1, 2, 3));
  EXPECT_EQ(hi, Eigen::Vector3d(1, 5, 4));
}

}  // namespace
