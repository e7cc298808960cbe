// Bad input at the OnlineEstimator (docs/reliability.md): wrong sizes, NaN, occlusion,
// reordered and duplicated frames are rejected or masked without losing the identified model;
// a clock jump (a bag played with --loop, a restarted capture) starts a new window instead of
// rejecting every frame until the clock catches up.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <thread>
#include <limits>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/online_estimator.h"
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

}  // namespace

// The node's services and marker building read the model while a worker thread runs update()
// back to back. They must not queue on the lock update() holds: std::mutex is not fair, so such
// a reader starved for many seconds (the services rostest timed out that way). The readers use
// the whole of each update's time for nothing but copies: 200 of them finish while the worker
// has done only a few updates, and a reset or a model replacement takes effect at once.
TEST_F(Fixture, ReadersAndResetsNeverWaitForARunningUpdate) {
  mme::OnlineEstimatorOptions o = options();
  o.generations_per_update = 200;  // long updates: a reader queued behind one would wait long
  mme::OnlineEstimator e(model, o);
  for (int t = 0; t < 50; ++t) ASSERT_EQ(e.addFrame(0.01 * t, frame(t), {}), "");
  ASSERT_TRUE(e.update());  // one update, so later ones re-evaluate a living population
  std::atomic<bool> stop{false};
  std::atomic<int> updates{0};
  std::thread worker([&] {
    while (!stop) if (e.update()) ++updates;
  });
  while (updates == 0) std::this_thread::yield();  // the worker is in its loop
  const int updates_before = updates;
  for (int k = 0; k < 200; ++k) {
    const mme::Model m = e.currentModel();
    ASSERT_EQ(m.particles.size(), 3u);
    EXPECT_GT(e.frameRateHz(), 0.0);
  }
  e.reset(false);
  EXPECT_FALSE(e.estimate().valid) << "reset clears the estimate at once";
  e.replaceModel(model);
  const int updates_after = updates;
  stop = true;
  worker.join();
  // Without the fix each currentModel() waited for at least one whole update (200 generations).
  EXPECT_LT(updates_after - updates_before, 50)
      << "200 model reads took " << (updates_after - updates_before) << " updates";
  // After the replacement the population restarts: the next estimate starts from generation 0.
  ASSERT_TRUE(e.update());
  EXPECT_LE(e.estimate().generation, 200u);
}
