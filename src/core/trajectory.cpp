#include "motion_model_estimation/core/trajectory.h"

#include <stdexcept>
#include <string>

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>

namespace mme {

void Trajectory::resize(int num_frames) {
  const size_t n = marker_names.size();
  times_s.resize(num_frames);
  frame_numbers.resize(num_frames);
  for (int t = 0; t < num_frames; ++t) {
    times_s[t] = frame_rate_hz > 0.0 ? t / frame_rate_hz : 0.0;
    frame_numbers[t] = static_cast<uint32_t>(t);
  }
  positions_m.assign(n * num_frames, Eigen::Vector3d::Zero());
  occluded.assign(n * num_frames, 1);
}

size_t Trajectory::countOccluded() const {
  size_t count = 0;
  for (uint8_t o : occluded) count += o != 0;
  return count;
}

bool observedBounds(const Trajectory& trajectory, Eigen::Vector3d* min_m, Eigen::Vector3d* max_m) {
  bool any = false;
  Eigen::Vector3d lo, hi;
  for (size_t k = 0; k < trajectory.positions_m.size() && k < trajectory.occluded.size(); ++k) {
    if (trajectory.occluded[k]) continue;
    const Eigen::Vector3d& x = trajectory.positions_m[k];
    lo = any ? lo.cwiseMin(x).eval() : x;
    hi = any ? hi.cwiseMax(x).eval() : x;
    any = true;
  }
  if (any) {
    *min_m = lo;
    *max_m = hi;
  }
  return any;
}

MarkerDistance markerDistance(const Trajectory& trajectory, int a, int b) {
  MarkerDistance d;
  double sum = 0.0, sum2 = 0.0;
  for (int t = 0; t < trajectory.numFrames(); ++t) {
    if (trajectory.isOccluded(t, a) || trajectory.isOccluded(t, b)) continue;
    const double l = (trajectory.position(t, b) - trajectory.position(t, a)).norm();
    sum += l;
    sum2 += l * l;
    ++d.seen_frames;
  }
  if (d.seen_frames == 0) return d;
  d.mean_m = sum / d.seen_frames;
  d.std_m = std::sqrt(std::max(0.0, sum2 / d.seen_frames - d.mean_m * d.mean_m));
  return d;
}

std::string Trajectory::validate() const {
  const size_t expected = marker_names.size() * times_s.size();
  if (frame_numbers.size() != times_s.size()) return "frame_numbers and times_s differ in length";
  if (positions_m.size() != expected || occluded.size() != expected)
    return "positions/occluded do not hold frames x markers samples";
  for (size_t k = 0; k < positions_m.size(); ++k)
    if (!occluded[k] && !positions_m[k].allFinite()) {
      std::ostringstream err;
      err << "non-finite position at frame " << k / marker_names.size() << ", marker '"
          << marker_names[k % marker_names.size()] << "'";
      return err.str();
    }
  return "";
}

Trajectory remapMarkers(const Trajectory& in, const std::vector<std::string>& names,
                        std::vector<std::string>* missing) {
  Trajectory out;
  out.marker_names = names;
  out.frame_rate_hz = in.frame_rate_hz;
  out.resize(in.numFrames());
  out.times_s = in.times_s;
  out.frame_numbers = in.frame_numbers;
  if (missing) missing->clear();
  for (size_t j = 0; j < names.size(); ++j) {
    int src = -1;
    for (int i = 0; i < in.numMarkers(); ++i)
      if (in.marker_names[i] == names[j]) { src = i; break; }
    if (src < 0) {
      if (missing) missing->push_back(names[j]);
      continue;
    }
    for (int t = 0; t < in.numFrames(); ++t) {
      out.position(t, static_cast<int>(j)) = in.position(t, src);
      out.occluded[t * names.size() + j] = in.occluded[t * in.numMarkers() + src];
    }
  }
  return out;
}

void addGaussianNoise(Trajectory* trajectory, double noise_std_m, uint64_t seed) {
  if (noise_std_m <= 0.0) return;
  std::mt19937_64 rng(seed);
  // Uniform in (0, 1]: 53 random bits, never 0 so the log is finite.
  auto uniform = [&rng]() { return (static_cast<double>(rng() >> 11) + 1.0) * 0x1.0p-53; };
  for (size_t k = 0; k < trajectory->positions_m.size(); ++k) {
    if (trajectory->occluded[k]) continue;
    for (int c = 0; c < 3; ++c) {
      const double r = std::sqrt(-2.0 * std::log(uniform()));
      trajectory->positions_m[k][c] += noise_std_m * r * std::cos(2.0 * M_PI * uniform());
    }
  }
}

Trajectory sliceFrames(const Trajectory& in, int first, int count) {
  if (first < 0 || count < 0 || first + count > in.numFrames())
    throw std::out_of_range("sliceFrames: frames [" + std::to_string(first) + ", " +
                            std::to_string(first + count) + ") outside 0.." +
                            std::to_string(in.numFrames()));
  Trajectory out;
  out.marker_names = in.marker_names;
  out.frame_rate_hz = in.frame_rate_hz;
  const size_t n = static_cast<size_t>(in.numMarkers());
  const size_t a = static_cast<size_t>(first), b = static_cast<size_t>(first + count);
  out.times_s.assign(in.times_s.begin() + a, in.times_s.begin() + b);
  out.frame_numbers.assign(in.frame_numbers.begin() + a, in.frame_numbers.begin() + b);
  out.positions_m.assign(in.positions_m.begin() + a * n, in.positions_m.begin() + b * n);
  out.occluded.assign(in.occluded.begin() + a * n, in.occluded.begin() + b * n);
  return out;
}

}  // namespace mme
