// SpatialGrid::pairsWithin against an all-pairs brute force.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>

#include "motion_model_estimation/core/spatial_grid.h"

namespace mme {
namespace {

using Pairs = std::vector<std::pair<int, int>>;

/// Unordered pairs {i in A, j in B}, i != j, within cutoff, as (min, max) sorted.
std::set<std::pair<int, int>> bruteForce(const std::vector<Eigen::Vector3d>& pts, double cutoff,
                                         const std::vector<uint8_t>& in_a,
                                         const std::vector<uint8_t>& in_b) {
  std::set<std::pair<int, int>> out;
  for (size_t i = 0; i < pts.size(); ++i)
    for (size_t j = 0; j < pts.size(); ++j) {
      if (i == j || !in_a[i] || !in_b[j]) continue;
      if ((pts[j] - pts[i]).norm() <= cutoff)
        out.insert({static_cast<int>(std::min(i, j)), static_cast<int>(std::max(i, j))});
    }
  return out;
}

std::vector<Eigen::Vector3d> randomPoints(std::mt19937_64& rng, int n, double lo, double hi) {
  std::uniform_real_distribution<double> u(lo, hi);
  std::vector<Eigen::Vector3d> pts(n);
  for (auto& p : pts) p = Eigen::Vector3d(u(rng), u(rng), u(rng));
  return pts;
}

void checkAgainstBruteForce(const std::vector<Eigen::Vector3d>& pts, double cutoff,
                            const std::vector<uint8_t>& in_a, const std::vector<uint8_t>& in_b) {
  SpatialGrid grid;
  grid.build(pts, cutoff);
  Pairs got;
  grid.pairsWithin(pts, cutoff, in_a, in_b, &got);
  // Each reported pair once, i in A, j in B.
  std::set<std::pair<int, int>> as_set;
  for (const auto& p : got) {
    EXPECT_NE(p.first, p.second);
    EXPECT_TRUE(in_a[p.first]);
    EXPECT_TRUE(in_b[p.second]);
    EXPECT_TRUE(as_set.insert({std::min(p.first, p.second), std::max(p.first, p.second)}).second)
        << "duplicate pair " << p.first << "," << p.second;
  }
  EXPECT_EQ(as_set, bruteForce(pts, cutoff, in_a, in_b)) << "cutoff " << cutoff;
}

TEST(SpatialGrid, MatchesBruteForceAllPoints) {
  std::mt19937_64 rng(11);
  const auto pts = randomPoints(rng, 400, -3.0, 5.0);
  const std::vector<uint8_t> all(pts.size(), 1);
  for (double cutoff : {0.1, 0.35, 0.8, 2.0, 20.0}) checkAgainstBruteForce(pts, cutoff, all, all);
}

TEST(SpatialGrid, MatchesBruteForceWithGroupMasks) {
  std::mt19937_64 rng(12);
  const auto pts = randomPoints(rng, 300, -2.0, 2.0);
  std::vector<uint8_t> gas(pts.size()), jet(pts.size()), mixed(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    gas[i] = i % 3 != 0;
    jet[i] = i % 3 == 0;
    mixed[i] = i % 2 == 0;  // overlaps both groups
  }
  for (double cutoff : {0.2, 0.5, 1.1}) {
    checkAgainstBruteForce(pts, cutoff, gas, gas);    // same group
    checkAgainstBruteForce(pts, cutoff, jet, gas);    // cross group
    checkAgainstBruteForce(pts, cutoff, gas, jet);
    checkAgainstBruteForce(pts, cutoff, mixed, gas);  // overlapping sets
  }
}

TEST(SpatialGrid, DeterministicCanonicalOrder) {
  std::mt19937_64 rng(13);
  const auto pts = randomPoints(rng, 200, -1.0, 1.0);
  const std::vector<uint8_t> all(pts.size(), 1);
  SpatialGrid g1, g2;
  g1.build(pts, 0.5);
  g2.build(pts, 0.7);  // a different cell size must not change the order
  Pairs a, b, c;
  g1.pairsWithin(pts, 0.4, all, all, &a);
  g1.pairsWithin(pts, 0.4, all, all, &b);
  g2.pairsWithin(pts, 0.4, all, all, &c);
  ASSERT_FALSE(a.empty());
  EXPECT_EQ(a, b);
  EXPECT_EQ(a, c);
  EXPECT_TRUE(std::is_sorted(a.begin(), a.end()));
}

TEST(SpatialGrid, NegativeCoordinatesAndCellBoundaries) {
  // Points straddling zero and exact cell boundaries (floor of negatives must not merge cells).
  std::vector<Eigen::Vector3d> pts = {{-0.05, 0, 0}, {0.05, 0, 0}, {-1.0, -1.0, -1.0},
                                      {-1.0, -1.0, -1.9}, {-2.0, 0, 0}, {-1.0, 0, 0}};
  const std::vector<uint8_t> all(pts.size(), 1);
  checkAgainstBruteForce(pts, 1.0, all, all);
  std::mt19937_64 rng(14);
  checkAgainstBruteForce(randomPoints(rng, 300, -100.0, -95.0), 0.6,
                         std::vector<uint8_t>(300, 1), std::vector<uint8_t>(300, 1));
}

TEST(SpatialGrid, EmptyAndSingleSets) {
  SpatialGrid grid;
  std::vector<Eigen::Vector3d> none;
  grid.build(none, 1.0);
  Pairs out;
  grid.pairsWithin(none, 1.0, {}, {}, &out);
  EXPECT_TRUE(out.empty());
  std::vector<Eigen::Vector3d> one = {{1, 2, 3}};
  grid.build(one, 1.0);
  grid.pairsWithin(one, 1.0, {1}, {1}, &out);
  EXPECT_TRUE(out.empty());
  // Empty group masks over a non-empty set.
  std::mt19937_64 rng(15);
  const auto pts = randomPoints(rng, 50, 0, 1);
  grid.build(pts, 1.0);
  grid.pairsWithin(pts, 1.0, std::vector<uint8_t>(50, 0), std::vector<uint8_t>(50, 1), &out);
  EXPECT_TRUE(out.empty());
}

TEST(SpatialGrid, UseMaskExcludesPointsAndFarPointsAreSafe) {
  std::mt19937_64 rng(16);
  auto pts = randomPoints(rng, 100, 0, 2);
  pts.push_back({1e12, -1e12, 0});  // beyond the packed cell range: clamped, still correct
  pts.push_back({1e12 + 0.1, -1e12, 0});
  std::vector<uint8_t> use(pts.size(), 1);
  use[5] = 0;
  SpatialGrid grid;
  grid.build(pts, 0.5, &use);
  Pairs got;
  const std::vector<uint8_t> all(pts.size(), 1);
  grid.pairsWithin(pts, 0.5, all, all, &got);
  std::set<std::pair<int, int>> expected;
  for (const auto& p : bruteForce(pts, 0.5, use, use)) expected.insert(p);
  std::set<std::pair<int, int>> as_set(got.begin(), got.end());
  EXPECT_EQ(as_set, expected);
  EXPECT_TRUE(as_set.count({100, 101}));
}

TEST(SpatialGrid, RejectsCutoffLargerThanCell) {
  std::vector<Eigen::Vector3d> pts = {{0, 0, 0}, {1, 0, 0}};
  SpatialGrid grid;
  grid.build(pts, 0.5);
  Pairs out;
  EXPECT_THROW(grid.pairsWithin(pts, 1.0, {1, 1}, {1, 1}, &out), std::invalid_argument);
  EXPECT_THROW(grid.build(pts, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace mme
