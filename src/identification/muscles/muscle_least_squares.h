// The sensor muscles' least-squares fit: ridge-regularised normal equations in scaled columns,
// solved by Cholesky with every muscle's own stiffness and damping held >= 0 (an active set).
// A particle's equations touch only the muscles at it, so the normal matrix is sparse in blocks
// of one muscle's unknowns: it is stored as those blocks alone and factorised as a sparse matrix
// whose fill-reducing ordering and symbolic factorisation are made once per layout and reused by
// every ridge, clamp round and rollout round (their rows touch the same blocks).
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include <Eigen/Core>

namespace mme::sensor_muscles {

/// Which blocks of the normal matrix can be non-zero: per muscle m, the muscles m2 <= m whose
/// unknowns meet m's in an equation (both at a particle that gives equations), and where each
/// such block is stored. One pattern per layout, shared by its systems.
struct BlockPattern {
  int muscles = 0;
  int per_muscle = 0;  ///< unknowns per muscle (2 sensors + 3)
  std::vector<std::vector<int>> coupled_below;  ///< per muscle, sorted
  std::vector<std::vector<int>> slot;           ///< the storage index of each coupled_below entry
  int blocks = 0;
  /// The storage index of block (m, m2), m2 <= m; -1 when the two never meet.
  int find(int m, int m2) const;
};

/// The pattern of `coupled_below` (any order, duplicates allowed).
std::shared_ptr<const BlockPattern> makeBlockPattern(int muscles, int per_muscle,
                                                     std::vector<std::vector<int>> coupled_below);

/// The equation error's normal equations in the scaled columns. Only the blocks on and below
/// the diagonal that the pattern names are stored (the diagonal blocks whole), so the memory
/// follows the non-zeros: a particle's rows touch only its own muscles.
struct System {
  std::shared_ptr<const BlockPattern> pattern;
  std::vector<Eigen::MatrixXd> blocks;  ///< per storage slot: rows m's unknowns, columns m2's
  Eigen::VectorXd atb;
  size_t rows = 0;
  double btb = 0.0;

  int unknowns() const { return static_cast<int>(atb.size()); }
  /// Block (m, m2) of the normal matrix, m2 <= m, coupled in the pattern.
  Eigen::MatrixXd& block(int m, int m2) { return blocks[pattern->find(m, m2)]; }
  /// The normal matrix's entry (row, col) (either triangle; 0 outside the pattern).
  double at(int row, int col) const;
  /// The normal matrix times theta.
  Eigen::VectorXd times(const Eigen::VectorXd& theta) const;
  /// The whole normal matrix as a dense one (for small systems and checks).
  Eigen::MatrixXd dense() const;
};

/// Gives an empty system its zero normal equations on `pattern`.
void sizeSystem(const std::shared_ptr<const BlockPattern>& pattern, System* sys);

/// The mean diagonal of a system's normal matrix (the ridges' reference).
double meanDiagonal(const System& sys);

/// Sum of the squared residuals of a system's rows at theta.
double residualSquares(const System& sys, const Eigen::VectorXd& theta);

/// RMS of a system's rows at theta [m/s^2].
double residualRms(const System& sys, const Eigen::VectorXd& theta);

/// The sparse factorisation's reusable part (muscle_least_squares.cpp).
struct SparseRidgeCache;
std::shared_ptr<SparseRidgeCache> makeSparseRidgeCache();

/// Where each muscle's unknowns sit and which the solve constrains.
struct SignConstraints {
  int muscles = 0;
  int per_muscle = 0;         ///< unknowns per muscle (2 sensors + 3)
  int own_stiffness = 0;      ///< a muscle's stiffness column within its block; damping follows
  bool nonnegative_own_spring = true;   ///< stiffness and damping >= 0
  std::vector<int> held_at_zero;        ///< columns always 0 (stiffness of muscles without one)
  /// Solve the normal matrix as a sparse one (its system's pattern); false: as a dense one.
  bool sparse = false;
  /// The sparse factorisation's ordering and symbolic part, made by the first solve and shared
  /// by copies of these constraints (one layout, one pattern).
  std::shared_ptr<SparseRidgeCache> cache;
};

/// theta for a relative ridge under `constraints`; false when a solve fails. The signs by an
/// active set that only grows: a negative stiffness or damping is held at 0 and the rest solved
/// again, until none is negative (at most 6 solves; what is still negative then is set to 0).
/// The ridge is relative to `reference_diagonal` when > 0 (to keep a ridge's weight when rows
/// are added), else to the system's own mean diagonal.
bool solveRidge(const System& sys, double ridge, const SignConstraints& constraints, Eigen::VectorXd* theta,
                double reference_diagonal = 0.0);

}  // namespace mme::sensor_muscles
