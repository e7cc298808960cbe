// A candidate's activation time constant (docs/muscles.md, *Activation time constant*): its
// validation fit judged again with each candidate time constant on every muscle.
#include <cmath>
#include <cstdio>

#include "sensor_muscle_fit.h"

namespace mme::sensor_muscles {

Activation chooseActivation(FitRun& run, int index) {
  const SensorMuscleOptions& o = run.o;
  const SensorMuscleCandidate& c = run.result.candidates[index];
  Activation chosen{0.0, c.validation_rms_m};
  if (run.thetas[index].size() == 0) return chosen;
  const double frame_period_s = run.equations.framePeriodS();
  for (double tau_frames : o.activation_times_frames) {
    if (!(tau_frames > 0.0)) continue;
    if (run.budget.stops(o, "further activation time constant")) break;
    double rms = std::nan("");
    bool bounded = false;
    const double time_s = tau_frames * frame_period_s;
    run.judge.judgeBuilt([&] { return run.build(run.thetas[index], run.validation_start, time_s); }, &rms,
                         &bounded);
    char line[240];
    std::snprintf(line, sizeof(line), "sensor muscles: ridge %.0e, %d rollout round(s), activation "
                  "time constant %g frames: %d frames ahead on the last %d frames %.2f mm, rollout %s",
                  c.ridge, c.rollout_rounds, tau_frames, o.horizon_frames, run.validationFrames(),
                  1e3 * rms, bounded ? "bounded" : "unbounded");
    say(o, line);
    if (bounded && std::isfinite(rms) && rms < chosen.validation_rms_m)
      chosen = {time_s, rms};
  }
  return chosen;
}

}  // namespace mme::sensor_muscles
