#include "sensor_muscle_fit.h"

#include <cmath>
#include <cstdio>
#include <string>
#include <utility>

#include "motion_model_estimation/core/error.h"
#include "muscle_model_build.h"

namespace mme::sensor_muscles {

int validationStart(int frames, const SensorMuscleOptions& o) {
  const int validation_start = static_cast<int>(std::floor((1.0 - o.validation_fraction) * frames));
  if (validation_start < 4 || frames - validation_start < o.horizon_frames + 1)
    throw InputError("sensor muscles: " + std::to_string(frames) + " frames are too few to hold out " +
                     "a validation of " + std::to_string(o.horizon_frames) + " frames ahead");
  return validation_start;
}

FitRun::FitRun(const Model& passive_model, const Trajectory& data_frames, const std::vector<char>& anchor,
               const SensorMuscleOptions& options, Budget& fit_budget, int first_validation_frame)
    : passive(passive_model), data(data_frames), o(options), budget(fit_budget),
      frames(data_frames.numFrames()), validation_start(first_validation_frame),
      layout(chooseLayoutWithinUnknowns(passive_model, data_frames, anchor, options)),
      equations(passive_model, data_frames, layout), rollouts(equations),
      judge(data_frames, options.horizon_frames, first_validation_frame),
      pool(options.threads > 1 ? std::make_unique<ThreadPool>(options.threads) : nullptr),
      constraints(equations.signConstraints(options.nonnegative_own_spring)) {
  result.sensors = static_cast<int>(layout.sensors.size());
  result.muscles = static_cast<int>(layout.muscles.size());
  result.unknowns = unknownsOf(layout);
  result.selected_muscles = result.muscles;
  result.selected_sensors = result.sensors;
  result.selected_parameters = result.unknowns - constraints.held_at_zero.size();
}

Model FitRun::build(const Eigen::VectorXd& theta, int t_end, double activation_time_s) const {
  return buildMuscleModel(equations, theta, o.gain_margin, t_end, activation_time_s, &selection);
}

bool FitRun::solve(const System& sys, double ridge, Eigen::VectorXd* theta, double reference_diagonal) const {
  return solveRidge(sys, ridge, constraints, theta, reference_diagonal);
}

int FitRun::addCandidate(const SensorMuscleCandidate& c, Eigen::VectorXd theta) {
  thetas.push_back(std::move(theta));
  result.candidates.push_back(c);
  const int index = static_cast<int>(result.candidates.size()) - 1;
  if (candidateBeats(c, best < 0 ? nullptr : &result.candidates[best])) best = index;
  return index;
}

bool candidateBeats(const SensorMuscleCandidate& c, const SensorMuscleCandidate* best) {
  return std::isfinite(c.validation_rms_m) &&
         (!best || (c.bounded && !best->bounded) ||
          (c.bounded == best->bounded && c.validation_rms_m < best->validation_rms_m));
}

SensorMuscleResult fitSensorMuscles(const Model& passive, const Trajectory& data,
                                    const std::vector<char>& anchor, const SensorMuscleOptions& o,
                                    Budget& budget) {
  FitRun run(passive, data, anchor, o, budget, validationStart(data.numFrames(), o));
  char line[200];
  std::snprintf(line, sizeof(line), "sensor muscles: %d sensors, %d muscles, %zu unknowns",
                run.result.sensors, run.result.muscles, run.result.unknowns);
  say(o, line);
  run.judge.judge(passive, &run.result.passive_rms_m, &run.result.constant_velocity_rms_m, nullptr);
  // With a time limit (Budget): once spent, no further candidate after the first that gave a
  // model, no rollout round and no activation time constant; the final refits are not cut (a
  // refit that leaves the data is common, and the next candidate's is what gives a model).
  judgeOneStepCandidates(run);
  selectGroups(run);
  judgeRolloutRounds(run);
  refitOnEveryFrame(run);
  return std::move(run.result);
}

}  // namespace mme::sensor_muscles
