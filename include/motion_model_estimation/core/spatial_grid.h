// Uniform hash grid for finding all particle pairs closer than a cutoff without an all-pairs loop.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <utility>
#include <vector>

namespace mme {

/// Buckets points into cubic cells of size cutoff; a query visits the 27 neighbour cells.
class SpatialGrid {
 public:
  /// Rebuilds the grid over `points` (only those with `use[i] != 0`; null = all) with cells of
  /// `cell_size_m` (> 0).
  void build(const std::vector<Eigen::Vector3d>& points, double cell_size_m,
             const std::vector<uint8_t>* use = nullptr);
  /// Appends pairs (i, j), i in set A, j in set B, i != j, |p_i - p_j| <= cutoff_m, each
  /// unordered pair once, in a deterministic order. Membership via in_a / in_b flags (size N).
  /// cutoff_m must be <= the cell size used in build().
  void pairsWithin(const std::vector<Eigen::Vector3d>& points, double cutoff_m,
                   const std::vector<uint8_t>& in_a, const std::vector<uint8_t>& in_b,
                   std::vector<std::pair<int, int>>* out) const;

 private:
  double cell_size_m_ = 1.0;
  // implementation-defined storage (sorted cell keys + particle indices)
  std::vector<int64_t> cell_keys_;       // sorted unique keys
  std::vector<int> cell_start_;          // start offset into sorted_index_ per key (+1 end)
  std::vector<int> sorted_index_;        // particle indices sorted by cell key
  std::vector<int> point_cell_;          // cell (index into cell_keys_) of each point, -1 = unused
};

}  // namespace mme
