#include "motion_model_estimation/identification/online/online_estimator.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>

#include "motion_model_estimation/core/short_term_cost.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/core/observations.h"
#include "motion_model_estimation/identification/estimators/answer_judge.h"
#include "motion_model_estimation/identification/estimators/output_error.h"
#include "motion_model_estimation/identification/estimators/prediction_error.h"
#include "motion_model_estimation/identification/search/threshold_search.h"

namespace mme {

std::string validateOptions(const OnlineEstimatorOptions& o) {
  if (o.window_frames < 3) return "window_frames must be >= 3";
  if (o.min_frames < 3 || o.min_frames > o.window_frames)
    return "min_frames must be in [3, window_frames]";
  if (o.generations_per_update < 1) return "generations_per_update must be >= 1";
  if (!(o.stability_rollout_factor >= 1.0)) return "stability_rollout_factor must be >= 1";
  if (!(o.update_budget_s > 0.0) || !std::isfinite(o.update_budget_s))
    return "update_budget_s must be > 0";
  if (!(o.refine_max_s > 0.0) || !std::isfinite(o.refine_max_s)) return "refine_max_s must be > 0";
  if (o.migrant_queue_batches < 1) return "migrant_queue_batches must be >= 1";
  if (!o.estimate_values && o.wait_for_structure)
    return "estimate_values false shows a given model: it cannot wait for a structure to be chosen";
  return validateOptions(o.es);
}

namespace {
/// [s] a frame further than this (or 10 frame intervals) from the previous one starts a new
/// window: see isClockJump.
constexpr double kClockJumpS = 1.0;
constexpr double kClockJumpFrameIntervals = 10.0;

void checkModel(const Model& model, const OnlineEstimatorOptions& options) {
  const std::string bad = validateModel(model);
  if (!bad.empty()) throw InputError("model: " + bad);
  if (!options.estimate_values) {
    // Shown as it is: every value must be there (an identified model), none is searched.
    for (const ParamRef& ref : freeParameters(model))
      if (!paramOf(model, ref).has_value)
        throw InputError("model: parameter '" + ref.name +
                         "' has no value; a model shown as it is (estimate_values false) must be "
                         "an identified one (e.g. identify's --out)");
    return;
  }
  if (!options.wait_for_structure && freeParameters(model).empty())
    throw InputError("model: no free parameter to identify");
}

std::vector<uint8_t> fixedFlags(const Model& model) {
  std::vector<uint8_t> fixed;
  for (const Particle& p : model.particles) fixed.push_back(p.fixed ? 1 : 0);
  return fixed;
}

/// The search for a new model: the refinement runs beside the generations (startRefinement), not
/// inside them; with resume_from_model_values and a complete set of values in the model, the
/// first population starts there.
std::unique_ptr<EvolutionStrategy> makeSearch(const Model& model, const Trajectory& window,
                                              const OnlineEstimatorOptions& options) {
  EsOptions es_options = options.es;
  es_options.refine_period = 0;
  auto es = std::make_unique<EvolutionStrategy>(ParameterSpace(model, window), es_options);
  if (!options.resume_from_model_values) return es;
  std::vector<double> values;
  for (size_t k = 0; k < es->space().size(); ++k) {
    const Param& p = paramOf(model, es->space().gene(k).ref);
    if (!p.has_value) break;
    values.push_back(p.value);
  }
  if (values.size() == es->space().size()) {
    std::vector<double> genes = es->space().toSearch(values);
    for (size_t k = 0; k < genes.size(); ++k) genes[k] = es->space().reflect(k, genes[k]);
    es->setInitialGuess(genes, 1e-3);
  }
  return es;
}

/// 1-sigma from the spread of the elite (best fifth, at least 2) of the population: cheap enough
/// to do at every update, unlike the Hessian used offline. NaN with fewer than 2 individuals.
std::vector<double> eliteStdDevs(const EvolutionStrategy& es, size_t parameters) {
  std::vector<const Individual*> sorted;
  for (const Individual& ind : es.population()) sorted.push_back(&ind);
  std::sort(sorted.begin(), sorted.end(),
            [](const Individual* a, const Individual* b) { return a->cost < b->cost; });
  const size_t elite = std::max<size_t>(2, sorted.size() / 5);
  std::vector<double> std_devs(parameters, std::numeric_limits<double>::quiet_NaN());
  if (sorted.size() < 2) return std_devs;
  const size_t used = std::min(elite, sorted.size());
  std::vector<std::vector<double>> values(used);
  for (size_t j = 0; j < used; ++j) values[j] = es.space().toPhysical(sorted[j]->genes);
  for (size_t k = 0; k < parameters; ++k) {
    double mean = 0, sq = 0;
    for (size_t j = 0; j < used; ++j) mean += values[j][k];
    mean /= used;
    for (size_t j = 0; j < used; ++j) sq += (values[j][k] - mean) * (values[j][k] - mean);
    std_devs[k] = std::sqrt(sq / (used - 1));
  }
  return std_devs;
}

/// Stability: a long rollout (`rollout_frames`) of `best` from the window start keeps its free
/// particles near the box the window sees them in (RolloutBound, as evaluate judges; fixed ones,
/// such as anchors far off the body, are not judged). No rollout (a hidden free particle that
/// cannot be placed, which is also the case when no free particle is seen): not stable.
bool staysBounded(const Model& best, const Trajectory& window, int rollout_frames) {
  const Trajectory long_run = OnlineEstimator::rollout(best, window, rollout_frames);
  if (long_run.positions_m.empty()) return false;
  const RolloutBound bound = RolloutBound::of(best, prepareObservations(best, window), 0, window.numFrames());
  const auto first = long_run.positions_m.begin();
  const int n = long_run.numMarkers();
  std::vector<Eigen::Vector3d> frame_x_m(static_cast<size_t>(n));  // one frame's, reused
  for (int t = 0; t < long_run.numFrames(); ++t) {
    std::copy(first + t * n, first + (t + 1) * n, frame_x_m.begin());
    if (!bound.holds(best, frame_x_m)) return false;
  }
  return true;
}


/// Whether an output-error fit on `window` may replace the one-step answer at `one_step_genes`:
/// finite, not far above its start's cost (a fit that blew up on the way), and judged K frames
/// ahead on the window no worse or with residuals at the noise (outputErrorReplacesOneStep).
bool outputErrorAdoptable(const Model& model, const Trajectory& window, const ParameterSpace& space,
                          const std::vector<double>& one_step_genes, const OutputErrorResult& oe) {
  constexpr double kDivergedFactor = 10.0;  // as the offline identification's output-error step
  if (!oe.ran || !std::isfinite(oe.observation_cost_m2) ||
      (oe.start_cost_m2 > 0.0 && oe.observation_cost_m2 > kDivergedFactor * oe.start_cost_m2))
    return false;
  Model one_step = model, fitted = model;
  setValues(one_step, space.refs(), space.toPhysical(one_step_genes));
  setValues(fitted, space.refs(), oe.values);
  return outputErrorReplacesOneStep(judgedPredictionRms_m(fitted, window),
                                    judgedPredictionRms_m(one_step, window), oe.noise_std_m,
                                    oe.noise_std_prior_m);
}

}  // namespace

struct OnlineEstimator::BackgroundRefinement {
  std::atomic<bool> cancel{false};
  std::atomic<bool> done{false};
  RefineResult result;       // written by the thread before `done`
  OutputErrorResult output;  // likewise, when the output-error fit ran
  // The output-error fit predicts the window no worse than the refined one-step answer and did
  // not diverge (answer_judge.h); written with `output`.
  bool output_adopted = false;
  std::thread thread;
  ~BackgroundRefinement() {
    cancel = true;
    if (thread.joinable()) thread.join();
  }
};

OnlineEstimator::~OnlineEstimator() {
  std::lock_guard<std::mutex> lock(update_mutex_);
  retireRefinement();
  retired_.clear();  // cancelled: each destructor joins its thread
}

void OnlineEstimator::retireRefinement() {
  if (!refinement_) return;
  refinement_->cancel = true;
  retired_.push_back(std::move(refinement_));
}

void OnlineEstimator::reapRetiredRefinements() {
  // Only the ended ones: joining a thread that has set `done` waits for its return alone.
  retired_.erase(std::remove_if(retired_.begin(), retired_.end(),
                                [](const std::unique_ptr<BackgroundRefinement>& job) { return job->done.load(); }),
                 retired_.end());
}

void OnlineEstimator::waitForRefinement() {
  std::lock_guard<std::mutex> lock(update_mutex_);
  if (refinement_ && refinement_->thread.joinable()) refinement_->thread.join();
}

void OnlineEstimator::startRefinement(std::shared_ptr<const Cost> cost, const Model& model,
                                      const Trajectory& window) {
  auto job = std::make_unique<BackgroundRefinement>();
  RefineSettings settings = es_->refineSettings();
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                            std::chrono::duration<double>(options_.refine_max_s));
  settings.deadline = deadline;
  settings.cancel = &job->cancel;
  const Individual& best = es_->best();
  RefineStart start{best.genes, best.cost, best.mutability};
  BackgroundRefinement* out = job.get();
  const RefineAlgorithm algorithm = options_.es.refine_algorithm;
  // The output-error fit continues from its own last answer (the one-step search's best is
  // biased by the noise), or from the refined best the first time.
  const bool output_error = use_output_error_;
  const std::vector<double> warm = output_error_.ran ? output_error_.genes : std::vector<double>();
  OutputErrorOptions oe_options = options_.output_error;
  // The thread owns copies of what it reads (the space, the start, the window) and shares the
  // window's cost.
  job->thread = std::thread([out, cost, space = es_->space(), start, settings, algorithm,
                             output_error, warm, oe_options, model, window, deadline,
                             on_start = options_.on_background_thread_start]() mutable {
    if (on_start) on_start();
    const std::unique_ptr<Refiner> refiner = Refiner::Create(algorithm);
    try {
      out->result = refineAlternating(*refiner, *cost, space, start, settings, nullptr);
      if (output_error && !out->cancel) {
        const double left =
            std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
        if (left > 0.0) {
          oe_options.max_time_s = oe_options.max_time_s > 0.0 ? std::min(oe_options.max_time_s, left) : left;
          oe_options.cancel = &out->cancel;
          out->output = estimateOutputError(model, window, space,
                                            warm.empty() ? out->result.genes : warm, oe_options);
          out->output_adopted = outputErrorAdoptable(model, window, space, out->result.genes, out->output);
        }
      }
    } catch (const std::exception&) {
      out->result = RefineResult{start.genes, start.cost, 0, RefineStatus::kNoProgress};
    }
    out->done = true;
  });
  refinement_ = std::move(job);
  last_refine_generation_ = es_->generation();
}

