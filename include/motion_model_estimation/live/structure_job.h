// The live node's structure selection (~select_structure): chooses the model's structure on the
// first window that is long enough and again on request (~reset), from the model the node
// started with (the particles, possibly some bonds). No ROS here: the node runs it on a thread
// of its own and hands the chosen model to the estimator.
#pragma once

#include <functional>
#include <mutex>
#include <optional>
#include <string>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/pipeline/identify_pipeline.h"

namespace mme {

class StructureJob {
 public:
  enum class State { kIdle, kPending, kRunning, kChosen, kFailed };

  /// `options`: the pipeline's (its structure step runs; identify.max_wall_time_s bounds it).
  /// `min_frames`: the window length a selection waits for (at least the 35 frames selection
  /// needs: 20 fitted, 15 held out). `request_first`: the first selection is requested now
  /// (else on the first request()).
  StructureJob(Model base, PipelineOptions options, int min_frames, bool request_first = true);

  /// (Re)selects on the next window holding min_frames frames (thread-safe).
  void request();
  bool pending() const;
  /// Receives the first level's model (every free value set, the base model's frame-rate
  /// setting) and its name while the selection goes on.
  using FirstLevel = std::function<void(const Model& model, const std::string& level)>;

  /// Runs the selection when one is requested and `window` holds enough frames (blocking; call
  /// from one thread). Returns the result, or nothing when it did not run or failed (status()
  /// then says why). `first_level`, when given, gets the first level as soon as it is judged
  /// (on this thread, during the call), so that a structure is in use long before the later
  /// levels are judged.
  std::optional<StructureResult> runIfDue(const Trajectory& window, const FirstLevel& first_level = {});
  /// Whether `result` chose the structure of its first level (that level, or a later one that
  /// kept nothing new): what runIfDue's `first_level` got is then the answer already.
  static bool choseFirstLevel(const StructureResult& result);
  /// kIdle (nothing requested yet), kPending, kRunning, kChosen, kFailed (thread-safe).
  State state() const;
  /// The state as ~stats names it: "idle", "pending", "running", "chosen:<level>", "failed".
  std::string status() const;
  std::string lastError() const;
  int minFrames() const { return min_frames_; }
  /// Whether the time limit (PipelineOptions::identify.max_wall_time_s) cut the last selection that
  /// chose a model (thread-safe).
  bool lastCut() const;
  uint32_t selections() const;  ///< selections that chose a model

 private:
  Model base_;
  PipelineOptions options_;
  int min_frames_;
  mutable std::mutex mutex_;
  bool requested_ = true;
  State state_ = State::kPending;
  std::string level_;  ///< the level the last selection chose
  std::string error_;
  uint32_t selections_ = 0;
  bool last_cut_ = false;
};

}  // namespace mme
