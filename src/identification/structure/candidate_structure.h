// Candidate generation for structure selection: which bonds, flexions and drags a level may
// choose from. Candidates are cheap to propose and expensive to keep wrong, so they come from
// the markers' geometry alone (nearest neighbours, near-rigid pairs, near-collinear triples) and
// each one starts with a type of its own; the elimination (elimination.h) decides which stay.
#pragma once

#include <array>
#include <utility>
#include <vector>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/identification/structure/structure_selection.h"

namespace mme {
namespace structure {

/// Candidate pairs (a < b, sorted): each particle's `options.neighbours` nearest by mean
/// distance and every pair whose distance's std / mean is below `options.rigid_relative_std`;
/// pairs already bonded in `model`, pairs of two fixed particles and pairs seen in fewer than 3
/// frames are left out; at most `options.max_candidates`, the shortest kept.
std::vector<std::pair<int, int>> candidatePairs(const Model& model, const Trajectory& data,
                                                const StructureOptions& options);

/// A spring bond of its own type per pair (stiffness free, rest length free at the pair's mean
/// distance, a free damping when `dampers`), appended to `model`; returns the first new type.
int addCandidateBonds(Model* model, const std::vector<std::pair<int, int>>& pairs,
                      const Trajectory& data, bool dampers);

/// Near-collinear triples (a, v, c) for flexion: a and c among the `nearest` candidate partners
/// of the vertex v, with a mean angle at v of at least `min_angle_rad` (a chain's bend: springs
/// alone resist it only at second order, unlike a triangle's), the straightest first, at most
/// `most`; returned sorted.
std::vector<std::array<int, 3>> candidateTriples(const Model& model, const Trajectory& data,
                                                 const std::vector<std::pair<int, int>>& pairs,
                                                 int nearest, double min_angle_rad, int most);

/// A flexion bond of its own type per triple (stiffness, rest angle at the mean angle, and a
/// damping when `dampers`).
void addCandidateFlexions(Model* model, const std::vector<std::array<int, 3>>& triples,
                          const Trajectory& data, bool dampers);

/// A viscosity (drag on the particle's velocity) of its own type per free particle.
void addCandidateViscosities(Model* model);

}  // namespace structure
}  // namespace mme
