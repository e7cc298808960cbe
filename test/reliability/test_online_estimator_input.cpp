// Bad input at the OnlineEstimator (docs/reliability.md): wrong sizes, NaN, occlusion,
// reordered and duplicated frames are rejected or masked without losing the identified model;
// a clock jump (a bag played with --loop, a restarted capture) starts a new window instead of
// rejecting every frame until the clock catches up.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/online/online_estimator.h"
#include "motion_model_estimation/io/model_yaml.h"

namespace {

const char* kModel = R"(
frame_rate_hz: 100
gravity: [0, 0, 0]
particles:
  - {name: a, mass: 1.0, position: [0, 0, 0], velocity: [0.3, 0, 0]}
  - {name: b, mass: 0.8, position: [0.12, 0, 0], velocity: [-0.2, 0.1, 0]}
  - {name: c, mass: 1.2, position: [0.05, 0.1, 0.02], velocity: [-0.12, -0.07, 0]}
bond_types:
  - {name: s1, kind: spring, stiffness: {value: 20, free: true, min: 2, max: 200}, rest_length: 0.1}
bonds:
  - {type: s1, particles: [a, b]}
  - {type: s1, particles: [b, c]}
  - {type: s1, particles: [a, c]}
)";

struct Fixture : ::testing::Test {
  mme::Model model = mme::loadModelString(kModel, "test");
  mme::Trajectory truth = mme::simulateTrajectory(model, 400, 100.0);
  mme::OnlineEstimatorOptions options() const {
    mme::OnlineEstimatorOptions o;
    o.window_frames = 50;
    o.min_frames = 10;
    o.generations_per_update = 2;
    o.es.population = 10;
    o.es.offspring = 10;
    o.es.refine_period = 0;
    return o;
  }
  std::vector<Eigen::Vector3d> frame(int t) const {
    std::vector<Eigen::Vector3d> x;
    for (int i = 0; i < truth.numMarkers(); ++i) x.push_back(truth.position(t, i));
    return x;
  }
};

TEST_F(Fixture, WrongSizesAndNonFiniteTimesAreRejected) {
  mme::OnlineEstimator e(model, options());
  std::vector<Eigen::Vector3d> x = frame(0);
  x.pop_back();
  EXPECT_NE(e.addFrame(0.0, x, {}), "");
  EXPECT_NE(e.addFrame(0.0, frame(0), {0, 1}), "");  // occluded of the wrong length
  EXPECT_NE(e.addFrame(std::numeric_limits<double>::quiet_NaN(), frame(0), {}), "");
  EXPECT_NE(e.addFrame(std::numeric_limits<double>::infinity(), frame(0), {}), "");
  const mme::InputCounters c = e.counters();
  EXPECT_EQ(c.accepted, 0u);
  EXPECT_EQ(c.rejected_size, 2u);
  EXPECT_EQ(c.rejected_time, 2u);
  EXPECT_EQ(e.window().numFrames(), 0);
}

TEST_F(Fixture, NanAndOccludedSamplesAreMaskedNotRejected) {
  mme::OnlineEstimator e(model, options());
  std::vector<Eigen::Vector3d> x = frame(0);
  x[1].y() = std::numeric_limits<double>::quiet_NaN();
  x[2].z() = std::numeric_limits<double>::infinity();
  EXPECT_EQ(e.addFrame(0.0, x, {}), "");
  EXPECT_EQ(e.addFrame(0.01, frame(1), {1, 0, 0}), "");
  const mme::Trajectory w = e.window();
  ASSERT_EQ(w.numFrames(), 2);
  EXPECT_TRUE(w.isOccluded(0, 1));
  EXPECT_TRUE(w.isOccluded(0, 2));
  EXPECT_TRUE(w.isOccluded(1, 0));
  EXPECT_FALSE(w.isOccluded(1, 1));
  EXPECT_TRUE(w.validate().empty()) << w.validate();
  EXPECT_EQ(e.counters().occluded_samples, 3u);
  EXPECT_EQ(e.counters().accepted, 2u);
}

TEST_F(Fixture, ReorderedAndDuplicatedFramesAreRejected) {
  mme::OnlineEstimator e(model, options());
  for (int t = 0; t < 5; ++t) ASSERT_EQ(e.addFrame(t * 0.01, frame(t), {}), "");
  EXPECT_NE(e.addFrame(0.04, frame(4), {}), "");  // duplicate
  EXPECT_NE(e.addFrame(0.02, frame(2), {}), "");  // late (reordered)
  EXPECT_EQ(e.addFrame(0.05, frame(5), {}), "");
  EXPECT_EQ(e.counters().rejected_time, 2u);
  EXPECT_EQ(e.window().numFrames(), 6);
}

