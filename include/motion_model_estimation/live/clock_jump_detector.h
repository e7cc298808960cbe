// Tells, for each frame the OnlineEstimator accepted, whether the input clock jumped there (a
// looping bag, a restarted capture, a pause) so that the estimator started a new window with
// it, and counts those jumps for ~stats. The rule is the estimator's own
// (OnlineEstimator::isClockJump), applied here to the accepted frames because the estimator does
// not report the restart; test_clock_jump_detector checks that both agree.
// Thread-safe. No ROS here.
#pragma once

#include <cstdint>
#include <mutex>
#include <optional>
#include <string>

namespace mme {

class ClockJumpDetector {
 public:
  /// A frame stamped `time_s` [s] was accepted by the estimator. Returns the jump [s] (this
  /// frame's time minus the previous accepted frame's, either sign) when the estimator's window
  /// restarted with this frame, else nothing.
  std::optional<double> onAcceptedFrame(double time_s);
  /// The estimator's window was emptied (a model with other particles was loaded): the next
  /// frame starts a window without a jump.
  void forgetWindow();
  uint64_t jumps() const;  ///< jumps so far

  /// "input clock jumped by -60.000 s (looping bag, restarted capture or a pause): the window
  /// restarts (3 jumps so far)"
  static std::string warning(double jump_s, uint64_t jumps);

 private:
  mutable std::mutex mutex_;
  int frames_ = 0;          // frames of the window known here, capped at 2
  double last_s_ = 0.0;     // the last accepted frame's time
  double step_s_ = 0.0;     // the interval between the last two frames of the window
  uint64_t jumps_ = 0;
};

}  // namespace mme
