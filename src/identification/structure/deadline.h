// The structure selection's wall-time limit (StructureOptions::max_wall_time_s). The selection
// reads it between its steps rather than interrupting them, so that a step under way (one
// solve, one refit bounded by what is left) still ends and leaves a consistent state; the steps
// decide for themselves what a spent limit means to them (give a level up, or end the first
// level on what it has). A raised cancel flag (identify.cancel, e.g. Ctrl-C) reads as a spent
// limit, so that an interrupted selection ends the same way.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <limits>

namespace mme {
namespace structure {

/// The selection's wall-time limit (0 = none), started when constructed.
class Deadline {
 public:
  explicit Deadline(double max_s, const std::atomic<bool>* cancel = nullptr)
      : max_s_(max_s), cancel_(cancel), start_(std::chrono::steady_clock::now()) {}
  double elapsedS() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  bool limited() const { return max_s_ > 0.0; }
  bool cancelled() const { return cancel_ && cancel_->load(); }
  bool passed() const { return cancelled() || (limited() && elapsedS() >= max_s_); }
  /// [s] left; infinite without a limit.
  double remainingS() const {
    return limited() ? std::max(0.0, max_s_ - elapsedS()) : std::numeric_limits<double>::infinity();
  }
  double maxS() const { return max_s_; }

 private:
  double max_s_;
  const std::atomic<bool>* cancel_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace structure
}  // namespace mme