TEST_F(Fixture, ClockJumpStartsANewWindowAndKeepsTheModel) {
  mme::OnlineEstimator e(model, options());
  for (int t = 0; t < 60; ++t) ASSERT_EQ(e.addFrame(100.0 + t * 0.01, frame(t), {}), "");
  ASSERT_TRUE(e.update());
  const mme::Estimate before = e.estimate();
  ASSERT_TRUE(before.valid);
  // The stamps jump back by 60 s (a looping bag): every frame is still accepted.
  for (int t = 0; t < 5; ++t) EXPECT_EQ(e.addFrame(40.0 + t * 0.01, frame(100 + t), {}), "");
  EXPECT_EQ(e.window().numFrames(), 5);            // a new window: the old one did not continue
  EXPECT_FALSE(e.update());                         // not enough frames yet ...
  EXPECT_TRUE(e.estimate().valid);                  // ... and the model is kept meanwhile
  EXPECT_EQ(e.estimate().generation, before.generation);
  // Forward jump (a pause in the capture) as well.
  for (int t = 0; t < 20; ++t) EXPECT_EQ(e.addFrame(50.0 + t * 0.01, frame(200 + t), {}), "");
  EXPECT_EQ(e.window().numFrames(), 20);
  EXPECT_TRUE(e.update());                          // the population lives on (warm start)
  EXPECT_GT(e.estimate().generation, before.generation);
  EXPECT_EQ(e.counters().accepted, 85u);
  EXPECT_EQ(e.counters().rejected_time, 0u);
}

// A bag shorter than a second played with --loop steps back by less than a second at every
// loop: a new window each time, not a stream of "reordered" frames lost after the first loop.
// A frame a couple of intervals late is still a reordered one.
TEST_F(Fixture, AShortLoopingBagStartsANewWindowAtEveryLoop) {
  mme::OnlineEstimator e(model, options());
  for (int loop = 0; loop < 3; ++loop)
    for (int t = 0; t < 40; ++t) {
      ASSERT_EQ(e.addFrame(0.01 * t, frame(t), {}), "") << "loop " << loop << " frame " << t;
      if (loop > 0 && t == 0) {
        EXPECT_EQ(e.window().numFrames(), 1) << "a new window at the loop";
      }
    }
  EXPECT_EQ(e.counters().accepted, 120u);
  EXPECT_EQ(e.counters().rejected_time, 0u);
  EXPECT_NE(e.addFrame(0.37, frame(37), {}), "");  // 2 intervals late: reordered
  EXPECT_EQ(e.window().numFrames(), 40);
}

}  // namespace

// The node's services and marker building read the model while a worker thread runs update().
// They must not queue on the lock update() holds (std::mutex is not fair: such a reader starved
// for many seconds). Here one update is made to run for up to a minute; 200 reads finish while
// it is still running, and a reset() stops it at its next generation without committing
// anything. The verdicts do not depend on the machine's speed: only a reader blocked for the
// whole update, or an update that commits a stale result, fails them.
TEST_F(Fixture, ReadersAndResetsNeverWaitForARunningUpdate) {
  mme::OnlineEstimatorOptions o = options();
  o.generations_per_update = 100000000;  // ends on the budget (or on reset)
  o.update_budget_s = 60.0;
  mme::OnlineEstimator e(model, o);
  for (int t = 0; t < 50; ++t) ASSERT_EQ(e.addFrame(0.01 * t, frame(t), {}), "");
  std::atomic<bool> started{false}, finished{false};
  bool committed = true;
  std::thread worker([&] {
    started = true;
    committed = e.update();
    finished = true;
  });
  while (!started) std::this_thread::yield();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));  // well inside its generations
  for (int k = 0; k < 200; ++k) {
    const mme::Model m = e.currentModel();
    ASSERT_EQ(m.particles.size(), 3u);
    EXPECT_GT(e.frameRateHz(), 0.0);
    EXPECT_EQ(e.window().numFrames(), 50);
  }
  EXPECT_FALSE(finished) << "the reads waited for the running update";
  e.reset(false);
  EXPECT_FALSE(e.estimate().valid) << "reset clears the estimate at once";
  worker.join();
  EXPECT_FALSE(committed) << "an update in flight at reset() committed its stale result";
  EXPECT_FALSE(e.estimate().valid);
}

// An update under way when the model is replaced never commits onto the new model: while a
// worker runs updates back to back, every estimate seen after replaceModel() names the new
// model's parameters. Then the population restarts: one update gives the generations of one.
TEST_F(Fixture, AReplacedModelNeverReceivesAnOldUpdatesResult) {
  mme::OnlineEstimatorOptions o = options();
  o.generations_per_update = 20;
  mme::OnlineEstimator e(model, o);
  for (int t = 0; t < 50; ++t) ASSERT_EQ(e.addFrame(0.01 * t, frame(t), {}), "");
  ASSERT_TRUE(e.update());
  ASSERT_EQ(e.estimate().parameter_names, std::vector<std::string>{"s1/stiffness"});
  mme::Model renamed = model;
  renamed.bond_types[0].name = "s2";
  std::atomic<bool> stop{false};
  std::thread worker([&] {
    while (!stop) e.update();
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  e.replaceModel(renamed);
  std::vector<std::string> stale;  // the names of an estimate of the old model, if one is seen
  for (int k = 0; k < 2000 && stale.empty(); ++k) {
    const mme::Estimate now = e.estimate();
    if (now.valid && now.parameter_names != std::vector<std::string>{"s2/stiffness"})
      stale = now.parameter_names;
    std::this_thread::yield();
  }
  stop = true;
  worker.join();
  EXPECT_TRUE(stale.empty()) << "an estimate of the old model (" << stale.front()
                             << ") was committed after replaceModel()";
  e.replaceModel(model);
  ASSERT_TRUE(e.update());
  EXPECT_EQ(e.estimate().parameter_names, std::vector<std::string>{"s1/stiffness"});
  EXPECT_LE(e.estimate().generation, 20u);
}
