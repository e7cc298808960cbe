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
  /// Every muscle's activation [N], in bond order, for models whose muscles have an activation
  /// time constant (muscle.h); empty: each muscle starts at rest, at its excitation (set on the
  /// first step). Clear it when reusing a state for a new start.
  std::vector<double> activation_n;
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
  /// Whether some muscle has an activation time constant (states then carry activations).
  bool hasActivationState() const;
  /// Sets s's activations from an observed motion: every muscle at its excitation at s, plus
  /// the least change (minimum norm) of the activations with a time constant that makes the
  /// model's forces give the accelerations `acceleration_mps2` [m/s^2] of the particles marked
  /// `known` (free ones only) — the activation state a start in the data had. Returns the
  /// number of activations estimated (0 for a model without activation state: s's activations
  /// are then cleared).
  int estimateActivations(State* s, const std::vector<Eigen::Vector3d>& acceleration_mps2,
                          const std::vector<char>& known);
  /// Advances one substep of dt_s: v += dt F/m; x += dt v (free particles), then Provot clamps;
  /// then each activation with a time constant tau moves toward its excitation u (taken at the
  /// substep's start): a <- u + (a - u) exp(-dt / tau).
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