void OnlineEstimator::handOverRefinement() {
  if (!refinement_ || !refinement_->done) return;
  if (refinement_->thread.joinable()) refinement_->thread.join();
  const RefineResult result = refinement_->result;
  const OutputErrorResult output = refinement_->output;
  const bool adopted = refinement_->output_adopted;
  refinement_.reset();
  if (result.evaluations > 0) es_->offer(result.genes);
  if (output.ran && adopted) {
    output_error_ = output;
    es_->offer(output.genes);  // a good start for the global search too
  } else if (output.ran) {
    // Diverged, or predicts worse than the one-step answer: the population's best is published
    // and the next fit starts from the refined best instead of this answer.
    output_error_ = OutputErrorResult();
    ++output_error_rejections_;
  }
  ++refinements_done_;
  last_refine_status_ = result.status;
}

OnlineEstimator::OnlineEstimator(const Model& model, const OnlineEstimatorOptions& options)
    : model_(model), options_(options) {
  const std::string bad = validateOptions(options);
  if (!bad.empty()) throw InputError(bad);
  checkModel(model, options_);
  for (const Particle& p : model.particles) names_.push_back(p.name);
  fixed_ = fixedFlags(model);
}

std::string OnlineEstimator::addFrame(double time_s, const std::vector<Eigen::Vector3d>& positions_m,
                                      const std::vector<uint8_t>& occluded) {
  std::lock_guard<std::mutex> lock(frames_mutex_);
  if (positions_m.size() != names_.size() || (!occluded.empty() && occluded.size() != names_.size())) {
    ++counters_.rejected_size;
    return "expected " + std::to_string(names_.size()) + " positions, got " +
           std::to_string(positions_m.size());
  }
  if (!std::isfinite(time_s)) {
    ++counters_.rejected_time;
    return "frame time is not finite";
  }
  if (!times_s_.empty()) {
    // A jump of the clock (a bag played with --loop, a restarted capture) or a long pause: the
    // window's frames do not continue into this one, so a new window starts with it (the
    // population lives on). Smaller steps back are reordered or duplicated frames.
    const double last_step =
        times_s_.size() >= 2 ? times_s_.back() - times_s_[times_s_.size() - 2] : 0.0;
    if (isClockJump(time_s - times_s_.back(), last_step)) {
      times_s_.clear();
      positions_.clear();
      occluded_.clear();
    } else if (!(time_s > times_s_.back())) {
      ++counters_.rejected_time;
      return "frame time does not advance (reordered or duplicated frame)";
    }
  }
  std::vector<uint8_t> mask(names_.size(), 0);
  std::vector<Eigen::Vector3d> x = positions_m;
  for (size_t i = 0; i < x.size(); ++i) {
    const uint8_t flag = occluded.empty() ? 0 : occluded[i];
    if (flag != 0 || !x[i].allFinite()) {
      mask[i] = 1;
      x[i].setZero();
      if (flag == kNoMarker && fixed_[i])
        ++counters_.model_only_samples;  // a point of the model only: no marker to hide
      else
        ++counters_.occluded_samples;
    }
  }
  times_s_.push_back(time_s);
  positions_.push_back(std::move(x));
  occluded_.push_back(std::move(mask));
  while (static_cast<int>(times_s_.size()) > options_.window_frames) {
    times_s_.pop_front();
    positions_.pop_front();
    occluded_.pop_front();
  }
  ++counters_.accepted;
  ++frames_added_;
  return "";
}

