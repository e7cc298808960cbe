#include "motion_model_estimation/live/clock_jump_detector.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "motion_model_estimation/identification/online/online_estimator.h"

namespace mme {

std::optional<double> ClockJumpDetector::onAcceptedFrame(double time_s) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::optional<double> jump;
  if (frames_ > 0) {
    // OnlineEstimator::addFrame: the interval is 0 while the window holds a single frame.
    const double step_s = frames_ >= 2 ? step_s_ : 0.0;
    if (OnlineEstimator::isClockJump(time_s - last_s_, step_s)) jump = time_s - last_s_;
  }
  if (jump) {
    ++jumps_;
    frames_ = 1;  // the new window holds this frame only
  } else {
    if (frames_ > 0) step_s_ = time_s - last_s_;
    frames_ = std::min(frames_ + 1, 2);
  }
  last_s_ = time_s;
  return jump;
}

void ClockJumpDetector::forgetWindow() {
  std::lock_guard<std::mutex> lock(mutex_);
  frames_ = 0;
}

uint64_t ClockJumpDetector::jumps() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return jumps_;
}

std::string ClockJumpDetector::warning(double jump_s, uint64_t jumps) {
  char text[200];
  std::snprintf(text, sizeof(text),
                "input clock jumped by %.3f s (looping bag, restarted capture or a pause): the "
                "window restarts (%llu jumps so far)",
                jump_s, static_cast<unsigned long long>(jumps));
  return text;
}

}  // namespace mme
