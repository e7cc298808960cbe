#include "motion_model_estimation/live/muscle_job.h"

#include <chrono>
#include <cmath>
#include <exception>
#include <utility>

#include "motion_model_estimation/identification/estimators/prediction_error.h"
#include "motion_model_estimation/live/muscle_refit.h"

namespace mme {

namespace {

/// Thrown from the fit's progress callback to stop it at its next step on shutdown.
struct FitCancelled {};

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// The fitted model with `passive`'s free parameters free again (the fit writes every parameter
/// fixed; live, the estimator goes on estimating the passive ones). The fit appends its types
/// and particles, so the passive ones keep their indices. False when it did not.
bool keepPassiveFree(const Model& passive, Model* fitted) {
  if (fitted->bond_types.size() < passive.bond_types.size() ||
      fitted->particles.size() < passive.particles.size())
    return false;
  for (size_t k = 0; k < passive.bond_types.size(); ++k)
    if (fitted->bond_types[k].name != passive.bond_types[k].name) return false;
  for (size_t i = 0; i < passive.particles.size(); ++i)
    if (fitted->particles[i].name != passive.particles[i].name) return false;
  for (const ParamRef& ref : freeParameters(passive)) {
    const double value = paramOf(*fitted, ref).value;
    paramOf(*fitted, ref) = paramOf(passive, ref);
    paramOf(*fitted, ref).value = value;
  }
  return true;
}

/// `muscles` (a passive model with sensor muscles appended) with `passive`'s free values; false
/// when `passive` is not the model they were laid on (its types and particles not a prefix of
/// theirs, or other free parameters).
bool layOn(const Model& passive, Model* muscles) {
  if (muscles->bond_types.size() < passive.bond_types.size() ||
      muscles->particles.size() < passive.particles.size())
    return false;
  for (size_t k = 0; k < passive.bond_types.size(); ++k)
    if (muscles->bond_types[k].name != passive.bond_types[k].name) return false;
  for (size_t i = 0; i < passive.particles.size(); ++i)
    if (muscles->particles[i].name != passive.particles[i].name) return false;
  const std::vector<ParamRef> refs = freeParameters(passive);
  const std::vector<ParamRef> theirs = freeParameters(*muscles);
  if (refs.size() != theirs.size()) return false;
  for (size_t k = 0; k < refs.size(); ++k) {
    if (refs[k].name != theirs[k].name) return false;
    paramOf(*muscles, refs[k]) = paramOf(passive, refs[k]);
  }
  muscles->frame_rate_hz = passive.frame_rate_hz;
  return true;
}

double modelRmsM(const Model& model, const Trajectory& window, int horizon) {
  try {
    const PredictionReport report = evaluatePredictions(model, window, {horizon}, 1.0);
    for (const PredictionError& row : report.rows)
      if (row.predictor == Predictor::kModel && row.samples > 0) return row.rms_m;
  } catch (const std::exception&) {  // a window it cannot judge: no figure
  }
  return std::nan("");
}

}  // namespace

SensorMuscleOptions liveSensorMuscleOptions(int sensors, double max_time_s) {
  SensorMuscleOptions o;
  o.sensors = sensors;
  o.anchors = true;
  o.anchors_by_validation = false;
  o.anchor_stiffness = AnchorStiffness::kAuto;
  o.ridges = {3.0, 1.0, 0.3, 0.1};
  o.rollout_rounds = 0;
  o.activation_times_frames.clear();
  o.max_time_s = max_time_s;
  return o;
}

std::string validateOptions(const MuscleJobOptions& o) {
  if (o.fit.sensors < 1 || o.fit.sensors > 16) return "muscle_sensors must be in [1, 16]";
  if (!(o.fit.max_time_s >= 0.0) || !std::isfinite(o.fit.max_time_s))
    return "muscles_max_time_sec must be >= 0 (0 = no limit)";
  if (o.min_frames < 35) return "muscles need a window of at least 35 frames";
  if (!(o.refit_period_s >= 0.0) || !std::isfinite(o.refit_period_s))
    return "muscle_refit_period_sec must be >= 0 (0 = no refit)";
  if (!(o.retry_after_s > 0.0) || !std::isfinite(o.retry_after_s)) return "muscle retry period must be > 0";
  if (o.horizon_frames < 1) return "muscle refit horizon must be >= 1";
  return "";
}

MuscleJob::MuscleJob(MuscleJobOptions options) : options_(std::move(options)) {}

void MuscleJob::say(const std::string& line) const {
  if (options_.say) options_.say(line);
}

std::optional<Model> MuscleJob::fitIfDue(const Model& passive, const Trajectory& window, double now_s) {
  uint64_t version = 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (cancelled_ || state_ == State::kFitted || state_ == State::kFitting) return std::nullopt;
    if (window.numFrames() < options_.min_frames || now_s < next_try_s_) return std::nullopt;
    state_ = State::kFitting;
    version = version_;
  }
  SensorMuscleOptions o = options_.fit;
  o.progress = [this](const std::string& line) {
    if (cancelled_) throw FitCancelled();
    say(line);
  };
  const auto start = std::chrono::steady_clock::now();
  State state = State::kFailed;
  std::string message;
  std::optional<Model> model;
  int muscles = 0;
  double ridge = 1.0;
  // A live model may leave its rate to the stream (OnlineEstimator takes the window's then): so
  // does the fit, and the model handed back keeps the passive model's own setting.
  Model rated = passive;
  if (!(rated.frame_rate_hz > 0.0)) rated.frame_rate_hz = window.frame_rate_hz;
  try {
    SensorMuscleResult r = addSensorMuscles(rated, window, o);
    r.model.frame_rate_hz = passive.frame_rate_hz;
    if (!r.better_than_passive) {
      state = State::kNotKept;
      message = r.not_kept_because;
    } else if (!keepPassiveFree(passive, &r.model)) {
      message = "the fitted model does not extend the passive one";
    } else {
      state = State::kFitted;
      muscles = r.muscles;
      ridge = r.ridge;
      char line[240];
      std::snprintf(line, sizeof(line),
                    "%d muscles, %d sensors, %zu unknowns on %d frames; validation %.2f mm %d frames "
                    "ahead (passive %.2f mm, constant velocity %.2f mm)%s",
                    r.muscles, r.sensors, r.unknowns, window.numFrames(), 1e3 * r.validation_rms_m,
                    o.horizon_frames, 1e3 * r.passive_rms_m, 1e3 * r.constant_velocity_rms_m,
                    r.stopped_by_time ? " (cut by the time limit)" : "");
      message = line;
      model = std::move(r.model);
    }
  } catch (const FitCancelled&) {
    message = "cancelled";
  } catch (const std::exception& e) {
    message = e.what();
  }
  std::lock_guard<std::mutex> lock(mutex_);
  last_fit_s_ = secondsSince(start);
  if (version != version_ || cancelled_) {  // forgotten or cancelled meanwhile: stale
    state_ = State::kWaiting;
    return std::nullopt;
  }
  state_ = state;
  message_ = message;
  if (state != State::kFitted) {
    next_try_s_ = now_s + last_fit_s_ + options_.retry_after_s;
    return std::nullopt;
  }
  muscles_ = muscles;
  ridge_ = ridge;
  ++fits_;
  next_refit_s_ = now_s + last_fit_s_ + options_.refit_period_s;
  model_ = model;
  return model;
}

