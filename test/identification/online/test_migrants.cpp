// The island model in the online estimator: another island's best individuals enter the
// population when they are better, migrants of another parameter list are refused with a reason
// and change nothing, and the queue of waiting batches stays bounded.
#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/online/migrants.h"
#include "motion_model_estimation/identification/online/online_estimator.h"
#include "test_helpers.h"

namespace {

void feed(mme::OnlineEstimator* estimator, const mme::Trajectory& data, int first, int count) {
  const int n = data.numMarkers();
  for (int t = first; t < first + count; ++t) {
    std::vector<Eigen::Vector3d> x(data.positions_m.begin() + t * n, data.positions_m.begin() + (t + 1) * n);
    ASSERT_EQ(estimator->addFrame(data.times_s[t], x, {}), "");
  }
}

struct Islands {
  mme::Model truth = mme::test::smallObject();
  mme::Model search = mme::test::withoutValues(truth);
  mme::Trajectory data = mme::simulateTrajectory(truth, 100, 100.0);
  mme::OnlineEstimatorOptions options(uint64_t seed) const {
    mme::OnlineEstimatorOptions o;
    o.window_frames = 60;
    o.generations_per_update = 1;
    o.update_budget_s = 10.0;
    o.es.population = 20;
    o.es.offspring = 20;
    o.es.refine_period = 0;  // the search alone: the test's outcome does not hang on a thread
    o.cost = mme::CostChoice::kShortTerm;
    o.es.seed = seed;
    return o;
  }
};

TEST(Migrants, ParameterMismatchNamesTheFirstDifference) {
  const std::vector<std::string> ours = {"a/stiffness", "a/rest_length", "b/stiffness"};
  EXPECT_EQ(mme::parameterMismatch(ours, ours), "");
  const std::string swapped =
      mme::parameterMismatch(ours, {"a/rest_length", "a/stiffness", "b/stiffness"});
  EXPECT_NE(swapped.find("parameter 0"), std::string::npos) << swapped;
  EXPECT_NE(swapped.find("'a/rest_length' in the migrants"), std::string::npos) << swapped;
  const std::string missing = mme::parameterMismatch(ours, {"a/stiffness", "a/rest_length"});
  EXPECT_NE(missing.find("'b/stiffness' is missing"), std::string::npos) << missing;
  const std::string extra =
      mme::parameterMismatch(ours, {"a/stiffness", "a/rest_length", "b/stiffness", "gravity"});
  EXPECT_NE(extra.find("'gravity' is not searched here"), std::string::npos) << extra;
}

TEST(Migrants, NoEmigrantsBeforeTheFirstUpdate) {
  Islands f;
  mme::OnlineEstimator island(f.search, f.options(1));
  feed(&island, f.data, 0, 60);
  EXPECT_TRUE(island.emigrants(3).individuals.empty());
  ASSERT_TRUE(island.update());
  const mme::MigrantBatch batch = island.emigrants(3);
  ASSERT_EQ(batch.individuals.size(), 3u);
  EXPECT_EQ(batch.parameter_names, island.estimate().parameter_names);
  EXPECT_EQ(batch.seed, 1u);
  EXPECT_EQ(batch.generation, 1u);
  EXPECT_DOUBLE_EQ(batch.window_start_time_s, f.data.times_s[0]);
  EXPECT_DOUBLE_EQ(batch.window_end_time_s, f.data.times_s[59]);
  EXPECT_LE(batch.individuals[0].cost, batch.individuals[2].cost);  // best first
}

// A far-searched island's best individuals enter a young island's population at its next
// update, re-evaluated on its own window: its best is then at least as good as theirs.
TEST(Migrants, BetterMigrantsEnterAtTheNextUpdate) {
  Islands f;
  mme::OnlineEstimator old_island(f.search, f.options(1));
  mme::OnlineEstimator young_island(f.search, f.options(2));
  feed(&old_island, f.data, 0, 60);
  feed(&young_island, f.data, 0, 60);
  for (int u = 0; u < 40; ++u) ASSERT_TRUE(old_island.update());
  ASSERT_TRUE(young_island.update());
  const double young_before = young_island.estimate().global_cost;
  mme::MigrantBatch batch = old_island.emigrants(3);
  batch.island_id = "old";
  const double best_migrant = batch.individuals[0].cost;
  ASSERT_LT(best_migrant, young_before);
  EXPECT_EQ(young_island.receiveMigrants(batch), "");
  EXPECT_EQ(young_island.migrationCounters().received, 3u);
  EXPECT_EQ(young_island.migrationCounters().applied, 0u);  // waits for the update
  ASSERT_TRUE(young_island.update());
  const mme::MigrationCounters c = young_island.migrationCounters();
  EXPECT_EQ(c.applied, 3u);
  EXPECT_GE(c.accepted, 1u);
  EXPECT_EQ(c.refused, 0u);
  EXPECT_LE(young_island.estimate().global_cost, best_migrant * (1.0 + 1e-12));
}

// Migrants naming the parameters in another order (another model file) are refused with the
// reason, and the island's search goes on exactly as its twin's that received nothing.
TEST(Migrants, OtherParametersAreRefusedAndChangeNothing) {
  Islands f;
  mme::OnlineEstimator sender(f.search, f.options(1));
  mme::OnlineEstimator island(f.search, f.options(2));
  mme::OnlineEstimator twin(f.search, f.options(2));
  for (mme::OnlineEstimator* e : {&sender, &island, &twin}) {
    feed(e, f.data, 0, 60);
    for (int u = 0; u < 3; ++u) ASSERT_TRUE(e->update());
  }
  mme::MigrantBatch batch = sender.emigrants(3);
  ASSERT_GE(batch.parameter_names.size(), 2u);
  std::swap(batch.parameter_names[0], batch.parameter_names[1]);
  const std::string why = island.receiveMigrants(batch);
  EXPECT_NE(why.find("parameter 0 is '" + batch.parameter_names[0] + "'"), std::string::npos) << why;
  mme::MigrantBatch short_genes = sender.emigrants(1);
  short_genes.individuals[0].genes.pop_back();
  EXPECT_NE(island.receiveMigrants(short_genes).find("genes"), std::string::npos);
  const mme::MigrationCounters c = island.migrationCounters();
  EXPECT_EQ(c.refused, 4u);
  EXPECT_EQ(c.received, 0u);
  ASSERT_TRUE(island.update());
  ASSERT_TRUE(twin.update());
  EXPECT_EQ(island.estimate().values, twin.estimate().values);
  EXPECT_EQ(island.estimate().evaluations, twin.estimate().evaluations);
  EXPECT_EQ(island.migrationCounters().applied, 0u);
}

// Batches beyond migrant_queue_batches push out the oldest (counted); only the kept ones are
// re-evaluated at the update.
TEST(Migrants, TheQueueIsBoundedAndDropsTheOldest) {
  Islands f;
  mme::OnlineEstimator sender(f.search, f.options(1));
  mme::OnlineEstimatorOptions options = f.options(2);
  options.migrant_queue_batches = 2;
  mme::OnlineEstimator island(f.search, options);
  feed(&sender, f.data, 0, 60);
  feed(&island, f.data, 0, 60);
  ASSERT_TRUE(sender.update());
  ASSERT_TRUE(island.update());
  for (int b = 0; b < 5; ++b) EXPECT_EQ(island.receiveMigrants(sender.emigrants(3)), "");
  mme::MigrationCounters c = island.migrationCounters();
  EXPECT_EQ(c.received, 15u);
  EXPECT_EQ(c.dropped, 9u);
  ASSERT_TRUE(island.update());
  c = island.migrationCounters();
  EXPECT_EQ(c.applied, 6u);
  mme::OnlineEstimatorOptions bad = options;
  bad.migrant_queue_batches = 0;
  EXPECT_NE(mme::validateOptions(bad).find("migrant_queue_batches"), std::string::npos);
}

}  // namespace