Trajectory OnlineEstimator::snapshotLocked() const {
  Trajectory t;
  t.marker_names = names_;
  const int frames = static_cast<int>(times_s_.size());
  t.times_s.assign(times_s_.begin(), times_s_.end());
  t.frame_numbers.resize(frames);
  t.positions_m.reserve(frames * names_.size());
  t.occluded.reserve(frames * names_.size());
  for (int f = 0; f < frames; ++f) {
    t.frame_numbers[f] = static_cast<uint32_t>(f);
    t.positions_m.insert(t.positions_m.end(), positions_[f].begin(), positions_[f].end());
    t.occluded.insert(t.occluded.end(), occluded_[f].begin(), occluded_[f].end());
  }
  // Rate from the median frame interval: robust to a dropped frame.
  std::vector<double> dts;
  for (int f = 1; f < frames; ++f) dts.push_back(t.times_s[f] - t.times_s[f - 1]);
  if (!dts.empty()) {
    std::nth_element(dts.begin(), dts.begin() + dts.size() / 2, dts.end());
    t.frame_rate_hz = 1.0 / dts[dts.size() / 2];
  }
  return t;
}

Trajectory OnlineEstimator::window() const {
  std::lock_guard<std::mutex> lock(frames_mutex_);
  return snapshotLocked();
}