Trajectory MuscleJob::asModelParticles(const Trajectory& window, const Model& model) {
  std::vector<std::string> names;
  for (const Particle& p : model.particles) names.push_back(p.name);
  if (names == window.marker_names) return window;
  return remapMarkers(window, names, nullptr);
}

std::optional<Model> MuscleJob::withMuscles(const Model& passive) const {
  std::optional<Model> model;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    model = model_;
  }
  if (!model || !layOn(passive, &*model)) return std::nullopt;
  return model;
}

std::optional<Model> MuscleJob::refitIfDue(const Model& passive, const Trajectory& window, double now_s) {
  uint64_t version = 0;
  double ridge = 1.0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (cancelled_ || state_ != State::kFitted || !(options_.refit_period_s > 0.0)) return std::nullopt;
    if (now_s < next_refit_s_) return std::nullopt;
    version = version_;
    ridge = ridge_;
  }
  const std::optional<Model> current = withMuscles(passive);
  if (!current) return std::nullopt;
  const auto start = std::chrono::steady_clock::now();
  Model rated = *current;  // the stream's rate where the model leaves it open (see fitIfDue)
  if (!(rated.frame_rate_hz > 0.0)) rated.frame_rate_hz = window.frame_rate_hz;
  const Trajectory data = asModelParticles(window, rated);
  MuscleRefitResult r = refitMuscleActivations(rated, data, ridge, options_.fit.gain_margin);
  const bool adopted = r.ok && judgeRefit(rated, r.model, data);
  r.model.frame_rate_hz = passive.frame_rate_hz;
  std::lock_guard<std::mutex> lock(mutex_);
  ++refits_;
  last_refit_ms_ = 1e3 * secondsSince(start);
  // The period runs from the end of a refit: the refits take at most their share of a core.
  next_refit_s_ = now_s + last_refit_ms_ / 1e3 + options_.refit_period_s;
  if (version != version_ || !adopted) return std::nullopt;
  ++refits_adopted_;
  model_ = r.model;
  return std::move(r.model);
}

bool MuscleJob::judgeRefit(const Model& current, const Model& refitted, const Trajectory& window) const {
  const double before_m = modelRmsM(current, window, options_.horizon_frames);
  const double after_m = modelRmsM(refitted, window, options_.horizon_frames);
  if (!std::isfinite(after_m)) return false;
  return !std::isfinite(before_m) || after_m <= before_m;
}

void MuscleJob::forget() {
  std::lock_guard<std::mutex> lock(mutex_);
  ++version_;
  state_ = State::kWaiting;
  muscles_ = 0;
  model_.reset();
  next_try_s_ = -1e300;
}

void MuscleJob::cancel() { cancelled_ = true; }

MuscleJob::State MuscleJob::state() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return state_;
}

std::string MuscleJob::status() const {
  switch (state()) {
    case State::kWaiting: return "waiting";
    case State::kFitting: return "fitting";
    case State::kFitted: return "fitted";
    case State::kNotKept: return "not_kept";
    case State::kFailed: return "failed";
  }
  return "?";
}

std::string MuscleJob::lastMessage() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return message_;
}

int MuscleJob::muscles() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return muscles_;
}

uint32_t MuscleJob::fits() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return fits_;
}

uint32_t MuscleJob::refits() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return refits_;
}

uint32_t MuscleJob::refitsAdopted() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return refits_adopted_;
}

double MuscleJob::lastRefitMs() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return last_refit_ms_;
}

double MuscleJob::lastFitS() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return last_fit_s_;
}

}  // namespace mme
