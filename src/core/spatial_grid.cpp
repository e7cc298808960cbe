// Uniform grid over sorted packed cell keys: no hashing (deterministic, no allocation churn),
// neighbour cells found by binary search once per occupied cell.
#include "motion_model_estimation/core/spatial_grid.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace mme {

namespace {

// Cell coordinates are packed 21 bits per axis. Coordinates beyond the range are clamped:
// clamping is monotone and never increases the distance between two cells, so points closer
// than the cutoff still land in neighbouring cells (far-away points merely share edge cells,
// which costs time, never correctness: every candidate is checked by distance).
constexpr int kBits = 21;
constexpr int64_t kHalfRange = int64_t{1} << (kBits - 1);
constexpr int64_t kMask = (int64_t{1} << kBits) - 1;

int64_t cellCoord(double p_m, double inv_cell) {
  double c = std::floor(p_m * inv_cell);
  // The negated test also sends NaN (non-finite points) to a valid cell.
  if (!(c >= static_cast<double>(-kHalfRange))) c = static_cast<double>(-kHalfRange);
  if (c > static_cast<double>(kHalfRange - 1)) c = static_cast<double>(kHalfRange - 1);
  return static_cast<int64_t>(c) + kHalfRange;  // in [0, 2^kBits)
}

int64_t packKey(int64_t cx, int64_t cy, int64_t cz) { return (cx << (2 * kBits)) | (cy << kBits) | cz; }

}  // namespace

void SpatialGrid::build(const std::vector<Eigen::Vector3d>& points, double cell_size_m,
                        const std::vector<uint8_t>* use) {
  if (!(cell_size_m > 0.0) || !std::isfinite(cell_size_m))
    throw std::invalid_argument("SpatialGrid::build: cell size must be finite and > 0");
  if (use && use->size() != points.size())
    throw std::invalid_argument("SpatialGrid::build: use mask size differs from point count");
  cell_size_m_ = cell_size_m;
  const double inv_cell = 1.0 / cell_size_m;
  const int n = static_cast<int>(points.size());

  std::vector<std::pair<int64_t, int>> keyed;
  keyed.reserve(points.size());
  for (int i = 0; i < n; ++i) {
    if (use && !(*use)[i]) continue;
    const Eigen::Vector3d& p = points[i];
    keyed.emplace_back(packKey(cellCoord(p.x(), inv_cell), cellCoord(p.y(), inv_cell),
                               cellCoord(p.z(), inv_cell)),
                       i);
  }
  // (key, index) order: cells ascending, indices ascending inside a cell.
  std::sort(keyed.begin(), keyed.end());

  cell_keys_.clear();
  cell_start_.clear();
  sorted_index_.clear();
  point_cell_.assign(points.size(), -1);
  sorted_index_.reserve(keyed.size());
  for (size_t k = 0; k < keyed.size(); ++k) {
    if (k == 0 || keyed[k].first != keyed[k - 1].first) {
      cell_keys_.push_back(keyed[k].first);
      cell_start_.push_back(static_cast<int>(k));
    }
    sorted_index_.push_back(keyed[k].second);
    point_cell_[keyed[k].second] = static_cast<int>(cell_keys_.size()) - 1;
  }
  cell_start_.push_back(static_cast<int>(keyed.size()));
}

void SpatialGrid::pairsWithin(const std::vector<Eigen::Vector3d>& points, double cutoff_m,
                              const std::vector<uint8_t>& in_a, const std::vector<uint8_t>& in_b,
                              std::vector<std::pair<int, int>>* out) const {
  const size_t n = points.size();
  if (point_cell_.size() != n || in_a.size() != n || in_b.size() != n)
    throw std::invalid_argument("SpatialGrid::pairsWithin: sizes differ from the built grid");
  // A relative slack so a cutoff equal to the cell size computed differently still passes.
  if (cutoff_m > cell_size_m_ * (1.0 + 1e-12))
    throw std::invalid_argument("SpatialGrid::pairsWithin: cutoff larger than the cell size");
  if (!(cutoff_m >= 0.0)) return;

  const size_t num_cells = cell_keys_.size();
  // Neighbour cells of each occupied cell, computed on first use.
  std::vector<int> nb_begin(num_cells, -1), nb_count(num_cells, 0);
  std::vector<int> nb_list;
  auto neighbours = [&](int c) {
    if (nb_begin[c] >= 0) return;
    nb_begin[c] = static_cast<int>(nb_list.size());
    const int64_t key = cell_keys_[c];
    const int64_t cx = key >> (2 * kBits), cy = (key >> kBits) & kMask, cz = key & kMask;
    for (int64_t dx = -1; dx <= 1; ++dx)
      for (int64_t dy = -1; dy <= 1; ++dy)
        for (int64_t dz = -1; dz <= 1; ++dz) {
          const int64_t x = cx + dx, y = cy + dy, z = cz + dz;
          if (x < 0 || y < 0 || z < 0 || x > kMask || y > kMask || z > kMask) continue;
          const int64_t nk = packKey(x, y, z);
          auto it = std::lower_bound(cell_keys_.begin(), cell_keys_.end(), nk);
          if (it != cell_keys_.end() && *it == nk)
            nb_list.push_back(static_cast<int>(it - cell_keys_.begin()));
        }
    nb_count[c] = static_cast<int>(nb_list.size()) - nb_begin[c];
  };

  std::vector<int> js;
  for (size_t ii = 0; ii < n; ++ii) {
    const int i = static_cast<int>(ii);
    if (!in_a[i] || point_cell_[i] < 0) continue;
    const int c = point_cell_[i];
    neighbours(c);
    js.clear();
    const Eigen::Vector3d& pi = points[i];
    const bool i_in_b = in_b[i] != 0;
    for (int q = 0; q < nb_count[c]; ++q) {
      const int nc = nb_list[nb_begin[c] + q];
      for (int s = cell_start_[nc]; s < cell_start_[nc + 1]; ++s) {
        const int j = sorted_index_[s];
        if (j == i || !in_b[j]) continue;
        // A pair reachable from both ends is reported once, from its smaller index.
        if (i_in_b && in_a[j] && j < i) continue;
        const Eigen::Vector3d& pj = points[j];
        // Same expression as the spring kernel's length (b - a), so "within the cutoff" here and
        // "active below max_distance" there agree to the last bit.
        const double dx = pj.x() - pi.x(), dy = pj.y() - pi.y(), dz = pj.z() - pi.z();
        if (std::sqrt(dx * dx + dy * dy + dz * dz) <= cutoff_m) js.push_back(j);
      }
    }
    std::sort(js.begin(), js.end());
    for (int j : js) out->emplace_back(i, j);
  }
}

}  // namespace mme
