// Online identification over a sliding window of frames: frames arrive from any thread, a
// worker calls update() to run a few generations on the current window with the population
// warm-started from the previous window, and readers take the latest estimate. No ROS here; the
// node only converts messages and drives it.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <Eigen/Core>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/identification/search/evolution_strategy.h"
#include "motion_model_estimation/identification/identifier.h"
#include "motion_model_estimation/identification/estimators/output_error.h"
#include "motion_model_estimation/identification/online/migrants.h"

namespace mme {

/// The preset's engine options. Online, the refinement does not run inside a generation: the
/// estimator runs it beside the generations on its own thread (see OnlineEstimator), on the
/// preset's schedule.
inline EsOptions onlineEsOptions(Preset preset = Preset::kDefault) { return esOptionsFor(preset); }

struct OnlineEstimatorOptions {
  int window_frames = 100;          ///< frames in the sliding window
  int min_frames = 10;              ///< frames needed before the first update
  int generations_per_update = 5;   ///< generations run by one update() at most
  /// [s] one update() returns within about this: it runs the generations that fit (at least
  /// one). The refinement never runs inside it (it runs beside, see OnlineEstimator).
  double update_budget_s = 0.08;
  /// [s] a refinement running beside the generations stops after this long (its best so far is
  /// handed over as usual).
  double refine_max_s = 10.0;
  /// Called first on each thread the estimator starts beside the worker (the refinements), e.g.
  /// to name it or lower its priority so that the worker gets the cores first (may be empty).
  std::function<void()> on_background_thread_start;
  /// Which cost gives the published estimate (identifier.h): kAuto picks the output-error
  /// estimator when the first window's estimated marker noise reaches auto_noise_threshold_m.
  /// It runs beside the generations after each refinement, warm-started from its last answer.
  CostChoice cost = CostChoice::kAuto;
  double auto_noise_threshold_m = 1e-7;
  OutputErrorOptions output_error;
  double stability_rollout_factor = 10.0;  ///< stability rollout length / window length
  /// Start the population at the model's values of the free parameters when all have one
  /// (resuming an autosaved model) instead of the paper's random initialisation.
  bool resume_from_model_values = false;
  /// Accept a model with no free parameter (the particles alone, while a structure is being
  /// chosen): frames are collected and update() returns false until replaceModel() gives one.
  bool wait_for_structure = false;
  /// false: the model is shown as it is, nothing is searched. The model must hold a value for
  /// every free parameter (an identified model); update() publishes those values, judged on the
  /// current window (cost, stability), once per new frame and never changes them.
  bool estimate_values = true;
  EsOptions es = onlineEsOptions();  ///< population, seed, threads, operators
  /// Island model: batches of migrants waiting for the next update() at most; a batch arriving
  /// at a full queue pushes out the oldest (counted in MigrationCounters::dropped), so a fast
  /// or numerous set of peers never makes the queue grow.
  int migrant_queue_batches = 8;
};

std::string validateOptions(const OnlineEstimatorOptions& options);

/// A snapshot of the current best model.
struct Estimate {
  /// The refinement beside the generations: how many have been handed over and how the last
  /// ended (kNotRun before the first).
  uint32_t refinements = 0;
  RefineStatus last_refine_status = RefineStatus::kNotRun;
  /// The cost of the published values: kShortTerm (the population's best on this window) or
  /// kOutputError (the last output-error fit, on the window it ran on).
  Estimator estimator = Estimator::kShortTerm;
  std::vector<ParameterFlag> parameter_flags;  ///< per parameter
  double noise_std_m = 0.0;         ///< output error: the marker noise its residuals show
  /// Output-error fits not adopted so far (diverged, or predicting the window worse than the
  /// one-step answer, answer_judge.h): the one-step answer was published instead.
  uint32_t output_error_rejections = 0;
  bool valid = false;               ///< false until the first update
  uint32_t generation = 0;
  uint64_t evaluations = 0;
  double global_cost = 0.0;         ///< [m^2] on the window it was computed on
  uint32_t window_frames = 0;
  std::vector<std::string> parameter_names;
  std::vector<double> values;
  std::vector<double> std_devs;     ///< 1-sigma spread of the population's elite (NaN: unknown)
  std::vector<double> local_costs;  ///< per particle [m^2]
  bool stable = false;              ///< the long rollout from the window start stays bounded
  double window_start_time_s = 0.0;
  double window_end_time_s = 0.0;
};

/// Counters of rejected input, for diagnostics.
struct InputCounters {
  uint64_t accepted = 0;
  uint64_t rejected_size = 0;      ///< wrong number of positions
  uint64_t rejected_time = 0;      ///< time not after the previous frame (reordered, duplicated)
  uint64_t occluded_samples = 0;   ///< occluded or non-finite samples of markers, masked
  /// Samples of fixed particles the stream has no marker for (kNoMarker: a point of the model
  /// only, such as a sensor muscle's anchor), masked but not occluded markers.
  uint64_t model_only_samples = 0;
};

/// The refinement of the best individual (the engine's periodic one) runs beside the generations
/// on a thread of its own, on the window of the moment it starts; when it ends, its answer is
/// offered to the population on the window of that moment. update() never waits for it, not
/// even when the model changes (the refinement is then cancelled and left to end on its own),
/// so an update takes about update_budget_s whatever the model's size.
class OnlineEstimator {
 public:
  /// Throws InputError when the model or options are unusable.
  OnlineEstimator(const Model& model, const OnlineEstimatorOptions& options);
  ~OnlineEstimator();

