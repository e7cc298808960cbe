// Integrates a model with the motion law of SPEC section 3 (semi-implicit Euler, Provot clamp).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"

namespace mme {

struct State {
  std::vector<Eigen::Vector3d> x_m;
  std::vector<Eigen::Vector3d> v_mps;
};

/// Compiled form of a model for fast stepping. Interaction bonds are found with a SpatialGrid
/// from the positions at the start of each substep.
class Simulator {
 public:
  explicit Simulator(const Model& model);
  ~Simulator();
  Simulator(Simulator&&) noexcept;
  Simulator& operator=(Simulator&&) noexcept;

  /// Replaces the parameter values (same structure as the constructor's model).
  void setParameters(const Model& model);
  /// Initial state from the model's particles.
  State initialState() const;
  /// Total force on every particle [N] (bonds, interactions, viscosity, gravity); fixed
  /// particles get forces too (they are just not moved).
  void computeForces(const State& s, std::vector<Eigen::Vector3d>* forces_n);
  /// Advances one substep of dt_s: v += dt F/m; x += dt v (free particles), then Provot clamps.
  void step(State* s, double dt_s);
  /// Advances one frame = model.substeps substeps of frame_period_s / substeps.
  void stepFrame(State* s, double frame_period_s);
  /// Kinetic + elastic (springs, flexion) + gravitational energy [J]; dampers excluded.
  double totalEnergy(const State& s);
  /// Number of interaction bonds found at the last computeForces call.
  size_t lastInteractionBondCount() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Simulates `num_frames` frames (frame 0 = the initial state) at `frame_rate_hz` (> 0) and
/// returns them as a trajectory named after the particles, nothing occluded.
Trajectory simulateTrajectory(const Model& model, int num_frames, double frame_rate_hz);

}  // namespace mme
