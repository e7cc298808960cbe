// The node's message conversions (ros/conversions.h), without a master: MarkerFrame points and
// their refusal, PointCloud2 decoding (NaN occluded, truncated clouds refused), tf's transform
// as a pose, and the estimate as ~estimate publishes it.
#include <gtest/gtest.h>

#include <cmath>
#include <sensor_msgs/point_cloud2_iterator.h>

#include "motion_model_estimation/ros/conversions.h"

namespace {

TEST(Conversions, MarkerFramePointsAndUnequalArraysRefused) {
  motion_model_estimation::MarkerFrame msg;
  msg.names = {"a", "b"};
  msg.positions.resize(2);
  msg.positions[1].x = 0.5;
  msg.occluded = {0, 1};
  mme::ObservedPoints points;
  ASSERT_EQ(mme::fromMarkerFrame(msg, &points), "");
  ASSERT_EQ(points.positions_m.size(), 2u);
  EXPECT_EQ(points.positions_m[1].x(), 0.5);
  EXPECT_EQ(points.occluded, (std::vector<uint8_t>{0, 1}));
  msg.occluded = {0};
  EXPECT_NE(mme::fromMarkerFrame(msg, &points), "");
}

sensor_msgs::PointCloud2 cloud(const std::vector<Eigen::Vector3f>& points) {
  sensor_msgs::PointCloud2 msg;
  sensor_msgs::PointCloud2Modifier modifier(msg);
  modifier.setPointCloud2FieldsByString(1, "xyz");
  modifier.resize(points.size());
  sensor_msgs::PointCloud2Iterator<float> it(msg, "x");
  for (const Eigen::Vector3f& p : points) {
    it[0] = p.x();
    it[1] = p.y();
    it[2] = p.z();
    ++it;
  }
  return msg;
}

TEST(Conversions, PointCloudDecodedInPointOrderWithNaNOccluded) {
  const float nan = std::nanf("");
  sensor_msgs::PointCloud2 msg = cloud({{1, 2, 3}, {nan, 0, 0}, {-1, 0.5, 2}});
  mme::ObservedPoints points;
  ASSERT_EQ(mme::fromPointCloud(msg, &points), "");
  ASSERT_EQ(points.positions_m.size(), 3u);
  EXPECT_EQ(points.positions_m[2], Eigen::Vector3d(-1, 0.5, 2));
  EXPECT_EQ(points.occluded, (std::vector<uint8_t>{0, 1, 0}));
  msg.data.resize(msg.data.size() - 1);  // truncated
  EXPECT_EQ(mme::fromPointCloud(msg, &points), "PointCloud2 without x/y/z fields or with truncated data");
  sensor_msgs::PointCloud2 no_fields;
  no_fields.width = 1;
  no_fields.height = 1;
  EXPECT_NE(mme::fromPointCloud(no_fields, &points), "");
}

TEST(Conversions, TransformAsAPose) {
  geometry_msgs::Transform t;
  t.translation.x = 1.0;
  t.rotation.z = std::sqrt(0.5);  // 90 degrees about z
  t.rotation.w = std::sqrt(0.5);
  const Eigen::Vector3d moved = mme::fromTransform(t) * Eigen::Vector3d(1, 0, 0);
  EXPECT_NEAR((moved - Eigen::Vector3d(1, 1, 0)).norm(), 0.0, 1e-12);
}

TEST(Conversions, EstimateAsPublished) {
  mme::Estimate e;
  e.generation = 7;
  e.parameter_names = {"s/stiffness", "s/damping"};
  e.values = {10.0, 0.2};
  e.std_devs = {0.1, std::nan("")};
  e.parameter_flags = {mme::ParameterFlag::kNone, mme::ParameterFlag::kUnidentifiable};
  e.estimator = mme::Estimator::kOutputError;
  e.noise_std_m = 1e-4;
  const motion_model_estimation::ModelEstimate msg = mme::toModelEstimateMsg(e, "world", ros::Time(5.0));
  EXPECT_EQ(msg.header.frame_id, "world");
  EXPECT_EQ(msg.header.stamp.toSec(), 5.0);
  EXPECT_EQ(msg.generation, 7u);
  EXPECT_EQ(msg.parameter_names, e.parameter_names);
  EXPECT_EQ(msg.estimator, "output_error");
  EXPECT_EQ(msg.parameter_flags, (std::vector<std::string>{"", "unidentifiable"}));
  EXPECT_EQ(msg.noise_std_m, 1e-4);
}

// Migrants: a batch survives the trip through the message (flattened migrant by migrant), and a
// message whose arrays do not agree with its counts is refused with the sizes.
TEST(Conversions, MigrantsRoundTripAndInconsistentArraysRefused) {
  mme::MigrantBatch batch;
  batch.island_id = "/island_1/estimator";
  batch.seed = 7;
  batch.generation = 40;
  batch.parameter_names = {"s01/stiffness", "s01/rest_length"};
  batch.individuals.resize(2);
  batch.individuals[0].genes = {1.0, -2.0};
  batch.individuals[0].mutability = {0.1, 0.2};
  batch.individuals[0].cost = 1e-6;
  batch.individuals[1].genes = {3.0, -4.0};
  batch.individuals[1].mutability = {0.3, 0.4};
  batch.individuals[1].cost = 2e-6;
  batch.window_start_time_s = 12.5;
  batch.window_end_time_s = 13.5;
  ros::Time stamp;
  stamp.fromSec(100.25);
  const motion_model_estimation::Migrants msg = mme::toMigrantsMsg(batch, stamp);
  EXPECT_EQ(msg.header.stamp, stamp);
  EXPECT_EQ(msg.migrant_count, 2u);
  EXPECT_EQ(msg.genes, (std::vector<double>{1.0, -2.0, 3.0, -4.0}));
  mme::MigrantBatch back;
  ASSERT_EQ(mme::fromMigrantsMsg(msg, &back), "");
  EXPECT_EQ(back.island_id, batch.island_id);
  EXPECT_EQ(back.seed, 7u);
  EXPECT_EQ(back.generation, 40u);
  EXPECT_EQ(back.parameter_names, batch.parameter_names);
  ASSERT_EQ(back.individuals.size(), 2u);
  EXPECT_EQ(back.individuals[1].genes, batch.individuals[1].genes);
  EXPECT_EQ(back.individuals[1].mutability, batch.individuals[1].mutability);
  EXPECT_EQ(back.individuals[1].cost, 2e-6);
  EXPECT_DOUBLE_EQ(back.window_start_time_s, 12.5);
  EXPECT_DOUBLE_EQ(back.window_end_time_s, 13.5);
  motion_model_estimation::Migrants bad = msg;
  bad.genes.pop_back();
  const std::string why = mme::fromMigrantsMsg(bad, &back);
  EXPECT_NE(why.find("need 4 genes"), std::string::npos) << why;
  EXPECT_TRUE(back.individuals.empty());
}

}  // namespace