InputCounters OnlineEstimator::counters() const {
  std::lock_guard<std::mutex> lock(frames_mutex_);
  return counters_;
}

std::vector<std::string> OnlineEstimator::particleNames() const {
  std::lock_guard<std::mutex> lock(frames_mutex_);
  return names_;
}

double OnlineEstimator::frameRateHz() const {
  std::lock_guard<std::mutex> lock(model_mutex_);
  return model_.frame_rate_hz;
}

Trajectory OnlineEstimator::rollout(const Model& model, const Trajectory& window, int frames) {
  Trajectory empty;
  const int n = window.numMarkers();
  if (window.numFrames() < 2 || frames < 1 || n != static_cast<int>(model.particles.size()))
    return empty;
  const double rate_hz = model.frame_rate_hz > 0 ? model.frame_rate_hz : window.frame_rate_hz;
  if (!(rate_hz > 0)) return empty;
  Observations obs;
  bool any_hidden = false;
  for (int i = 0; i < n; ++i)
    any_hidden = any_hidden || window.isOccluded(0, i) || window.isOccluded(1, i);
  if (any_hidden) {
    try {
      obs = prepareObservations(model, window);
    } catch (const InputError&) {
      return empty;
    }
  }
  Model start = model;
  for (int i = 0; i < n; ++i) {
    Particle& p = start.particles[i];
    if (p.fixed) {  // held: at its marker when seen, else where the model puts it (an anchor)
      if (!window.isOccluded(1, i)) p.position_m = window.position(1, i);
      p.velocity_mps.setZero();
      continue;
    }
    Eigen::Vector3d x0 = window.position(0, i), x1 = window.position(1, i);
    if (window.isOccluded(0, i) && !fillFromNeighbours(obs, model, 0, i, &x0, true)) return empty;
    if (window.isOccluded(1, i) && !fillFromNeighbours(obs, model, 1, i, &x1, true)) return empty;
    p.position_m = x1;
    p.velocity_mps = (x1 - x0) * rate_hz;
  }
  return simulateTrajectory(start, frames, rate_hz);
}