  /// addFrame's `occluded` value for a particle the input has no marker of (MarkerNameMap): a
  /// fixed particle then is a point of the model only (counted in model_only_samples), a free
  /// one a hidden marker (counted as occluded).
  static constexpr uint8_t kNoMarker = 2;
  /// Adds a frame in the model's particle order (thread-safe). Returns an empty string when
  /// accepted, else why it was rejected. Non-finite positions are masked as occluded;
  /// `occluded` holds 0 (seen), 1 (occluded) or kNoMarker per particle, or is empty.
  std::string addFrame(double time_s, const std::vector<Eigen::Vector3d>& positions_m,
                       const std::vector<uint8_t>& occluded);
  /// Runs generations_per_update generations on the current window (call from one worker
  /// thread). Returns false when there are not enough frames yet, or when reset() or
  /// replaceModel() came during the update: its result belongs to the old model, so it stops at
  /// the next generation and is never committed.
  bool update();
  /// Waits for a refinement running beside the generations (tests; update() never waits).
  void waitForRefinement();
  /// The latest estimate (thread-safe copy).
  Estimate estimate() const;
  InputCounters counters() const;
  /// The current window (thread-safe copy), particles as markers.
  Trajectory window() const;
  /// The model with the best values filled in (the loaded model before the first update).
  Model currentModel() const;
  /// Island model: copies of the `count` best individuals of the population with the parameter
  /// names, generation, seed and window they belong to; no individual before the first update.
  /// Thread-safe; waits for a running update(), so the worker calls it between its updates.
  MigrantBatch emigrants(int count) const;
  /// Island model (thread-safe, never waits for an update): queues `batch` for the next
  /// update(), which re-evaluates its individuals on its window and lets them replace its worst
  /// (EvolutionStrategy::immigrate). Returns "" when queued; else why it was refused (the
  /// parameters differ by name or order, parameterMismatch; or the batch is malformed), and
  /// nothing changes but the refused count.
  std::string receiveMigrants(MigrantBatch batch);
  /// Island model: migrants the transport could not read (e.g. a message whose arrays do not
  /// match its counts, unflattenMigrants): `individuals` (as many as the sender announced) are
  /// counted as refused; returns `why`.
  std::string refuseMigrants(uint64_t individuals, const std::string& why);
  MigrationCounters migrationCounters() const;
  /// Forgets the population (and the window when `clear_window`).
  void reset(bool clear_window);
  /// Replaces the model (same or different structure); the population restarts. Throws
  /// InputError when unusable.
  void replaceModel(const Model& model);
  std::vector<std::string> particleNames() const;  ///< model particle order (thread-safe copy)
  double frameRateHz() const;
  /// Simulates `frames` frames of `model` from the first two frames of `window` (positions and
  /// finite-difference velocity). A fixed particle starts where the model holds it (an anchor
  /// has no marker); a free one hidden in either frame is placed there by its neighbours' rigid
  /// motion (fillFromNeighbours, later frames of the window too). Empty when the window is too
  /// short, is not the model's particles, or a hidden free particle cannot be placed.
  static Trajectory rollout(const Model& model, const Trajectory& window, int frames);
  /// Whether a frame `step_s` [s] after the previous one (either sign) starts a new window
  /// (addFrame's rule). Forward: beyond max(1 s, 10 frame intervals), a pause (shorter gaps are
  /// dropped frames). Backward: beyond 10 frame intervals, a looping bag or a restarted capture
  /// (a reordered or duplicated frame is a few intervals late at most; one topic's frames come
  /// in order); 1 s while the interval is unknown (`interval_s` 0: one frame in the window).
  static bool isClockJump(double step_s, double interval_s);

