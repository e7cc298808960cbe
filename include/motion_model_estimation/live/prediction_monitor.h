// The live node's judge of its own model: every `period_s` the current model's open-loop
// prediction K frames ahead on the current window (evaluatePredictions, as the `evaluate` tool
// computes it), next to the model-free guesses, for the ~stats line. The window is what the
// model was fitted on, so these are in-sample figures; `evaluate` on later frames is the
// held-out judge. Thread-safe. No ROS here.
#pragma once

#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/identification/estimators/prediction_error.h"

namespace mme {

/// The rviz caption's line on the model against the guesses `horizon` frames ahead, e.g.
/// "10 frames ahead: model 7.1 mm (41 muscles), constant velocity 12.3, constant acceleration
/// 9.8 mm" (`muscles` 0: "(passive)"); "" when the report has no sample at that horizon.
std::string predictionCaption(const PredictionReport& report, int horizon, int muscles);

class PredictionMonitor {
 public:
  static constexpr double kDefaultPeriodS = 5.0;

  /// Throws InputError on horizons < 1, none, or a period <= 0.
  explicit PredictionMonitor(std::vector<int> horizons = {1, 5, 10},
                             double period_s = kDefaultPeriodS);
  /// True when no evaluation was tried yet or `period_s` has passed since the last try (`now_s`
  /// on the caller's monotonic clock).
  bool due(double now_s) const;
  /// Evaluates `model` (every free value set) on `window` (its particles as markers) and keeps
  /// the report; a window the predictions cannot use (too short, occluded at every start)
  /// keeps nothing and its reason is kept instead. Returns whether a report was made.
  bool evaluate(double now_s, const Model& model, const Trajectory& window);
  /// The last report, when the last try made one.
  std::optional<PredictionReport> report() const;
  std::string lastError() const;  ///< why the last try made no report ("" when it did)

 private:
  const std::vector<int> horizons_;
  const double period_s_;
  mutable std::mutex mutex_;
  bool tried_ = false;
  double last_try_s_ = 0.0;
  std::optional<PredictionReport> report_;
  std::string error_;
};

}  // namespace mme
