// Observed marker trajectories: frames of labelled 3-D positions with occlusion flags.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace mme {

/// T frames x N markers. Positions in metres; occluded samples keep position (0,0,0) and
/// occluded = 1. Storage is frame-major: sample (t, i) at index t * N + i.
struct Trajectory {
  std::vector<std::string> marker_names;
  double frame_rate_hz = 0.0;
  std::vector<double> times_s;             ///< one per frame
  std::vector<uint32_t> frame_numbers;     ///< one per frame
  std::vector<Eigen::Vector3d> positions_m;  ///< T*N
  std::vector<uint8_t> occluded;             ///< T*N, 1 = occluded

  int numFrames() const { return static_cast<int>(times_s.size()); }
  int numMarkers() const { return static_cast<int>(marker_names.size()); }
  const Eigen::Vector3d& position(int t, int i) const { return positions_m[t * numMarkers() + i]; }
  Eigen::Vector3d& position(int t, int i) { return positions_m[t * numMarkers() + i]; }
  bool isOccluded(int t, int i) const { return occluded[t * numMarkers() + i] != 0; }
  /// Resizes to T frames of the current markers; all samples occluded at (0,0,0); times from
  /// frame_rate_hz.
  void resize(int num_frames);
  /// Number of occluded samples.
  size_t countOccluded() const;
  /// Empty string when sizes are consistent and positions finite, else the reason.
  std::string validate() const;
};

/// Reorders/filters the trajectory's markers to follow `names` (e.g. a model's particles).
/// Markers in `names` absent from the trajectory are reported in `missing` (and left occluded);
/// returns the remapped trajectory.
Trajectory remapMarkers(const Trajectory& in, const std::vector<std::string>& names,
                        std::vector<std::string>* missing);

/// Frames [first, first + count) of a trajectory (markers, rate and per-frame data kept).
/// Throws std::out_of_range when the range does not lie inside it.
Trajectory sliceFrames(const Trajectory& in, int first, int count);

/// The box around every observed (not occluded) sample [m]; false (and the box untouched) when
/// no sample is observed.
bool observedBounds(const Trajectory& trajectory, Eigen::Vector3d* min_m, Eigen::Vector3d* max_m);

/// The distance between markers a and b over the frames where both are seen: its mean and
/// standard deviation [m] and how many frames saw both (0: the statistics are 0).
struct MarkerDistance {
  double mean_m = 0.0;
  double std_m = 0.0;
  int seen_frames = 0;
};
MarkerDistance markerDistance(const Trajectory& trajectory, int a, int b);

/// Adds independent Gaussian noise of `noise_std_m` [m] to every non-occluded coordinate,
/// reproducibly from `seed` (own Box-Muller on mt19937_64: same output on every platform).
void addGaussianNoise(Trajectory* trajectory, double noise_std_m, uint64_t seed);

}  // namespace mme