bool OnlineEstimator::update() {
  std::lock_guard<std::mutex> lock(update_mutex_);
  Trajectory window_data;
  uint64_t frames_added = 0;
  {
    std::lock_guard<std::mutex> frames_lock(frames_mutex_);
    if (static_cast<int>(times_s_.size()) < options_.min_frames) return false;
    window_data = snapshotLocked();
    frames_added = frames_added_;
  }
  Model model;
  uint64_t version = 0;
  {
    std::lock_guard<std::mutex> model_lock(model_mutex_);
    model = model_;
    version = model_version_;
  }
  const auto began = std::chrono::steady_clock::now();
  reapRetiredRefinements();
  if (version != es_version_) {  // reset() or replaceModel() since the last update
    retireRefinement();  // cancelled, never waited for: it ends on its own
    es_.reset();
    last_refine_generation_ = -1;
    output_error_ = OutputErrorResult();
    held_updates_ = 0;
  }
  es_version_ = version;
  if (!options_.estimate_values) return holdModelValues(model, window_data, frames_added, version);
  if (freeParameters(model).empty()) return false;  // waiting for a structure (replaceModel)
  // Live streams carry their own clock: the model's rate wins only when it states one.
  if (!(model.frame_rate_hz > 0.0)) model.frame_rate_hz = window_data.frame_rate_hz;
  auto cost = std::make_shared<ShortTermCost>(model, window_data);
  if (cost->termCount() == 0) return false;
  if (!es_) {
    es_ = makeSearch(model, window_data, options_);
    use_output_error_ = options_.cost == CostChoice::kOutputError ||
                        (options_.cost == CostChoice::kAuto &&
                         estimateMarkerNoise(window_data) >= options_.auto_noise_threshold_m);
  }
  es_->setCost(cost);  // re-evaluates the living population on the new window
  window_start_time_s_ = window_data.times_s.front();
  window_end_time_s_ = window_data.times_s.back();
  handOverRefinement();
  // Other islands' migrants compete on this window; a population not drawn yet takes them
  // after its first generation.
  bool migrants_applied = !es_->population().empty();
  if (migrants_applied) applyMigrants(version);
  // The generations that fit in the budget (at least one), at the pace of the ones done.
  const auto deadline = began + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                    std::chrono::duration<double>(options_.update_budget_s));
  for (int g = 0; g < options_.generations_per_update; ++g) {
    if (modelChangedSince(version)) return false;  // stale: the next update starts afresh
    const auto before = std::chrono::steady_clock::now();
    es_->step();
    if (!migrants_applied) {
      applyMigrants(version);
      migrants_applied = true;
    }
    const auto after = std::chrono::steady_clock::now();
    if (after + (after - before) > deadline) break;
  }
  if (modelChangedSince(version)) return false;
  const EsOptions& es_options = options_.es;
  if (!refinement_ && es_options.refine_period > 0 &&
      es_->generation() >= es_options.refine_start_generation &&
      (last_refine_generation_ < 0 ||
       es_->generation() - last_refine_generation_ >= es_options.refine_period))
    startRefinement(cost, model, window_data);

  Estimate e = makeEstimate(model, window_data);
  // A reset() or replaceModel() during this update makes its result stale: drop it.
  std::lock_guard<std::mutex> model_lock(model_mutex_);
  if (model_version_ != version) return false;
  std::lock_guard<std::mutex> estimate_lock(estimate_mutex_);
  estimate_ = std::move(e);
  return true;
}

/// The estimate the update just made: the population's best on `window_data`, or the last
/// output-error fit's values when that estimator publishes, judged for stability on the window.
Estimate OnlineEstimator::makeEstimate(const Model& model, const Trajectory& window_data) const {
  Estimate e;
  e.valid = true;
  e.generation = static_cast<uint32_t>(es_->generation());
  e.evaluations = es_->evaluations();
  e.global_cost = es_->best().cost;
  e.window_frames = static_cast<uint32_t>(window_data.numFrames());
  e.window_start_time_s = window_data.times_s.front();
  e.window_end_time_s = window_data.times_s.back();
  for (const Gene& g : es_->space().genes()) e.parameter_names.push_back(g.ref.name);
  e.values = es_->bestValues();
  e.local_costs = es_->best().local_costs;
  e.refinements = refinements_done_;
  e.last_refine_status = last_refine_status_;
  e.estimator = Estimator::kShortTerm;
  e.output_error_rejections = output_error_rejections_;
  std::vector<double> genes = es_->best().genes;
  const bool from_output_error = use_output_error_ && output_error_.ran;
  e.std_devs = eliteStdDevs(*es_, e.values.size());
  if (from_output_error) {
    // The published values are the output-error fit's, with its std (from its Jacobian).
    e.estimator = Estimator::kOutputError;
    e.values = output_error_.values;
    e.std_devs = output_error_.std_devs;
    e.global_cost = output_error_.observation_cost_m2;
    e.noise_std_m = output_error_.noise_std_m;
    genes = output_error_.genes;
  }
  e.parameter_flags = parameterFlags(es_->space(), genes, from_output_error ? &output_error_.unidentifiable : nullptr);
  Model best = model;
  setValues(best, es_->space().refs(), e.values);
  e.stable = staysBounded(best, window_data,
                          static_cast<int>(options_.stability_rollout_factor * window_data.numFrames()));
  return e;
}

