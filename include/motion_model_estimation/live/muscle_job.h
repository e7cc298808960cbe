// The live node's sensor muscles (~sensor_muscles): adds them to the passive model the node
// estimates, once its window is long enough, by the offline fit (addSensorMuscles) under a time
// limit and with a smaller search than offline, then keeps them fitted on the sliding window by
// refitting only their linear part (refitMuscleActivations) each period, a refit replacing the
// muscles only where it predicts the window no worse. The job keeps the muscles; the estimator
// goes on with the passive model alone (its search never pays for the muscles' forces), and
// withMuscles() lays the muscles on its latest passive values for the node's predictions, rviz
// and exports. No ROS here: the node runs it on a thread of its own.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <string>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/identification/muscles/sensor_muscles.h"

namespace mme {

struct MuscleJobOptions {
  /// The first fit's options (liveSensorMuscleOptions: few sensors, one layout, no rollout
  /// rounds, a time limit). Its `progress` lines are passed on to `say`.
  SensorMuscleOptions fit;
  int min_frames = 50;           ///< window frames the first fit waits for [frames]
  double refit_period_s = 1.0;   ///< [s] between refits of the linear part (0: never refit)
  /// [s] a fit that was not kept or failed is tried again on a later window after this long.
  double retry_after_s = 10.0;
  int horizon_frames = 10;       ///< the refit's judge: open-loop error this many frames ahead
  std::function<void(const std::string&)> say;  ///< one line per event (may be empty)
};

/// The node's defaults: `sensors` sensor bonds, the anchor layout only (a walk's accelerations
/// live in the world) with the anchors' own stiffness held at 0 when the body travels, four
/// ridges, no rollout rounds and no activation time constant, `max_time_s` [s] for the search.
SensorMuscleOptions liveSensorMuscleOptions(int sensors = 6, double max_time_s = 20.0);

/// "" or why the options are unusable (naming the option).
std::string validateOptions(const MuscleJobOptions& options);

class MuscleJob {
 public:
  enum class State { kWaiting, kFitting, kFitted, kNotKept, kFailed };

  explicit MuscleJob(MuscleJobOptions options);

  /// When no muscles are fitted yet (or a retry is due at `now_s`, a monotonic clock [s]) and
  /// `window` holds min_frames frames: fits sensor muscles on `passive` (every free value set;
  /// the window has its particles as markers). Returns the model with them, passive's free
  /// parameters still free, when they are kept (and keeps it). Blocking; call from one thread.
  std::optional<Model> fitIfDue(const Model& passive, const Trajectory& window, double now_s);
  /// When muscles are fitted and refit_period_s has passed since the last refit ended: refits
  /// their linear part on `window` laid on `passive` (the estimator's model and window, its
  /// free values set) and keeps and returns the refitted model when its open-loop error
  /// horizon_frames ahead on the window is not above that of the muscles it replaces.
  std::optional<Model> refitIfDue(const Model& passive, const Trajectory& window, double now_s);
  /// The kept muscles laid on `passive` (the estimator's current model: its free values become
  /// the muscle model's); nothing when no muscles are kept or `passive` is not the model they
  /// were fitted on (another structure).
  std::optional<Model> withMuscles(const Model& passive) const;
  /// Forgets the muscles (a new structure was chosen, or a model loaded): the next fitIfDue fits.
  void forget();
  /// Stops a fit under way at its next step (shutdown); every later call does nothing.
  void cancel();

  State state() const;
  /// ~stats' word: "waiting", "fitting", "fitted", "not_kept", "failed".
  std::string status() const;
  std::string lastMessage() const;  ///< why not kept / failed, or the last fit's report
  int muscles() const;              ///< muscles of the fitted model (0 before)
  uint32_t fits() const;            ///< fits that gave muscles
  uint32_t refits() const;          ///< refits tried
  uint32_t refitsAdopted() const;   ///< refits that replaced the muscles
  double lastRefitMs() const;       ///< the last refit's wall time [ms] (0 before the first)
  double lastFitS() const;          ///< the last fit's wall time [s] (0 before the first)

  /// `window` with `model`'s particles as markers: the muscles' anchors, which have no marker,
  /// are added occluded.
  static Trajectory asModelParticles(const Trajectory& window, const Model& model);

 private:
  bool judgeRefit(const Model& current, const Model& refitted, const Trajectory& window) const;
  void say(const std::string& line) const;

  const MuscleJobOptions options_;
  std::atomic<bool> cancelled_{false};
  mutable std::mutex mutex_;
  State state_ = State::kWaiting;
  std::string message_;
  int muscles_ = 0;
  double ridge_ = 1.0;          // the fit's relative ridge, reused by the refits
  uint64_t version_ = 0;        // forget() bumps it: a fit under way then is stale
  std::optional<Model> model_;  // the kept muscles on the passive model they were fitted on
  double next_try_s_ = -1e300;  // fitIfDue: not before
  double next_refit_s_ = 0.0;
  uint32_t fits_ = 0, refits_ = 0, refits_adopted_ = 0;
  double last_refit_ms_ = 0.0, last_fit_s_ = 0.0;
};

}  // namespace mme
