// The island model: one island is the plain evolution strategy, the result does not depend on
// the thread count, migration carries a good individual to the next island (ring) or to all
// (broadcast), bad options are refused, and on cable objects (several threshold intervals:
// several local minima) three islands beat one population of 300 (the same evaluations per
// generation).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <memory>
#include <string>
#include <vector>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/short_term_cost.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/identifier.h"
#include "motion_model_estimation/identification/search/island_model.h"
#include "motion_model_estimation/scenes/random_object.h"
#include "test_helpers.h"

namespace {

using Fixture = mme::test::SmallObjectFixture;

mme::EsOptions smallEs() {
  mme::EsOptions o;
  o.population = 20;
  o.offspring = 20;
  o.seed = 3;
  return o;
}

TEST(IslandModel, OneIslandIsTheEvolutionStrategyBitForBit) {
  Fixture f;
  const mme::ParameterSpace space(f.search, f.data);
  mme::EvolutionStrategy es(space, smallEs());
  mme::IslandModel islands(space, smallEs(), mme::IslandOptions{});
  es.setCost(f.cost);
  islands.setCost(f.cost);
  for (int g = 0; g < 12; ++g) {  // refinements at 5 and 10 included
    es.step();
    islands.step();
  }
  ASSERT_EQ(islands.islandCount(), 1);
  EXPECT_EQ(islands.evaluations(), es.evaluations());
  EXPECT_EQ(islands.refinements(), es.refinements());
  ASSERT_EQ(islands.island(0).population().size(), es.population().size());
  for (size_t i = 0; i < es.population().size(); ++i) {
    EXPECT_EQ(islands.island(0).population()[i].genes, es.population()[i].genes);
    EXPECT_EQ(islands.island(0).population()[i].cost, es.population()[i].cost);
  }
  EXPECT_EQ(islands.migrations(), 0);
}

TEST(IslandModel, IslandSeedsDifferAndTheFirstIsTheRunsSeed) {
  EXPECT_EQ(mme::islandSeed(42, 0), 42u);
  EXPECT_NE(mme::islandSeed(42, 1), mme::islandSeed(42, 2));
  EXPECT_NE(mme::islandSeed(42, 1), mme::islandSeed(43, 1));
  EXPECT_NE(mme::islandSeed(42, 1), 42u);
}

TEST(IslandModel, SameSeedAndIslandsGiveTheSameResultOnOneTwoAndSixThreads) {
  Fixture f;
  mme::IdentifyOptions o;
  o.generations = 40;
  o.es.population = 20;
  o.es.offspring = 20;
  o.islands.islands = 3;
  o.islands.migration_period_generations = 4;
  o.estimate_std = false;
  o.es.threads = 1;
  const mme::IdentifyResult one = mme::identifyModel(f.search, f.data, o);
  o.es.threads = 2;  // two islands step at a time
  const mme::IdentifyResult two = mme::identifyModel(f.search, f.data, o);
  o.es.threads = 6;  // three islands at a time, each evaluating its children on two threads
  const mme::IdentifyResult six = mme::identifyModel(f.search, f.data, o);
  EXPECT_EQ(one.values, six.values);
  EXPECT_EQ(one.evaluations, six.evaluations);
  EXPECT_EQ(one.values, two.values);
  EXPECT_EQ(one.global_cost, two.global_cost);
  EXPECT_EQ(one.evaluations, two.evaluations);
  EXPECT_EQ(one.island_evaluations, two.island_evaluations);
  EXPECT_EQ(one.island_immigrants_accepted, two.island_immigrants_accepted);
  EXPECT_EQ(one.best_island, two.best_island);
  ASSERT_EQ(one.island_evaluations.size(), 3u);
  EXPECT_GT(one.migrations, 0);
  uint64_t sum = 0;
  for (uint64_t e : one.island_evaluations) sum += e;
  EXPECT_EQ(sum, one.evaluations);
}

TEST(IslandModel, OneIslandIdentifiesExactlyAsWithoutIslands) {
  Fixture f;
  mme::IdentifyOptions o;
  o.generations = 30;
  o.es.population = 20;
  o.es.offspring = 20;
  o.estimate_std = false;
  const mme::IdentifyResult plain = mme::identifyModel(f.search, f.data, o);
  o.islands.migration_period_generations = 3;  // no migration with one island
  const mme::IdentifyResult one = mme::identifyModel(f.search, f.data, o);
  EXPECT_EQ(plain.values, one.values);
  EXPECT_EQ(plain.evaluations, one.evaluations);
  ASSERT_EQ(one.island_evaluations.size(), 1u);
  EXPECT_EQ(one.island_evaluations[0], one.evaluations);
  EXPECT_EQ(one.migrations, 0);
}

// An individual only island 0 has (the truth, offered to it) reaches island 1 at the next
// migration and not island 2 (the ring sends to the next island only); broadcast reaches both.
TEST(IslandModel, MigrationCarriesAGoodIndividualToTheNextIsland) {
  Fixture f;
  const mme::ParameterSpace space(f.search, f.data);
  const std::vector<double> truth = space.toSearch(f.true_values);
  for (mme::MigrationTopology topology : {mme::MigrationTopology::kRing, mme::MigrationTopology::kBroadcast}) {
    mme::EsOptions es = smallEs();
    es.refine_period = 0;  // nothing but migration brings an island the truth
    mme::IslandOptions io;
    io.islands = 3;
    io.migration_period_generations = 2;
    io.migrants = 1;
    io.topology = topology;
    mme::IslandModel islands(space, es, io);
    islands.setCost(f.cost);
    islands.step();
    ASSERT_TRUE(islands.island(0).offer(truth));
    for (int i = 1; i < 3; ++i) ASSERT_NE(islands.island(i).best().genes, truth);
    islands.step();  // generation 2: migration
    EXPECT_EQ(islands.migrations(), 1);
    EXPECT_EQ(islands.island(1).best().genes, truth) << mme::migrationTopologyName(topology);
    EXPECT_GE(islands.immigrantsAccepted(1), 1u);
    if (topology == mme::MigrationTopology::kRing)
      EXPECT_NE(islands.island(2).best().genes, truth);
    else
      EXPECT_EQ(islands.island(2).best().genes, truth);
    EXPECT_EQ(islands.bestIsland(), 0);  // the lowest index among equal costs
  }
}

TEST(IslandModel, BadOptionsAreRefusedWithTheirName) {
  mme::IslandOptions o;
  EXPECT_EQ(mme::validateOptions(o), "");
  o.islands = 0;
  EXPECT_NE(mme::validateOptions(o).find("islands"), std::string::npos);
  o = mme::IslandOptions{};
  o.migration_period_generations = 0;
  EXPECT_NE(mme::validateOptions(o).find("migration_period_generations"), std::string::npos);
  o = mme::IslandOptions{};
  o.migrants = -1;
  EXPECT_NE(mme::validateOptions(o).find("migrants"), std::string::npos);
  Fixture f;
  mme::IdentifyOptions io;
  io.islands.islands = 0;
  EXPECT_THROW(mme::identifyModel(f.search, f.data, io), mme::InputError);
  mme::MigrationTopology t;
  EXPECT_TRUE(mme::parseMigrationTopology("broadcast", &t));
  EXPECT_EQ(t, mme::MigrationTopology::kBroadcast);
  EXPECT_FALSE(mme::parseMigrationTopology("star", &t));
}

/// The stability map's conditional cell (bench_islands, bench/peers/instances.cpp's
/// cableProblem): a random 15-particle object with 10 spring types, the first `cables` of them
/// cables (active only when stretched beyond a free min_distance), 60 noise-free frames.
struct CableScene {
  CableScene(int cables, uint64_t seed) {
    mme::RandomObjectSpec spec;
    spec.bond_types = 10;
    spec.cable_types = cables;
    spec.particles = 15;
    spec.bonds = 31;
    spec.frame_rate_hz = 100.0;
    spec.seed = seed;
    truth = mme::makeRandomObject(spec);
    search = mme::test::withoutValues(truth);
    data = mme::simulateTrajectory(truth, 60, 100.0);
  }
  /// Every threshold of `values` in the truth's flat interval (between observed lengths): the
  /// global minimum's basin, whatever the interval's middle gives against the truth.
  bool inTheTruthsIntervals(const std::vector<double>& values) const {
    const mme::ParameterSpace space(search, data);
    const std::vector<double> genes = space.toSearch(values);
    const std::vector<double> truth_genes = space.toSearch(mme::getValues(truth, space.refs()));
    for (size_t k = 0; k < space.size(); ++k) {
      const mme::Gene& g = space.gene(k);
      auto interval = [&g](double x) {
        return std::upper_bound(g.breakpoints.begin(), g.breakpoints.end(), x) - g.breakpoints.begin();
      };
      if (!g.smooth && interval(genes[k]) != interval(truth_genes[k])) return false;
    }
    return true;
  }
  mme::Model truth, search;
  mme::Trajectory data;
};

// Islands as child processes (identify --island-processes) give the threaded islands' answer
// bit for bit on a conditional scene (5 cable types: thresholds, several basins), with the same
// evaluations, migrations and immigrants per island.
TEST(IslandModel, ProcessesGiveTheThreadsResultBitForBit) {
  const CableScene scene(5, 4003);
  mme::IdentifyOptions o = mme::identifyOptionsFor(mme::Preset::kDefault);
  o.es.seed = 3;
  o.estimate_std = false;
  o.generations = 30;
  o.patience_generations = 0;  // every generation runs: six migrations
  o.es.population = o.es.offspring = 40;
  o.islands.islands = 3;
  o.islands.migration_period_generations = 5;
  const mme::IdentifyResult threads = mme::identifyModel(scene.search, scene.data, o);
  o.islands.processes = true;
  const mme::IdentifyResult processes = mme::identifyModel(scene.search, scene.data, o);
  EXPECT_EQ(threads.values, processes.values);
  EXPECT_EQ(threads.global_cost, processes.global_cost);
  EXPECT_EQ(threads.evaluations, processes.evaluations);
  EXPECT_EQ(threads.generations, processes.generations);
  EXPECT_EQ(threads.island_evaluations, processes.island_evaluations);
  EXPECT_EQ(threads.island_immigrants_accepted, processes.island_immigrants_accepted);
  EXPECT_EQ(threads.migrations, processes.migrations);
  EXPECT_EQ(threads.best_island, processes.best_island);
  EXPECT_GE(processes.migrations, 5);
  uint64_t accepted = 0;
  for (uint64_t a : processes.island_immigrants_accepted) accepted += a;
  EXPECT_GT(accepted, 0u);
}

// An island's process that dies mid-run (the test hook makes island 1 kill itself at its second
// generation) ends the run with an error naming the island and how it ended, never a hang; the
// other processes are reaped.
TEST(IslandModel, AnIslandProcessThatDiesEndsTheRunNamingIt) {
  Fixture f;
  const mme::ParameterSpace space(f.search, f.data);
  mme::IslandOptions io;
  io.islands = 3;
  io.processes = true;
  ::setenv(mme::IslandProcesses::kTestDieVariable, "1", 1);
  std::string message;
  {
    mme::IslandModel islands(space, smallEs(), io);
    islands.setCost(f.cost);
    islands.step();  // the processes start, every island steps once
    try {
      islands.step();
    } catch (const std::runtime_error& e) {
      message = e.what();
    }
  }  // the surviving processes are stopped here
  ::unsetenv(mme::IslandProcesses::kTestDieVariable);
  EXPECT_NE(message.find("island 1 "), std::string::npos) << message;
  EXPECT_NE(message.find("killed by signal 9"), std::string::npos) << message;
}

// Several local minima (one per wrong threshold interval of 10 cable types): `identify --islands
// 3` (three populations of 100, broadcast migration) against one population of 300 (the same
// evaluations per generation, the same stop rules), 10 seeds (the map's instances 4001..4010).
// Measured: the islands put every threshold in the truth's interval in 10/10 runs, the single
// population in 6/10, with fewer evaluations (109 178 against 142 434 over the ten runs); every
// parameter within 1 %: 5/10 against 3/10 (the intervals' middles allow at most 5/10 here).
// The assertions leave one run of that margin (a compiler's rounding may move a run).
TEST(IslandModel, ThreeIslandsBeatOnePopulationOfTheirSizeOnTenCableTypes) {
  int islands_right = 0, one_right = 0, islands_ok = 0, one_ok = 0;
  uint64_t islands_evaluations = 0, one_evaluations = 0;
  for (int seed = 1; seed <= 10; ++seed) {
    const CableScene scene(10, 4000 + seed);
    const std::vector<double> truth = mme::getValues(scene.truth, mme::freeParameters(scene.truth));
    mme::IdentifyOptions o = mme::identifyOptionsFor(mme::Preset::kDefault);
    o.es.seed = static_cast<uint64_t>(seed);
    o.estimate_std = false;
    o.generations = 150;  // the map's budget of 45 000 evaluations in generations of 300
    o.es.population = o.es.offspring = 300;
    const mme::IdentifyResult one = mme::identifyModel(scene.search, scene.data, o);
    o.es.population = o.es.offspring = 100;
    o.islands.islands = 3;
    const mme::IdentifyResult islands = mme::identifyModel(scene.search, scene.data, o);
    one_right += scene.inTheTruthsIntervals(one.values);
    islands_right += scene.inTheTruthsIntervals(islands.values);
    one_ok += mme::test::maxRelativeError(one.values, truth) < 0.01;
    islands_ok += mme::test::maxRelativeError(islands.values, truth) < 0.01;
    one_evaluations += one.evaluations;
    islands_evaluations += islands.evaluations;
  }
  std::printf("right intervals: islands %d/10, one population %d/10; within 1 %%: %d/10, %d/10; "
              "evaluations %llu, %llu\n", islands_right, one_right, islands_ok, one_ok,
              static_cast<unsigned long long>(islands_evaluations), static_cast<unsigned long long>(one_evaluations));
  EXPECT_GE(islands_right, one_right + 3);
  EXPECT_GE(islands_ok, one_ok + 1);
  EXPECT_LE(islands_evaluations, one_evaluations);
}

}  // namespace
