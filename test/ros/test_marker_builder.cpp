// buildMarkers (ros/marker_builder.h): what rviz is sent for one snapshot.
#include <gtest/gtest.h>

#include <string>
#include <tuple>

#include "motion_model_estimation/ros/marker_builder.h"

namespace {

using visualization_msgs::Marker;
using visualization_msgs::MarkerArray;

const Marker& find(const MarkerArray& a, const std::string& ns, int id) {
  for (const Marker& m : a.markers)
    if (m.ns == ns && m.id == id) return m;
  static Marker none;
  ADD_FAILURE() << "no marker " << ns << "/" << id;
  return none;
}

/// A body at negative coordinates with one marker occluded (the window holds 0, 0, 0 there, as
/// it does for an anchor, which has no marker) and one bond to it.
mme::VisualisationSnapshot bodyWithAGap() {
  mme::VisualisationSnapshot s;
  s.stamp_s = 12.5;
  s.observed = {{-5.0, -3.0, -1.0}, {-4.0, -2.5, -0.5}, {0.0, 0.0, 0.0}};
  s.observed_occluded = {0, 0, 1};
  s.predicted = {{-5.0, -3.0, -1.0}, {-4.0, -2.5, -0.5}, {-4.5, -2.0, -0.8}};
  s.bonds = {{0, 1}, {1, 2}};
  s.bond_values = {0.0, 0.05};
  s.text = "generation 3";
  return s;
}

TEST(MarkerBuilder, OnlySeenMarkersAreDrawnAsObservedAndBonded) {
  mme::MarkerStyle style;
  style.frame_id = "world";
  const MarkerArray a = mme::buildMarkers(bodyWithAGap(), style);
  const Marker& observed = find(a, "observed", 0);
  ASSERT_EQ(observed.points.size(), 2u);
  EXPECT_EQ(observed.points[1].x, -4.0);
  EXPECT_EQ(observed.header.frame_id, "world");
  EXPECT_DOUBLE_EQ(observed.header.stamp.toSec(), 12.5);
  EXPECT_EQ(find(a, "predicted", 0).points.size(), 3u);  // the model places the hidden one
  EXPECT_EQ(find(a, "bonds", 0).points.size(), 2u);      // the bond to the hidden marker is not drawn
}

TEST(MarkerBuilder, APointOfTheModelWithoutAMarkerIsNotDrawn) {
  // The third particle an anchor 20 m off: drawn, it would stretch rviz's view to it.
  mme::VisualisationSnapshot s = bodyWithAGap();
  s.predicted[2] = {20.0, 20.0, 20.0};
  s.reconstructed = s.predicted;
  s.reconstruction_trails = {{s.predicted[0], s.predicted[0]}, {s.predicted[1], s.predicted[1]},
                             {s.predicted[2], s.predicted[2]}};
  s.model_only = {0, 0, 1};
  const MarkerArray a = mme::buildMarkers(s, mme::MarkerStyle());
  for (const auto& [ns, id, points] : {std::make_tuple("predicted", 0, 2u),
                                        std::make_tuple("reconstruction", 0, 2u),
                                        std::make_tuple("reconstruction", 1, 4u)}) {
    const Marker& m = find(a, ns, id);
    EXPECT_EQ(m.points.size(), points) << ns << "/" << id;
    for (const auto& p : m.points) EXPECT_LT(p.x, 0.0) << ns << "/" << id;
  }
  // A hidden marker (not model-only) is still placed by the model.
  s.model_only = {0, 0, 0};
  const MarkerArray all = mme::buildMarkers(s, mme::MarkerStyle());
  EXPECT_EQ(find(all, "predicted", 0).points.size(), 3u);
}

TEST(MarkerBuilder, TheStatusTextStandsAboveTheSeenMarkers) {
  // Not above the hidden marker's 0, 0, 0: on a body in negative coordinates that put the text
  // metres away from it.
  mme::MarkerStyle style;
  style.particle_diameter_m = 0.02;
  const MarkerArray a = mme::buildMarkers(bodyWithAGap(), style);  // outlives the reference
  const Marker& text = find(a, "status", 0);
  EXPECT_EQ(text.text, "generation 3");
  EXPECT_DOUBLE_EQ(text.pose.position.x, -4.0);
  EXPECT_DOUBLE_EQ(text.pose.position.y, -2.5);
  EXPECT_DOUBLE_EQ(text.pose.position.z, -0.5 + 4.0 * 0.02);
}

}  // namespace
