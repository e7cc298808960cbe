// How the node replays a recording (live/replay_pacing.h): frames due at their stamp over the
// rate, or fed as fast as the estimator keeps up, waiting for its update except while a
// structure selection holds the window open or has failed.
#include <gtest/gtest.h>

#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/live/replay_pacing.h"
#include "motion_model_estimation/scenes/random_object.h"
#include "test_helpers.h"

namespace {

TEST(ReplayPacing, AtARateFramesAreDueAtTheirStampOverTheRate) {
  const mme::ReplayPacing twice(2.0, 10.0, 5);
  ASSERT_TRUE(twice.dueAfterS(10.0).has_value());
  EXPECT_DOUBLE_EQ(*twice.dueAfterS(10.0), 0.0);
  EXPECT_DOUBLE_EQ(*twice.dueAfterS(13.0), 1.5);
  // Following the clock, the replay never waits for the estimator.
  EXPECT_FALSE(twice.waitsForUpdate(100));
}

TEST(ReplayPacing, AsFastAsPossibleWaitsForAnUpdateOnceAWindowIsThere) {
  const mme::ReplayPacing fast(0.0, 0.0, 5);
  EXPECT_FALSE(fast.dueAfterS(3.0).has_value());
  EXPECT_FALSE(fast.waitsForUpdate(4));
  EXPECT_TRUE(fast.waitsForUpdate(5));
  EXPECT_FALSE(mme::ReplayPacing::structureReleases(nullptr, 5));
}

TEST(ReplayPacing, AStructureJobHoldsTheWindowOpenUntilItIsFullAndReleasesOnFailure) {
  mme::PipelineOptions options;
  options.identify.es.threads = 1;
  options.identify.generations = 20;
  // Pending on a window too short for it: frames go on until it is full.
  mme::StructureJob pending(mme::Model(), options, 40);
  EXPECT_TRUE(mme::ReplayPacing::structureReleases(&pending, 39));
  EXPECT_FALSE(mme::ReplayPacing::structureReleases(&pending, 40));
  // Not requested: the replay waits for updates as without a job.
  mme::StructureJob idle(mme::Model(), options, 40, false);
  EXPECT_FALSE(mme::ReplayPacing::structureReleases(&idle, 10));
  // A selection that failed (a model without particles): frames go on.
  mme::RandomObjectSpec spec;
  spec.particles = 6;
  spec.bond_types = 2;
  spec.bonds = 8;
  const mme::Model truth = mme::makeRandomObject(spec);
  const mme::Trajectory data = mme::simulateTrajectory(truth, 40, truth.frame_rate_hz);
  ASSERT_FALSE(pending.runIfDue(data).has_value());
  ASSERT_EQ(pending.state(), mme::StructureJob::State::kFailed) << pending.status();
  EXPECT_TRUE(mme::ReplayPacing::structureReleases(&pending, 40));
}

}  // namespace