bool OnlineEstimator::holdModelValues(Model model, const Trajectory& window, uint64_t frames_added,
                                      uint64_t version) {
  if (held_updates_ > 0 && frames_added == held_frames_) return false;  // nothing new to judge
  if (!(model.frame_rate_hz > 0.0)) model.frame_rate_hz = window.frame_rate_hz;
  Estimate e;
  e.valid = true;
  e.generation = held_updates_ + 1;  // counts the held estimates: each one is published
  e.window_frames = static_cast<uint32_t>(window.numFrames());
  e.window_start_time_s = window.times_s.front();
  e.window_end_time_s = window.times_s.back();
  for (const ParamRef& ref : freeParameters(model)) {
    e.parameter_names.push_back(ref.name);
    e.values.push_back(paramOf(model, ref).value);
  }
  e.std_devs.assign(e.values.size(), std::numeric_limits<double>::quiet_NaN());  // not estimated
  const ShortTermCost cost(model, window);
  if (cost.termCount() > 0) {
    std::vector<double> values;
    for (const ParamRef& ref : cost.freeParameters()) values.push_back(paramOf(model, ref).value);
    e.global_cost = cost.evaluate(values, &e.local_costs);
    e.evaluations = 1;
  }
  e.stable = staysBounded(model, window,
                          static_cast<int>(options_.stability_rollout_factor * window.numFrames()));
  std::lock_guard<std::mutex> model_lock(model_mutex_);
  if (model_version_ != version) return false;
  held_frames_ = frames_added;
  ++held_updates_;
  std::lock_guard<std::mutex> estimate_lock(estimate_mutex_);
  estimate_ = std::move(e);
  return true;
}

bool OnlineEstimator::isClockJump(double step_s, double interval_s) {
  if (step_s >= 0.0) return step_s > std::max(kClockJumpS, kClockJumpFrameIntervals * interval_s);
  return -step_s > (interval_s > 0.0 ? kClockJumpFrameIntervals * interval_s : kClockJumpS);
}

bool OnlineEstimator::modelChangedSince(uint64_t version) const {
  std::lock_guard<std::mutex> lock(model_mutex_);
  return model_version_ != version;
}

Estimate OnlineEstimator::estimate() const {
  std::lock_guard<std::mutex> lock(estimate_mutex_);
  return estimate_;
}

Model OnlineEstimator::currentModel() const {
  Model model;
  Estimate e;
  {
    std::lock_guard<std::mutex> lock(model_mutex_);  // the estimate belongs to this model
    model = model_;
    e = estimate();
  }
  if (e.valid) setValues(model, freeParameters(model), e.values);
  return model;
}

void OnlineEstimator::reset(bool clear_window) {
  {
    std::lock_guard<std::mutex> lock(model_mutex_);
    ++model_version_;  // the next update() starts a new population
    std::lock_guard<std::mutex> estimate_lock(estimate_mutex_);
    estimate_ = Estimate();
  }
  if (clear_window) {
    std::lock_guard<std::mutex> lock(frames_mutex_);
    times_s_.clear();
    positions_.clear();
    occluded_.clear();
  }
}

void OnlineEstimator::replaceModel(const Model& model) {
  checkModel(model, options_);
  std::vector<std::string> names;
  for (const Particle& p : model.particles) names.push_back(p.name);
  std::lock_guard<std::mutex> lock(model_mutex_);
  {
    std::lock_guard<std::mutex> frames_lock(frames_mutex_);
    if (names != names_) {  // other markers: the window no longer fits
      times_s_.clear();
      positions_.clear();
      occluded_.clear();
      names_ = names;
    }
    fixed_ = fixedFlags(model);
  }
  model_ = model;
  ++model_version_;  // the next update() starts a new population on this model
  std::lock_guard<std::mutex> estimate_lock(estimate_mutex_);
  estimate_ = Estimate();
}

}  // namespace mme