namespace {

// A message's flat arrays become the batch's individuals when their lengths match the counts;
// otherwise the reason names the counts and nothing is read, and the receiver counts the
// announced migrants as refused (malformed messages join the refused count, not only a warning).
TEST(Migrants, MalformedArraysAreRefusedAndCounted) {
  mme::MigrantBatch batch;
  batch.parameter_names = {"s01/stiffness", "s01/rest_length"};
  const std::vector<double> genes{1.0, -2.0, 3.0, -4.0}, mutabilities{0.1, 0.2, 0.3, 0.4}, costs{1e-6, 2e-6};
  ASSERT_EQ(mme::unflattenMigrants(2, genes, mutabilities, costs, &batch), "");
  ASSERT_EQ(batch.individuals.size(), 2u);
  EXPECT_EQ(batch.individuals[1].genes, (std::vector<double>{3.0, -4.0}));
  EXPECT_EQ(batch.individuals[1].mutability, (std::vector<double>{0.3, 0.4}));
  EXPECT_EQ(batch.individuals[1].cost, 2e-6);

  const std::vector<double> short_genes{1.0, -2.0, 3.0};
  std::string why = mme::unflattenMigrants(2, short_genes, mutabilities, costs, &batch);
  EXPECT_NE(why.find("need 4 genes"), std::string::npos) << why;
  EXPECT_TRUE(batch.individuals.empty());
  why = mme::unflattenMigrants(3, genes, mutabilities, costs, &batch);  // more announced than sent
  EXPECT_NE(why.find("migrant_count 3"), std::string::npos) << why;
  why = mme::unflattenMigrants(0xffffffffu, genes, mutabilities, costs, &batch);  // a wild count
  EXPECT_FALSE(why.empty());
  EXPECT_TRUE(batch.individuals.empty());

  Islands f;
  mme::OnlineEstimator island(f.search, f.options(2));
  EXPECT_EQ(island.refuseMigrants(3, why), why);
  const mme::MigrationCounters c = island.migrationCounters();
  EXPECT_EQ(c.refused, 3u);
  EXPECT_EQ(c.received, 0u);
}

}  // namespace
