#include "fit_budget.h"

#include <cstdio>

namespace mme::sensor_muscles {

void say(const SensorMuscleOptions& o, const std::string& line) {
  if (o.progress) o.progress(line);
}

std::string formatRidge(double ridge) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.0e", ridge);
  return text;
}

Budget::Budget(double max_time_s) : max_time_s_(max_time_s), start_(std::chrono::steady_clock::now()) {}

double Budget::elapsedS() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

bool Budget::stops(const SensorMuscleOptions& o, const std::string& what) {
  if (!spent()) return false;
  stopped_ = true;
  char line[240];
  std::snprintf(line, sizeof(line), "sensor muscles: time limit of %g s spent (%.1f s): no %s",
                max_time_s_, elapsedS(), what.c_str());
  say(o, line);
  return true;
}

}  // namespace mme::sensor_muscles
