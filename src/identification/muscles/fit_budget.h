// The sensor muscles' wall-time limit (SensorMuscleOptions::max_time_s) and their progress lines.
#pragma once

#include <chrono>
#include <string>

#include "motion_model_estimation/identification/muscles/sensor_muscles.h"

namespace mme::sensor_muscles {

/// A progress line to the caller, when it asked for them.
void say(const SensorMuscleOptions& o, const std::string& line);

/// A relative ridge as the progress lines write it ("3e+00").
std::string formatRidge(double ridge);

/// SensorMuscleOptions::max_time_s, counted from the start of addSensorMuscles; it remembers
/// whether it stopped a step (SensorMuscleResult::stopped_by_time).
class Budget {
 public:
  explicit Budget(double max_time_s);
  double elapsedS() const;
  /// The limit is set and reached.
  bool spent() const { return max_time_s_ > 0.0 && elapsedS() >= max_time_s_; }
  /// spent(), and when so a progress line saying what is not started (`what`).
  bool stops(const SensorMuscleOptions& o, const std::string& what);
  bool stopped() const { return stopped_; }  ///< stops() has stopped a step

 private:
  double max_time_s_;
  std::chrono::steady_clock::time_point start_;
  bool stopped_ = false;
};

}  // namespace mme::sensor_muscles
