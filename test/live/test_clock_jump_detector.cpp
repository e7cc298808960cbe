// ClockJumpDetector: a frame further than max(1 s, 10 frame intervals) ahead of the previous one,
// or more than 10 frame intervals behind it, is a jump; it agrees with OnlineEstimator's own
// window restarts on a long random stream.
#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "motion_model_estimation/identification/online/online_estimator.h"
#include "motion_model_estimation/io/model_yaml.h"
#include "motion_model_estimation/live/clock_jump_detector.h"

namespace {

const char* kModel = R"(
frame_rate_hz: 100
particles:
  - {name: a, mass: 1.0, position: [0, 0, 0]}
  - {name: b, mass: 1.0, position: [0.1, 0, 0]}
bond_types:
  - {name: s, kind: spring, stiffness: {value: 20, free: true}, rest_length: 0.1}
bonds:
  - {type: s, particles: [a, b]}
)";

TEST(ClockJumpDetector, SteadyStreamHasNoJumpAndALoopBackIsOne) {
  mme::ClockJumpDetector d;
  for (int k = 0; k < 500; ++k) EXPECT_FALSE(d.onAcceptedFrame(100.0 + 0.01 * k)) << k;
  const std::optional<double> back = d.onAcceptedFrame(100.0);  // a bag played with --loop
  ASSERT_TRUE(back);
  EXPECT_NEAR(*back, -4.99, 1e-9);
  EXPECT_EQ(d.jumps(), 1u);
  EXPECT_FALSE(d.onAcceptedFrame(100.01));
  const std::optional<double> pause = d.onAcceptedFrame(130.0);  // a pause forwards
  ASSERT_TRUE(pause);
  EXPECT_NEAR(*pause, 29.99, 1e-9);
  EXPECT_EQ(d.jumps(), 2u);
}

// A bag shorter than a second played with --loop: each loop steps back 0.49 s, 49 intervals.
TEST(ClockJumpDetector, AShortLoopingBagJumpsAtEveryLoop) {
  mme::ClockJumpDetector d;
  for (int loop = 0; loop < 3; ++loop)
    for (int k = 0; k < 50; ++k) {
      const std::optional<double> jump = d.onAcceptedFrame(0.01 * k);
      EXPECT_EQ(jump.has_value(), loop > 0 && k == 0) << loop << " " << k;
    }
  EXPECT_EQ(d.jumps(), 2u);
}

TEST(ClockJumpDetector, SlowStreamsGetTenFrameIntervals) {
  mme::ClockJumpDetector d;
  // 2 Hz: a 3 s gap (6 intervals, a few dropped frames) is no jump; 5.5 s (11 intervals) is.
  EXPECT_FALSE(d.onAcceptedFrame(0.0));
  EXPECT_FALSE(d.onAcceptedFrame(0.5));
  EXPECT_FALSE(d.onAcceptedFrame(1.0));
  EXPECT_FALSE(d.onAcceptedFrame(4.0));  // the interval is now 3 s: up to 30 s is no jump
  EXPECT_FALSE(d.onAcceptedFrame(4.5));
  EXPECT_TRUE(d.onAcceptedFrame(10.0));
  // Right after a jump the window holds one frame and no interval: 1 s is the threshold.
  EXPECT_TRUE(d.onAcceptedFrame(11.5));
  EXPECT_FALSE(d.onAcceptedFrame(12.0));
  EXPECT_FALSE(d.onAcceptedFrame(12.5));
  EXPECT_FALSE(d.onAcceptedFrame(16.5));  // 8 intervals of 0.5 s
  EXPECT_EQ(d.jumps(), 2u);
}

TEST(ClockJumpDetector, AnEmptiedWindowStartsWithoutAJump) {
  mme::ClockJumpDetector d;
  EXPECT_FALSE(d.onAcceptedFrame(50.0));
  EXPECT_FALSE(d.onAcceptedFrame(50.01));
  d.forgetWindow();  // a model with other particles was loaded
  EXPECT_FALSE(d.onAcceptedFrame(3.0));
  EXPECT_FALSE(d.onAcceptedFrame(3.01));
  EXPECT_EQ(d.jumps(), 0u);
}

TEST(ClockJumpDetector, WarningText) {
  EXPECT_EQ(mme::ClockJumpDetector::warning(-60.0, 3),
            "input clock jumped by -60.000 s (looping bag, restarted capture or a pause): the "
            "window restarts (3 jumps so far)");
}

TEST(ClockJumpDetector, AgreesWithTheEstimatorsWindowRestarts) {
  const mme::Model model = mme::loadModelString(kModel, "test");
  mme::OnlineEstimatorOptions options;
  options.window_frames = 5;  // the window slides often
  options.min_frames = 3;
  mme::OnlineEstimator estimator(model, options);
  mme::ClockJumpDetector detector;
  // Steps: steady rates of 100 Hz to 0.3 Hz, reordered and duplicated frames, dropped frames,
  // jumps back and forward, steps just around the thresholds.
  const std::vector<double> steps = {0.01, 0.01, 0.01, 0.05, 0.3, 0.5, 0.95, 1.05, 2.0, 3.5,
                                     -0.005, 0.0, -0.3, 4.9, 5.1, 9.0, 31.0, -60.0, 0.099, 0.11};
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<size_t> pick(0, steps.size() - 1);
  const std::vector<Eigen::Vector3d> x = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.1, 0, 0)};
  double t = 1000.0;
  int accepted = 0, restarts = 0;
  for (int k = 0; k < 5000; ++k) {
    // Runs of one step size, so that the interval before a big step is known.
    const double step = steps[pick(rng)];
    const int run = 1 + static_cast<int>(rng() % 4);
    for (int r = 0; r < run; ++r) {
      const double time_s = t + step;
      const int before = estimator.window().numFrames();
      if (!estimator.addFrame(time_s, x, {}).empty()) continue;  // rejected: not told
      t = time_s;
      ++accepted;
      const bool restarted = before >= 1 && estimator.window().numFrames() == 1;
      restarts += restarted;
      EXPECT_EQ(detector.onAcceptedFrame(time_s).has_value(), restarted)
          << "frame " << accepted << " at " << time_s << " s, step " << step;
    }
  }
  EXPECT_EQ(detector.jumps(), static_cast<uint64_t>(restarts));
  EXPECT_GT(restarts, 100);  // the stream really exercised both outcomes
  EXPECT_GT(accepted - restarts, 1000);
}

}  // namespace