 private:
  Trajectory snapshotLocked() const;
  /// The estimate of the update under way (update_mutex_ held).
  Estimate makeEstimate(const Model& model, const Trajectory& window_data) const;

  mutable std::mutex frames_mutex_;
  std::deque<double> times_s_;
  std::deque<std::vector<Eigen::Vector3d>> positions_;
  std::deque<std::vector<uint8_t>> occluded_;
  InputCounters counters_;

  std::vector<std::string> names_;  // guarded by frames_mutex_
  std::vector<uint8_t> fixed_;      // per particle, 1 = fixed (guarded by frames_mutex_)
  uint64_t frames_added_ = 0;       // accepted frames, ever (guarded by frames_mutex_)
  uint64_t held_frames_ = 0;        // frames_added_ at the last held estimate (update_mutex_)
  uint32_t held_updates_ = 0;       // held estimates made for this model (update_mutex_)
  /// update() without a search (estimate_values false): the model's own values on the window.
  /// `frames_added`: frames_added_ when `window` was taken; false when no frame came since the
  /// last held estimate, or the model changed since `version`.
  bool holdModelValues(Model model, const Trajectory& window, uint64_t frames_added,
                       uint64_t version);

  // model_ and model_version_ are read and replaced under model_mutex_, held only for a copy, so
  // services and marker building never wait for an update (std::mutex is not fair: a reader
  // queued on a lock that update() holds back to back would starve). reset() and
  // replaceModel() bump the version; update() drops its population when the version moved and
  // discards a result computed for an older version.
  mutable std::mutex model_mutex_;
  Model model_;
  uint64_t model_version_ = 0;
  /// Whether reset() or replaceModel() came since `version` was read.
  bool modelChangedSince(uint64_t version) const;

  /// The refinement running beside the generations (guarded by update_mutex_).
  struct BackgroundRefinement;
  /// Hands a finished refinement's answer to the population; starts the next one when due.
  void handOverRefinement();
  void startRefinement(std::shared_ptr<const Cost> cost, const Model& model,
                       const Trajectory& window);
  /// Cancels the running refinement (its answer belongs to an older model) and moves it to
  /// retired_, without waiting for it: a fit may take a while to notice the cancel (a
  /// covariance or a Ceres iteration runs to its end), and update() never waits for it.
  void retireRefinement();
  /// Joins the retired refinements that have ended (they no longer compute).
  void reapRetiredRefinements();

  mutable std::mutex update_mutex_;  // guards es_, es_version_ and refinement_ (held through update())
  const OnlineEstimatorOptions options_;  // never changes after construction
  std::unique_ptr<EvolutionStrategy> es_;
  uint64_t es_version_ = 0;  // the model_version_ es_ was built for
  std::unique_ptr<BackgroundRefinement> refinement_;
  /// Cancelled refinements still running (guarded by update_mutex_); joined once ended, or by
  /// the destructor.
  std::vector<std::unique_ptr<BackgroundRefinement>> retired_;
  int last_refine_generation_ = -1;  // es_'s generation when the last refinement started
  uint32_t refinements_done_ = 0;
  RefineStatus last_refine_status_ = RefineStatus::kNotRun;
  bool use_output_error_ = false;   // decided when the population starts
  OutputErrorResult output_error_;  // the last output-error fit (ran = false before the first)
  uint32_t output_error_rejections_ = 0;  // fits not adopted (Estimate::output_error_rejections)
  /// Applies the queued migrants to es_ (under update_mutex_); batches queued for an older
  /// model are dropped.
  void applyMigrants(uint64_t version);
  struct QueuedBatch {
    MigrantBatch batch;
    uint64_t model_version = 0;  // the model whose parameter names it matched
  };
  mutable std::mutex migrants_mutex_;  // guards migrant_queue_ and migration_ (held briefly)
  std::deque<QueuedBatch> migrant_queue_;
  MigrationCounters migration_;
  double window_start_time_s_ = 0.0, window_end_time_s_ = 0.0;  // es_'s window (update_mutex_)
  mutable std::mutex estimate_mutex_;  // guards estimate_ (readers never wait for an update)
  Estimate estimate_;
};

}  // namespace mme
