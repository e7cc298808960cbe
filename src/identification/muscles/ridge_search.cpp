// Step 1 of a layout's fit (sensor_muscle_fit.h): the one-step candidates. Each window's
// equations are gathered on the frames before the validation frames, solved at every candidate
// ridge (the largest first, so that a time limit leaves the steadier ones judged) and judged on
// the validation frames.
#include <cmath>
#include <cstdio>
#include <utility>

#include "motion_model_estimation/core/error.h"
#include "sensor_muscle_fit.h"

namespace mme::sensor_muscles {

SensorMuscleCandidate judgeRidge(const FitRun& run, const System& sys, int window, double ridge,
                                 Eigen::VectorXd* theta) {
  SensorMuscleCandidate c;
  c.window_frames = window;
  c.ridge = ridge;
  if (run.solve(sys, ridge, theta)) {
    run.judge.judgeBuilt([&] { return run.build(*theta, run.validation_start); }, &c.validation_rms_m,
                         &c.bounded);
  } else {
    theta->resize(0);
  }
  if (!std::isfinite(c.validation_rms_m)) c.bounded = false;
  return c;
}

void sayCandidate(const FitRun& run, const SensorMuscleCandidate& c) {
  char line[240];
  std::snprintf(line, sizeof(line), "sensor muscles: window %d, ridge %.0e: %d frames ahead on "
                "the last %d frames %.2f mm (passive %.2f mm, constant velocity %.2f mm), rollout %s",
                c.window_frames, c.ridge, run.o.horizon_frames, run.validationFrames(),
                1e3 * c.validation_rms_m,
                1e3 * run.result.passive_rms_m, 1e3 * run.result.constant_velocity_rms_m,
                c.bounded ? "bounded" : "unbounded");
  say(run.o, line);
}

namespace {

/// The candidates of one window; false when the window gives no equation.
bool judgeWindow(FitRun& run, int window) {
  System sys;
  run.equations.accumulate(window, 0, run.validation_start - window, &sys, run.pool.get());
  if (sys.rows == 0) return false;
  const int window_first = static_cast<int>(run.result.candidates.size());
  for (double ridge : run.o.ridges) {
    if (run.best >= 0 && run.budget.stops(run.o, "further ridge")) break;
    Eigen::VectorXd theta;
    const SensorMuscleCandidate c = judgeRidge(run, sys, window, ridge, &theta);
    sayCandidate(run, c);
    run.addCandidate(c, std::move(theta));
  }
  if (run.best >= window_first) run.best_sys = std::move(sys);
  return true;
}

}  // namespace

void judgeOneStepCandidates(FitRun& run) {
  bool any_rows = false;
  for (int window : run.o.windows_frames) {
    if (run.best >= 0 && run.budget.stops(run.o, "further window")) break;
    if (judgeWindow(run, window)) any_rows = true;
  }
  if (!any_rows)
    throw InputError("sensor muscles: no frame gives an equation before the validation frames "
                     "(too short, or gaps everywhere)");
  if (run.best < 0) throw InputError("sensor muscles: no candidate gave a model (every solve failed)");
}

}  // namespace mme::sensor_muscles
