#include "motion_model_estimation/live/replay_pacing.h"

namespace mme {

ReplayPacing::ReplayPacing(double rate, double first_time_s, int min_frames)
    : rate_(rate), first_time_s_(first_time_s), min_frames_(min_frames) {}

std::optional<double> ReplayPacing::dueAfterS(double time_s) const {
  if (!(rate_ > 0.0)) return std::nullopt;
  return (time_s - first_time_s_) / rate_;
}

bool ReplayPacing::waitsForUpdate(int frames_fed) const {
  return rate_ == 0.0 && frames_fed >= min_frames_;
}

bool ReplayPacing::structureReleases(const StructureJob* structure, int frames_fed) {
  if (!structure) return false;
  const StructureJob::State state = structure->state();
  if (state == StructureJob::State::kFailed) return true;
  return state == StructureJob::State::kPending && frames_fed < structure->minFrames();
}

}  // namespace mme
