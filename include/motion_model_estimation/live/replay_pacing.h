// How estimator_node replays a recording (~bag): at a multiple of its own rate, each frame due
// at its time since the first divided by the rate; or (~bag_rate 0) as fast as the estimator
// keeps up, each window position fed once the estimator has updated on the one before, except
// while a structure is still to be chosen. The rules without ROS or threads, so that they are
// tested; the node only sleeps and waits as they say.
#pragma once

#include <optional>

#include "motion_model_estimation/live/structure_job.h"

namespace mme {

class ReplayPacing {
 public:
  /// `rate`: x real time (0: as fast as the estimator keeps up). `first_time_s`: the recording's
  /// first stamp. `min_frames`: the frames the estimator needs before its first update.
  ReplayPacing(double rate, double first_time_s, int min_frames);

  /// [s] after the replay's start at which the frame stamped `time_s` is due; nothing when the
  /// replay does not follow the clock (rate 0).
  std::optional<double> dueAfterS(double time_s) const;

  /// After `frames_fed` frames: whether the replay waits for the estimator's next update before
  /// the next frame (rate 0, and enough frames for an update).
  bool waitsForUpdate(int frames_fed) const;

  /// While waiting for an update: whether the structure job lets the replay go on without one.
  /// A failed selection does (frames go on); one still pending on a window shorter than it needs
  /// does (the window must fill first). `structure` null: no structure job.
  static bool structureReleases(const StructureJob* structure, int frames_fed);

 private:
  double rate_;
  double first_time_s_;
  int min_frames_;
};

}  // namespace mme
