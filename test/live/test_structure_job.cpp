// The live node's structure selection: it waits for a window long enough, chooses the structure
// of a random object from its particles alone, runs once per request (the first at start, then
// ~reset), hands over its first level as soon as it is judged, and a window it cannot use leaves
// it failed with the reason and no model.
#include <gtest/gtest.h>

#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/structure/marker_model.h"
#include "motion_model_estimation/io/trajectory_io.h"
#include "motion_model_estimation/live/structure_job.h"
#include "motion_model_estimation/scenes/random_object.h"
#include "test_helpers.h"

namespace {

mme::PipelineOptions quickOptions() {
  mme::PipelineOptions o;
  o.identify.es.threads = 1;
  o.identify.generations = 50;
  return o;
}

TEST(StructureJob, SelectsOnceTheWindowIsLongEnoughAndAgainOnRequest) {
  mme::RandomObjectSpec spec;
  spec.particles = 10;
  spec.bond_types = 3;
  spec.bonds = 16;
  const mme::Model truth = mme::makeRandomObject(spec);
  const mme::Model particles = mme::test::particlesOnly(truth);
  const mme::Trajectory data = mme::simulateTrajectory(truth, 120, truth.frame_rate_hz);
  mme::StructureJob job(particles, quickOptions(), 100);
  EXPECT_EQ(job.minFrames(), 100);
  EXPECT_TRUE(job.pending());
  EXPECT_EQ(job.status(), "pending");
  // Too short a window: nothing runs, the request stays.
  EXPECT_FALSE(job.runIfDue(mme::sliceFrames(data, 0, 60)).has_value());
  EXPECT_TRUE(job.pending());
  const std::optional<mme::StructureResult> r = job.runIfDue(data);
  ASSERT_TRUE(r.has_value());
  EXPECT_FALSE(job.pending());
  EXPECT_EQ(job.status().rfind("chosen:springs", 0), 0u) << job.status();
  EXPECT_EQ(job.selections(), 1u);
  const mme::StructureScore score = mme::scoreStructure(truth, r->model);
  EXPECT_GE(score.f1, 0.95);
  EXPECT_EQ(score.types, 3);
  // No request: nothing runs; a request runs it again.
  EXPECT_FALSE(job.runIfDue(data).has_value());
  job.request();
  EXPECT_EQ(job.status(), "pending");
  EXPECT_TRUE(job.runIfDue(data).has_value());
  EXPECT_EQ(job.selections(), 2u);
}

TEST(StructureJob, AnUnusableWindowFailsWithTheReason) {
  mme::RandomObjectSpec spec;
  spec.particles = 6;
  spec.bond_types = 2;
  spec.bonds = 8;
  const mme::Model truth = mme::makeRandomObject(spec);
  const mme::Model particles = mme::test::particlesOnly(truth);
  mme::Trajectory data = mme::simulateTrajectory(truth, 60, truth.frame_rate_hz);
  // Every sample of the window occluded: no candidate pair.
  for (auto& o : data.occluded) o = 1;
  mme::StructureJob job(particles, quickOptions(), 10);
  EXPECT_EQ(job.minFrames(), 35);  // selection's own minimum
  EXPECT_FALSE(job.runIfDue(data).has_value());
  EXPECT_EQ(job.status(), "failed");
  EXPECT_EQ(job.state(), mme::StructureJob::State::kFailed);
  EXPECT_NE(job.lastError().find("candidate"), std::string::npos) << job.lastError();
  EXPECT_EQ(job.selections(), 0u);
}

// The real window that crashed the node (test/data/crash): with the time limit spent at once the
// job still chooses (the first level's elimination so far) and says it was cut.
TEST(StructureJob, ACutSelectionOnTheCrashWindowChoosesAndIsFlagged) {
  const mme::Trajectory data =
      mme::sliceFrames(mme::readTrajectoryFile(std::string(MME_TEST_DATA_DIR) + "/crash/window_0_99.trc"), 0, 80);
  mme::PipelineOptions options = quickOptions();
  options.identify.max_wall_time_s = 1e-9;
  mme::StructureJob job(mme::markerModel(data), options, 80);
  const std::optional<mme::StructureResult> r = job.runIfDue(data);
  ASSERT_TRUE(r.has_value()) << job.lastError();
  EXPECT_EQ(job.status(), "chosen:springs");
  EXPECT_EQ(job.state(), mme::StructureJob::State::kChosen);
  EXPECT_TRUE(job.lastCut());
  EXPECT_TRUE(r->stopped_by_time);
  EXPECT_FALSE(r->model.bonds.empty());
}

// The first level reaches the caller during the selection, once, with every free value set and
// the base model's rate setting; the result says whether the choice is that level's structure.
TEST(StructureJob, HandsOverTheFirstLevelWhileTheSelectionGoesOn) {
  mme::RandomObjectSpec spec;
  spec.particles = 10;
  spec.bond_types = 3;
  spec.bonds = 16;
  const mme::Model truth = mme::makeRandomObject(spec);
  mme::Model particles = mme::test::particlesOnly(truth);
  particles.frame_rate_hz = 0.0;  // a live model: the stream's rate
  const mme::Trajectory data = mme::simulateTrajectory(truth, 120, truth.frame_rate_hz);
  mme::StructureJob job(particles, quickOptions(), 100);
  int calls = 0;
  std::string level, status_during;
  mme::Model first;
  const std::optional<mme::StructureResult> r =
      job.runIfDue(data, [&](const mme::Model& model, const std::string& name) {
        ++calls;
        first = model;
        level = name;
        status_during = job.status();
      });
  ASSERT_TRUE(r.has_value()) << job.lastError();
  EXPECT_EQ(calls, 1);
  EXPECT_EQ(level, "springs");
  EXPECT_EQ(status_during, "running");  // the later levels were still to come
  EXPECT_EQ(first.frame_rate_hz, 0.0);
  ASSERT_FALSE(mme::freeParameters(first).empty());
  for (const mme::ParamRef& ref : mme::freeParameters(first)) EXPECT_TRUE(mme::paramOf(first, ref).has_value) << ref.name;
  EXPECT_GT(r->candidates.size(), 1u);
  // Noiseless springs: the springs level is chosen, so what was handed over is the answer.
  EXPECT_EQ(job.status().rfind("chosen:springs", 0), 0u) << job.status();
  EXPECT_TRUE(mme::StructureJob::choseFirstLevel(*r));
  mme::StructureResult other = *r;
  for (mme::StructureCandidate& c : other.candidates) c.chosen = false;
  other.candidates.back().chosen = true;
  other.candidates.back().same_as.clear();
  EXPECT_FALSE(mme::StructureJob::choseFirstLevel(other));
  other.candidates.back().same_as = other.candidates.front().name;
  EXPECT_TRUE(mme::StructureJob::choseFirstLevel(other));
}

}  // namespace
