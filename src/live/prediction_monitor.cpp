#include "motion_model_estimation/live/prediction_monitor.h"

#include <cstdio>
#include <exception>
#include <utility>

#include "motion_model_estimation/core/error.h"

namespace mme {

std::string predictionCaption(const PredictionReport& report, int horizon, int muscles) {
  double rms_mm[3] = {-1.0, -1.0, -1.0};
  for (const PredictionError& row : report.rows) {
    const int k = static_cast<int>(row.predictor);
    if (row.horizon == horizon && row.samples > 0 && k < 3) rms_mm[k] = 1e3 * row.rms_m;
  }
  if (rms_mm[0] < 0.0 || rms_mm[1] < 0.0 || rms_mm[2] < 0.0) return "";
  const std::string what = muscles > 0 ? std::to_string(muscles) + " muscles" : "passive";
  char text[200];
  std::snprintf(text, sizeof(text),
                "%d frames ahead: model %.1f mm (%s), constant velocity %.1f, constant "
                "acceleration %.1f mm",
                horizon, rms_mm[0], what.c_str(), rms_mm[1], rms_mm[2]);
  return text;
}

PredictionMonitor::PredictionMonitor(std::vector<int> horizons, double period_s)
    : horizons_(std::move(horizons)), period_s_(period_s) {
  if (horizons_.empty()) throw InputError("prediction monitor: no horizon");
  for (int k : horizons_)
    if (k < 1) throw InputError("prediction monitor: horizon " + std::to_string(k) + " < 1");
  if (!(period_s_ > 0.0)) throw InputError("prediction monitor: period must be > 0 s");
}

bool PredictionMonitor::due(double now_s) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return !tried_ || now_s - last_try_s_ >= period_s_;
}

bool PredictionMonitor::evaluate(double now_s, const Model& model, const Trajectory& window) {
  std::optional<PredictionReport> report;
  std::string error;
  try {
    report = evaluatePredictions(model, window, horizons_);
  } catch (const std::exception& e) {  // a diagnostic: any failure is reported, never thrown
    error = e.what();
  }
  std::lock_guard<std::mutex> lock(mutex_);
  tried_ = true;
  last_try_s_ = now_s;
  report_ = std::move(report);
  error_ = std::move(error);
  return report_.has_value();
}

std::optional<PredictionReport> PredictionMonitor::report() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return report_;
}

std::string PredictionMonitor::lastError() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return error_;
}

}  // namespace mme
