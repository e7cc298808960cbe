// Step 2 of a layout's fit (sensor_muscle_fit.h): rounds of rollout equations (Data as
// Demonstrator). Each round runs the current fit open loop from frames over the fitted data,
// adds the equations written where its predictions went, and solves again; each round is a
// candidate judged on the validation frames like the one-step ones.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "sensor_muscle_fit.h"

namespace mme::sensor_muscles {

namespace {

/// The window-1 candidate with the lowest finite validation error (-1: none).
int lowestErrorCandidate(const std::vector<SensorMuscleCandidate>& candidates) {
  int lowest = -1;
  for (int k = 0; k < static_cast<int>(candidates.size()); ++k) {
    const SensorMuscleCandidate& c = candidates[k];
    if (c.window_frames == 1 && std::isfinite(c.validation_rms_m) &&
        (lowest < 0 || c.validation_rms_m < candidates[lowest].validation_rms_m))
      lowest = k;
  }
  return lowest;
}

/// The window-1 candidates with a finite validation error and a ridge below `ridge`, the
/// largest ridge first.
std::vector<int> lowerRidgeCandidates(const std::vector<SensorMuscleCandidate>& candidates, double ridge) {
  std::vector<int> lower;
  for (int k = 0; k < static_cast<int>(candidates.size()); ++k) {
    const SensorMuscleCandidate& c = candidates[k];
    if (c.window_frames == 1 && c.ridge < ridge && std::isfinite(c.validation_rms_m)) lower.push_back(k);
  }
  std::stable_sort(lower.begin(), lower.end(),
                   [&](int a, int b) { return candidates[a].ridge > candidates[b].ridge; });
  return lower;
}

/// The candidates the rounds start from: the best one-step candidate (when of window 1), the one
/// with the lowest validation error when its ridge differs (the rollout equations can bound
/// it), and the next rollout_lower_ridges ridges below the best's (the rollout rows hold the fit
/// near the data as the ridge does, so a round's best ridge can lie below the one-step fit's).
std::vector<int> roundStarts(const FitRun& run) {
  const std::vector<SensorMuscleCandidate>& candidates = run.result.candidates;
  std::vector<int> starts;
  if (run.o.rollout_rounds <= 0 || candidates[run.best].window_frames != 1) return starts;
  starts.push_back(run.best);
  const int lowest = lowestErrorCandidate(candidates);
  if (lowest >= 0 && candidates[lowest].ridge != candidates[run.best].ridge) starts.push_back(lowest);
  const std::vector<int> lower = lowerRidgeCandidates(candidates, candidates[run.best].ridge);
  for (int k = 0; k < static_cast<int>(lower.size()) && k < run.o.rollout_lower_ridges; ++k)
    if (std::find(starts.begin(), starts.end(), lower[k]) == starts.end()) starts.push_back(lower[k]);
  return starts;
}

/// A round's fit as a candidate: `start` after `round` rounds, judged on the validation frames.
void addRoundCandidate(FitRun& run, const SensorMuscleCandidate& start, int round, const Eigen::VectorXd& theta,
                       const RolloutCount& count) {
  SensorMuscleCandidate c = start;
  c.rollout_rounds = round;
  c.validation_rms_m = std::nan("");
  run.judge.judgeBuilt([&] { return run.build(theta, run.validation_start); }, &c.validation_rms_m, &c.bounded);
  if (!std::isfinite(c.validation_rms_m)) c.bounded = false;
  c.rollout_starts = count.starts;
  char line[240];
  std::snprintf(line, sizeof(line), "sensor muscles: ridge %.0e, rollout round %d (%d "
                "rollouts, %d from a filled marker, %d stopped off the data): %d frames "
                "ahead on the last %d frames %.2f mm, rollout %s", c.ridge, round,
                count.starts, count.filled, count.stopped,
                run.o.horizon_frames, run.validationFrames(), 1e3 * c.validation_rms_m,
                c.bounded ? "bounded" : "unbounded");
  say(run.o, line);
  run.addCandidate(c, theta);
}

}  // namespace

bool runRounds(FitRun& run, const System& data_rows, double ridge, Eigen::VectorXd theta, int gain_t_end,
               int start_end, int rounds, bool budgeted, const RoundCallback& each) {
  const SensorMuscleOptions& o = run.o;
  const RolloutSettings settings{o.horizon_frames, o.rollout_stride_frames, o.rollout_correction_frames};
  const double reference_diagonal = meanDiagonal(data_rows);
  System all = data_rows;
  for (int round = 1; round <= rounds; ++round) {
    if (budgeted && round > 1 && run.budget.stops(o, "further rollout round")) return true;
    const RolloutCount count =
        run.rollouts.accumulate(run.build(theta, gain_t_end), settings, 1, start_end, &all, run.pool.get());
    if (!run.solve(all, ridge, &theta, reference_diagonal)) return false;
    each(round, theta, count);
  }
  return true;
}

void judgeRolloutRounds(FitRun& run) {
  for (int index : roundStarts(run)) {
    if (run.budget.stops(run.o, "further rollout rounds")) break;
    const SensorMuscleCandidate start = run.result.candidates[index];
    runRounds(run, run.best_sys, start.ridge, run.thetas[index], run.validation_start,
              run.validation_start - run.o.horizon_frames - 1, run.o.rollout_rounds, true,
              [&](int round, const Eigen::VectorXd& theta, const RolloutCount& count) {
                addRoundCandidate(run, start, round, theta, count);
              });
  }
}

}  // namespace mme::sensor_muscles
