// Step 1b of a layout's fit (sensor_muscle_fit.h): the grouped selection of muscles and sensors
// (group_selection.h) on the best one-step candidate's equations at its ridge, judged on the
// validation frames against the fit without it; adopted, it holds the dropped muscles and
// sensors at 0 in every later fit and leaves them out of every model built.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>
#include <vector>

#include "sensor_muscle_fit.h"

namespace mme::sensor_muscles {

namespace {

/// After a selection is adopted: the one-step candidates of `window` fitted and judged again
/// with it (their figures are then the selected model's); those of another window, whose
/// equations are no longer at hand, can no longer be chosen. The best is found again.
void rejudgeOneStep(FitRun& run, const System& sys, int window, int selected_index,
                    const SensorMuscleCandidate& selected, const Eigen::VectorXd& selected_theta) {
  std::vector<SensorMuscleCandidate>& candidates = run.result.candidates;
  for (int k = 0; k < static_cast<int>(candidates.size()); ++k) {
    SensorMuscleCandidate& c = candidates[k];
    if (k == selected_index) {
      c = selected;
      run.thetas[k] = selected_theta;
    } else if (c.window_frames != window) {
      c.validation_rms_m = std::nan("");
      c.bounded = false;
      run.thetas[k].resize(0);
    } else {
      c = judgeRidge(run, sys, window, c.ridge, &run.thetas[k]);
      sayCandidate(run, c);
    }
  }
  run.best = -1;
  for (int k = 0; k < static_cast<int>(candidates.size()); ++k)
    if (candidateBeats(candidates[k], run.best < 0 ? nullptr : &candidates[run.best])) run.best = k;
}

void saySelection(const FitRun& run, const GroupSelection& s, const EliminationReport& report, double rms_m,
                  bool bounded, bool adopted) {
  const SensorMuscleCandidate& best = run.result.candidates[run.best];
  char line[400];
  std::snprintf(line, sizeof(line), "sensor muscles: grouped selection at ridge %.0e (%d solves, price "
                "%.3g per parameter): %d of %d muscles, %d of %d sensors, %d of %zu parameters on "
                "%zu samples; %d frames ahead %.2f mm (rollout %s) against %.2f mm without: %s",
                best.ridge, report.solves, report.price_per_param,
                run.result.muscles - static_cast<int>(std::count(s.muscle_dropped.begin(), s.muscle_dropped.end(), 1)),
                run.result.muscles,
                run.result.sensors - static_cast<int>(std::count(s.sensor_dropped.begin(), s.sensor_dropped.end(), 1)),
                run.result.sensors, s.parameters, run.result.selected_parameters, run.best_sys.rows,
                run.o.horizon_frames, 1e3 * rms_m, bounded ? "bounded" : "unbounded", 1e3 * best.validation_rms_m,
                adopted ? "adopted" : "not adopted");
  say(run.o, line);
}

}  // namespace

void selectGroups(FitRun& run) {
  const SensorMuscleOptions& o = run.o;
  if (!o.select_groups || run.best < 0 || run.thetas[run.best].size() == 0) return;
  if (run.budget.stops(o, "grouped selection")) return;
  const SensorMuscleCandidate best = run.result.candidates[run.best];
  Eigen::VectorXd theta = run.thetas[run.best];
  EliminationReport report;
  GroupSelection selection = eliminateGroups(run.best_sys, best.ridge, run.constraints, run.result.sensors,
                                             o.selection_max_solves, &theta, &report);
  if (selection.groups_dropped() == 0) {
    say(o, "sensor muscles: grouped selection: every muscle and sensor pays for its parameters");
    return;
  }
  // The selected fit judged as a candidate of the same window and ridge, its model without the
  // dropped muscles and sensors.
  std::swap(run.selection, selection);
  SensorMuscleCandidate c = best;
  c.validation_rms_m = std::nan("");
  run.judge.judgeBuilt([&] { return run.build(theta, run.validation_start); }, &c.validation_rms_m, &c.bounded);
  if (!std::isfinite(c.validation_rms_m)) c.bounded = false;
  const bool adopted = (c.bounded || !best.bounded) && std::isfinite(c.validation_rms_m) &&
                       c.validation_rms_m <= (1.0 + o.selection_tolerance) * best.validation_rms_m;
  if (!adopted) std::swap(run.selection, selection);
  saySelection(run, adopted ? run.selection : selection, report, c.validation_rms_m, c.bounded, adopted);
  if (!adopted) return;
  const std::vector<int> dropped = droppedColumns(run.selection, run.result.sensors, run.equations.perMuscle());
  std::vector<int>& held = run.constraints.held_at_zero;
  held.insert(held.end(), dropped.begin(), dropped.end());
  std::sort(held.begin(), held.end());
  held.erase(std::unique(held.begin(), held.end()), held.end());
  run.result.selected_muscles =
      run.result.muscles - static_cast<int>(std::count(run.selection.muscle_dropped.begin(),
                                                       run.selection.muscle_dropped.end(), 1));
  run.result.selected_sensors =
      run.result.sensors - static_cast<int>(std::count(run.selection.sensor_dropped.begin(),
                                                       run.selection.sensor_dropped.end(), 1));
  run.result.selected_parameters = static_cast<size_t>(run.selection.parameters);
  rejudgeOneStep(run, run.best_sys, best.window_frames, run.best, c, theta);
}

}  // namespace mme::sensor_muscles
