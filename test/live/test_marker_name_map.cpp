// MarkerNameMap: input markers land on their particles in any order, absent particles are
// flagged as having no marker (kNoMarker, not a plain occlusion), unknown names are ignored and reported once per name list, a frame without any
// known name is refused, and a new particle list rebuilds the index.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "motion_model_estimation/live/marker_name_map.h"
#include "motion_model_estimation/identification/online/online_estimator.h"

namespace {

using V = Eigen::Vector3d;

mme::MarkerNameMap abc() { return mme::MarkerNameMap({"a", "b", "c"}); }

TEST(MarkerNameMap, PlacesMarkersInParticleOrderWhateverTheInputOrder) {
  mme::MarkerNameMap map = abc();
  const mme::MappedFrame f =
      map.map({"c", "a", "b"}, {V(3, 0, 0), V(1, 0, 0), V(2, 0, 0)}, {0, 1, 0});
  EXPECT_TRUE(f.rejection.empty());
  EXPECT_TRUE(f.warning.empty());
  EXPECT_TRUE(f.names_changed);
  EXPECT_EQ(f.matched, 3u);
  EXPECT_EQ(f.unknown, 0u);
  ASSERT_EQ(f.positions_m.size(), 3u);
  EXPECT_EQ(f.positions_m[0], V(1, 0, 0));
  EXPECT_EQ(f.positions_m[1], V(2, 0, 0));
  EXPECT_EQ(f.positions_m[2], V(3, 0, 0));
  EXPECT_EQ(f.occluded, (std::vector<uint8_t>{1, 0, 0}));  // a's flag followed it
}

TEST(MarkerNameMap, ParticlesAbsentFromTheFrameHaveNoMarkerAtTheOrigin) {
  mme::MarkerNameMap map = abc();
  const mme::MappedFrame f = map.map({"b"}, {V(2, 2, 2)}, {});
  EXPECT_TRUE(f.rejection.empty());
  EXPECT_EQ(f.matched, 1u);
  const uint8_t none = mme::OnlineEstimator::kNoMarker;
  EXPECT_EQ(f.occluded, (std::vector<uint8_t>{none, 0, none}));
  EXPECT_EQ(f.positions_m[0], V::Zero());
  EXPECT_EQ(f.positions_m[1], V(2, 2, 2));
  EXPECT_EQ(f.positions_m[2], V::Zero());
}

TEST(MarkerNameMap, UnknownNamesAreIgnoredAndReportedOncePerNameList) {
  mme::MarkerNameMap map = abc();
  const std::vector<std::string> names = {"a", "stray", "b", "other", "c"};
  const std::vector<V> x = {V(1, 0, 0), V(9, 9, 9), V(2, 0, 0), V(8, 8, 8), V(3, 0, 0)};
  mme::MappedFrame f = map.map(names, x, {});
  EXPECT_TRUE(f.rejection.empty());
  EXPECT_EQ(f.matched, 3u);
  EXPECT_EQ(f.unknown, 2u);
  EXPECT_EQ(f.example_unknown, "stray");
  EXPECT_EQ(f.warning,
            "2 marker names in the input are not model particles (ignored), e.g. 'stray'");
  EXPECT_EQ(f.positions_m[2], V(3, 0, 0));
  EXPECT_EQ(f.occluded, (std::vector<uint8_t>{0, 0, 0}));

  // The same name list again: no new warning, the counts are still known.
  f = map.map(names, x, {});
  EXPECT_FALSE(f.names_changed);
  EXPECT_TRUE(f.warning.empty());
  EXPECT_EQ(f.unknown, 2u);
  EXPECT_EQ(f.example_unknown, "stray");

  // Another list: rebuilt and reported again; then the first list once more is a change too.
  f = map.map({"other", "a"}, {V(8, 8, 8), V(1, 0, 0)}, {});
  EXPECT_TRUE(f.names_changed);
  EXPECT_EQ(f.warning,
            "1 marker names in the input are not model particles (ignored), e.g. 'other'");
  f = map.map(names, x, {});
  EXPECT_TRUE(f.names_changed);
  EXPECT_FALSE(f.warning.empty());
}

TEST(MarkerNameMap, AFrameWithNoKnownNameIsRefused) {
  mme::MarkerNameMap map = abc();
  const mme::MappedFrame f = map.map({"x", "y"}, {V(1, 0, 0), V(2, 0, 0)}, {});
  EXPECT_EQ(f.matched, 0u);
  EXPECT_EQ(f.rejection, "no marker name matches a model particle");
  EXPECT_EQ(f.unknown, 2u);
  EXPECT_FALSE(f.warning.empty());
}

TEST(MarkerNameMap, UnequalLengthsAreRefusedWithTheNodesReason) {
  mme::MarkerNameMap map = abc();
  EXPECT_EQ(map.map({"a", "b"}, {V(1, 0, 0)}, {}).rejection,
            "names, positions and occluded differ in length");
  EXPECT_EQ(map.map({"a"}, {V(1, 0, 0)}, {0, 0}).rejection,
            "names, positions and occluded differ in length");
}

TEST(MarkerNameMap, NoNamesMeansParticleOrderAndPassesThrough) {
  mme::MarkerNameMap map = abc();
  // The estimator checks the size; the map does not (a point cloud of another size passes).
  const mme::MappedFrame f = map.map({}, {V(1, 0, 0), V(2, 0, 0)}, {0, 1});
  EXPECT_TRUE(f.rejection.empty());
  EXPECT_EQ(f.positions_m, (std::vector<V>{V(1, 0, 0), V(2, 0, 0)}));
  EXPECT_EQ(f.occluded, (std::vector<uint8_t>{0, 1}));
  EXPECT_FALSE(f.names_changed);
}

TEST(MarkerNameMap, ALaterMarkerOfTheSameNameWins) {
  mme::MarkerNameMap map = abc();
  const mme::MappedFrame f = map.map({"a", "a"}, {V(1, 0, 0), V(5, 0, 0)}, {1, 0});
  EXPECT_EQ(f.positions_m[0], V(5, 0, 0));
  EXPECT_EQ(f.occluded[0], 0);
  EXPECT_EQ(f.matched, 2u);
}

TEST(MarkerNameMap, NewParticlesRebuildTheIndexAndReportUnknownNamesAgain) {
  mme::MarkerNameMap map = abc();
  const std::vector<std::string> names = {"a", "d"};
  const std::vector<V> x = {V(1, 0, 0), V(4, 0, 0)};
  mme::MappedFrame f = map.map(names, x, {});
  EXPECT_EQ(f.unknown, 1u);
  EXPECT_EQ(f.positions_m.size(), 3u);
  map.map(names, x, {});  // cached

  map.setParticles({"d", "a"});  // a model with other particles was loaded
  EXPECT_EQ(map.particles(), (std::vector<std::string>{"d", "a"}));
  f = map.map(names, x, {});
  EXPECT_TRUE(f.names_changed);
  EXPECT_EQ(f.unknown, 0u);
  EXPECT_EQ(f.matched, 2u);
  ASSERT_EQ(f.positions_m.size(), 2u);
  EXPECT_EQ(f.positions_m[0], V(4, 0, 0));
  EXPECT_EQ(f.positions_m[1], V(1, 0, 0));

  // The same particles again (a reload of the same model): its unknown names are said again.
  map.setParticles({"d", "a"});
  f = map.map({"a", "zz"}, {V(1, 0, 0), V(0, 0, 0)}, {});
  EXPECT_FALSE(f.warning.empty());
  map.setParticles({"d", "a"});
  f = map.map({"a", "zz"}, {V(1, 0, 0), V(0, 0, 0)}, {});
  EXPECT_TRUE(f.names_changed);
  EXPECT_EQ(f.warning,
            "1 marker names in the input are not model particles (ignored), e.g. 'zz'");
}

}  // namespace
