// rostest: estimator_node tracks a parameter that changes during the stream. simulator_node
// streams paper_object and multiplies ~step_param by ~step_factor after ~step_after_frames
// frames. Pass:
//   1. before the step, every parameter is within `tolerance` of the original truth;
//   2. within `max_frames_after_step` frames after the step (two window lengths), the estimate
//      of the stepped parameter is within `tolerance` of its new value (for `consecutive`
//      successive estimates).
// Frames are counted by the frame_number of the newest MarkerFrame this node has received when
// an estimate arrives (an upper bound of the frames the estimate has seen).
#include <atomic>
#include <cmath>
#include <sstream>

#include "test_estimator_common.h"
#include "master_check.h"

namespace {

using namespace mmetest;

std::atomic<int64_t> g_last_frame{-1};
void onFrame(const MarkerFrame::ConstPtr& m) { g_last_frame = m->frame_number; }

TEST(EstimatorNode, TracksAParameterStep) {
  ros::NodeHandle nh, pnh("~");
  std::string step_param = "s00/stiffness";
  double step_factor = 2.0, tolerance = 0.02, timeout_s = 40.0;
  int step_after_frames = 0, max_frames_after_step = 200, consecutive = 3;
  pnh.getParam("step_param", step_param);
  pnh.getParam("step_factor", step_factor);
  ASSERT_TRUE(pnh.getParam("step_after_frames", step_after_frames));
  pnh.getParam("max_frames_after_step", max_frames_after_step);
  pnh.getParam("tolerance", tolerance);
  pnh.getParam("timeout_s", timeout_s);
  pnh.getParam("consecutive", consecutive);

  const Truth before = sceneTruth("paper_object");
  const double old_value = before.at(step_param);
  ASSERT_TRUE(std::isfinite(old_value)) << step_param << " is not a free parameter";
  Truth after_step;  // only the stepped parameter is checked after the step
  after_step.names = {step_param};
  after_step.values = {old_value * step_factor};

  ros::Subscriber frames = nh.subscribe("markers", 1000, onFrame);
  EstimateRecorder recorder(nh, "estimator/estimate", [] { return g_last_frame.load(); });

  // 1. Converged on the original values before the step.
  std::string report = "no estimate";
  const long converged =
      waitForConvergence(recorder, before, tolerance, timeout_s, consecutive, &report, 0, 100);
  ASSERT_GE(converged, 0) << "before the step: " << report;
  const int64_t converged_frame = recorder.since(converged).front().tag;
  std::printf("[ INFO     ] converged on the original values at frame %lld\n",
              static_cast<long long>(converged_frame));
  ASSERT_LT(converged_frame + consecutive, step_after_frames)
      << "did not converge before the step: choose a later ~step_after_frames";

  // 2. Follows the step. Estimates received up to the step are skipped.
  ASSERT_TRUE(recorder.waitUntil(
      [&](const std::vector<EstimateRecorder::Entry>& e) {
        return !e.empty() && e.back().tag >= step_after_frames;
      },
      timeout_s));
  size_t first_after = 0;
  {
    const std::vector<EstimateRecorder::Entry> all = recorder.since(0);
    while (first_after < all.size() && all[first_after].tag < step_after_frames) ++first_after;
    ASSERT_GT(first_after, 0u);
    // Just before the step the estimate was still on the old value.
    const ModelEstimate& last_before = all[first_after - 1].msg;
    std::string worst;
    EXPECT_LE(worstRelativeError(last_before, before, &worst), tolerance) << worst;
  }
  report = "no estimate after the step";
  const long followed = waitForConvergence(recorder, after_step, tolerance, timeout_s,
                                           consecutive, &report, first_after);
  ASSERT_GE(followed, 0) << "after the step: " << report;
  const int64_t followed_frame = recorder.since(followed).front().tag;
  std::printf("[ INFO     ] %s followed %g -> %g at frame %lld (%lld frames after the step)\n",
              step_param.c_str(), old_value, old_value * step_factor,
              static_cast<long long>(followed_frame),
              static_cast<long long>(followed_frame - step_after_frames));
  EXPECT_LE(followed_frame - step_after_frames, max_frames_after_step)
      << step_param << " reached " << 100.0 * tolerance << " % of its new value "
      << old_value * step_factor << " only " << followed_frame - step_after_frames
      << " frames after the step";
}

}  // namespace

int main(int argc, char** argv) { return mmetest::runRosTests(argc, argv, "test_estimator_tracking"); }
