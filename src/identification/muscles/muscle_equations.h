// The sensor muscles' one-step equations: Newton's law on an observed frame, with the passive
// model's forces known, is linear in every muscle's (network weights x gain, stiffness, damping)
// (docs/muscles.md, *Fit*). MuscleEquations writes them, frame by frame or summed over a window,
// into a System's normal equations, in columns scaled to unit RMS.
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/core/thread_pool.h"
#include "motion_model_estimation/core/trajectory.h"
#include "muscle_least_squares.h"
#include "sensor_layout.h"

namespace mme::sensor_muscles {

/// Three consecutive frames (before, now, after): positions and occlusion flags per particle
/// (x[k] null: that frame is outside the data; occluded[k] null: every particle seen).
struct Frames3 {
  const Eigen::Vector3d* x[3] = {nullptr, nullptr, nullptr};
  const uint8_t* occluded[3] = {nullptr, nullptr, nullptr};
  bool seen(int k, int i) const { return x[k] && (!occluded[k] || !occluded[k][i]); }
};

/// One frame's one-step equations: per particle, usable (see usable()) and a - F_passive / m
/// from the frame differences; per muscle, its ends seen, its unit vector and its scaled
/// regressors (the sensor inputs, 1, its elongation and speed).
struct FramePieces {
  std::vector<char> particle_ok, muscle_ok;
  std::vector<Eigen::Vector3d> y, u;
  Eigen::MatrixXd phi;  // k x muscles
};

class MuscleEquations {
 public:
  /// `passive`, `data` and `layout` must outlive this.
  MuscleEquations(const Model& passive, const Trajectory& data, const Layout& layout);

  const Model& passive() const { return passive_; }
  const Trajectory& data() const { return data_; }
  const Layout& layout() const { return layout_; }
  int particles() const { return n_; }
  int sensors() const { return s_; }
  int muscles() const { return m_; }
  int perMuscle() const { return k_; }  ///< unknowns per muscle: 2 sensors + 3
  int unknowns() const { return m_ * k_; }
  double framePeriodS() const { return h_; }
  /// The scale of the network input j (2 sensors of them) and of muscle m's elongation [m] and
  /// speed [m/s] (their RMS over the data).
  double inputScale(int j) const { return z_scale_(j); }
  const Eigen::VectorXd& inputScales() const { return z_scale_; }
  double elongationScaleM(int m) const { return e_scale_[m]; }
  double speedScaleMps(int m) const { return s_scale_[m]; }
  /// The normal matrix's block pattern of this layout (every system it writes has it).
  const std::shared_ptr<const BlockPattern>& pattern() const { return pattern_; }
  /// The solve's sign constraints for this layout.
  SignConstraints signConstraints(bool nonnegative_own_spring) const;

  /// Adds the equations whose window's centre t lies in [centre_begin, centre_end) and whose
  /// window (frames t - window .. t + window) lies inside the data: per particle, the one-step
  /// equations of frames t - window + 1 .. t + window - 1 summed with triangle weights
  /// window - |j|.
  /// `pool` (may be null) shares window 1's accumulation out (addPiecesBatch): the same sums.
  void accumulate(int window, int centre_begin, int centre_end, System* sys, ThreadPool* pool = nullptr) const;
  /// Frames whose pieces a batch holds at most (each holds 2S + 3 doubles per muscle).
  static constexpr size_t kBatchFrames = 64;
  /// Adds one frame's equations (window 1).
  void addPieces(const FramePieces& f, System* sys) const;
  /// Adds the frames' equations in order, as addPieces one after the other does, bit for bit:
  /// with a pool, the normal matrix's block rows are shared out among its threads (each block
  /// row gets its terms in the same order whichever thread writes it). `pool` may be null.
  void addPiecesBatch(const std::vector<FramePieces>& batch, System* sys, ThreadPool* pool) const;
  /// The one-step equations of the middle frame of `frames` (its acceleration from all three).
  FramePieces pieces(const Frames3& frames) const;
  /// Frames t-1, t, t+1 of the data.
  Frames3 dataFrames(int t) const;
  /// The 2S network inputs now (elongations from the sensors' rest lengths, then speeds along
  /// them); false when a sensor's particle is unseen now or before.
  bool sensorInputs(const Frames3& f, Eigen::VectorXd* z) const;

 private:
  using Gradients = std::vector<Eigen::Matrix<double, 3, Eigen::Dynamic>>;

  FramePieces pieces(int t) const;
  FramePieces emptyPieces() const;
  void addWindowEquation(int i, int window, const std::deque<FramePieces>& ring, Gradients* g,
                         System* sys) const;
  void addEquation(int i, const Gradients& g, const Eigen::Vector3d& y, System* sys) const;
  void addFrameEquation(int i, const FramePieces& f, System* sys) const;
  /// addFrameEquation's terms of the muscles m with m % parts == part (their block rows and
  /// right-hand sides), without the residual's square and the row count.
  void addFrameEquationPart(int i, const FramePieces& f, int part, int parts, System* sys) const;
  State stateAt(const Frames3& f) const;
  bool muscleGeometry(const Frames3& f, int m, const State& state, Eigen::Vector3d* u, double* e,
                      double* s) const;
  bool usable(const Frames3& f, int i, const std::vector<char>& muscle_ok) const;
  void findPartners();
  void makePattern();
  void computeScales();

  const Model& passive_;
  const Trajectory& data_;
  const Layout& layout_;
  mutable Simulator sim_;  // computeForces keeps scratch
  int n_, s_, m_, k_;
  double h_ = 0.0;
  std::vector<std::vector<int>> partners_;
  bool all_partners_ = false;
  std::vector<std::vector<std::pair<int, double>>> at_;  ///< per particle: (muscle, sign)
  std::shared_ptr<const BlockPattern> pattern_;
  Eigen::VectorXd z_scale_;
  std::vector<double> e_scale_, s_scale_;
};

}  // namespace mme::sensor_muscles
