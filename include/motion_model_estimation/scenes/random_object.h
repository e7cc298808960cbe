// Random 3-D mass-spring objects for tests and benchmarks of identification beyond the paper's
// fixed scenes (e.g. generations to converge against the number of bond types).
#pragma once

#include <cstdint>

#include "motion_model_estimation/core/model.h"

namespace mme {

struct RandomObjectSpec {
  int particles = 18;
  int bond_types = 12;         ///< linear spring types (stiffness + rest_length free each)
  int bonds = 40;              ///< >= particles - 1 (a spanning tree keeps it connected)
  double frame_rate_hz = 120.0;
  double size_m = 0.3;         ///< edge of the cube the particles start in [m]
  /// > 0: every type also has a free damping, drawn log-uniformly in [damping_max / 10,
  /// damping_max] [N s/m] (light: the floating object keeps moving for tens of seconds).
  double damping_max_nspm = 0.0;
  /// > 0: every type also has a free cubic stiffness k_nl = u * this * k / L^2 (u uniform in
  /// [0.5, 1]; hardening: at a strain of 10 % it adds u * this % to the tension) [1].
  double stiffness_nl_scale = 0.0;
  /// The first this many types are cables: active only when stretched beyond their rest length
  /// (a free min_distance, true value = the rest length, bounds [L/2, 2L]).
  int cable_types = 0;
  uint64_t seed = 1;
};

/// A connected floating object (no gravity, no fixed particle) whose bonds use every type at
/// least once, with rest lengths that differ from the initial distances so it vibrates, and
/// stiffnesses low enough for the explicit integration at the frame rate (omega h < 0.5).
/// Free parameters carry their true values; bounds bracket them by 10x (stiffness) and 2x
/// (rest length). Throws InputError on an impossible spec.
Model makeRandomObject(const RandomObjectSpec& spec);

struct HangingObjectSpec {
  int particles = 16;          ///< the first two are fixed suspension points
  int bond_types = 8;          ///< damped linear spring types (stiffness, rest_length, damping free)
  int bonds = 30;              ///< >= particles - 1
  double frame_rate_hz = 120.0;
  double min_stretch = 2.4;    ///< bonds start at min..max_stretch times their rest length
  double max_stretch = 20.0;
  uint64_t seed = 1;
};

/// A soft object hanging under gravity from two fixed points, started away from its equilibrium
/// (it falls, swings and settles): springs far longer than their rest lengths, damping of
/// 0.02-0.3 N s/m. Free parameters carry their true values and no bounds (the defaults must do).
/// Throws InputError on an impossible spec.
Model makeHangingObject(const HangingObjectSpec& spec);

struct ChainObjectSpec {
  int chains = 3;              ///< chains hanging off a hub triangle of their roots (>= 3)
  int links = 5;               ///< particles per chain, root included (>= 3: one flexion at least)
  int spring_types = 2;        ///< segment spring types (chains round-robin)
  int flexion_types = 2;       ///< flexion types at the chains' inner particles (round-robin)
  double frame_rate_hz = 120.0;
  double segment_m = 0.06;     ///< segment length [m]
  /// > 0: every type also has a free damping (springs up to this [N s/m], flexion up to this
  /// times the segment length squared [N m s/rad]).
  double damping_max_nspm = 0.0;
  uint64_t seed = 1;
};

/// A floating object of bent chains (no gravity, no fixed particle): the roots form an
/// equilateral triangle of one spring type ("hub"); each chain is a line of springs whose inner
/// particles carry a flexion bond (vertex at the particle, its neighbours on the chain) at the
/// type's rest angle (150-172 deg: near-collinear). The chains start at their rest shape with
/// random velocities and spring rest lengths 0.9-1.1 of the segment, so they vibrate and bend.
/// Free parameters carry their true values, bounds as makeRandomObject. Throws InputError on an
/// impossible spec.
Model makeChainObject(const ChainObjectSpec& spec);

}  // namespace mme
