// Muscles in identification: the local-cost sites of a muscle type are its own ends, the
// search space keeps network parameters signed (linear coordinates, symmetric default bounds),
// the equation-error start declines muscle parameters with a reason, and the evolution
// strategy identifies a small scene with one muscle type; on data made without a controller,
// free muscles add nothing (the cost changes by less than 1 %).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "motion_model_estimation/core/short_term_cost.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/estimators/equation_error.h"
#include "motion_model_estimation/identification/identifier.h"
#include "motion_model_estimation/identification/muscles/muscle_placement.h"
#include "motion_model_estimation/identification/estimators/output_error.h"
#include "motion_model_estimation/identification/search/parameter_space.h"
#include "motion_model_estimation/scenes/scenes.h"
#include "test_helpers.h"

namespace {

using mme::Model;

/// muscleObject() with the muscle's gain and network (and, if asked, its spring part) free.
Model freeMuscle(bool spring_part_free) {
  Model m = mme::test::muscleObject();
  mme::BondType& t = m.bond_types[m.bondTypeIndex("m")];
  t.param(mme::kGain).free = true;
  for (mme::Param& p : t.network) p.free = true;
  if (spring_part_free)
    for (mme::ParamId id : {mme::kStiffness, mme::kRestLength, mme::kDamping}) t.param(id).free = true;
  return m;
}

TEST(MuscleIdentification, AMuscleTypesSitesAreItsEndsAndItsNetworkGenesAreSigned) {
  const Model m = freeMuscle(false);
  const mme::Trajectory data = mme::simulateTrajectory(m, 40, 100.0);
  const mme::ParameterSpace space(m, data);
  const int type = m.bondTypeIndex("m");
  EXPECT_EQ(space.sitesOfType()[type], (std::vector<int>{0, 3}));
  for (const mme::Gene& g : space.genes()) {
    if (!g.ref.isNetwork()) {
      EXPECT_TRUE(g.log_scale) << g.ref.name;  // the gain: a positive magnitude
      continue;
    }
    EXPECT_FALSE(g.log_scale) << g.ref.name;
    EXPECT_EQ(g.lower, -g.upper) << g.ref.name;
    EXPECT_EQ(g.upper, g.ref.name == "m/b2" ? 5.0 : 100.0) << g.ref.name;
  }
}

TEST(MuscleIdentification, TheEquationErrorLeavesMuscleParametersToTheSearch) {
  const Model m = freeMuscle(false);
  const mme::Trajectory data = mme::simulateTrajectory(m, 40, 100.0);
  const mme::EquationErrorResult declined = mme::solveEquationError(m, data);
  EXPECT_FALSE(declined.applicable);
  EXPECT_NE(declined.reason.find("'m/gain' does not enter the forces linearly"), std::string::npos)
      << declined.reason;
  // With the muscle fixed, the springs around it are solved as before: the muscle's force is
  // part of the known forces.
  Model springs = mme::test::muscleObject();
  springs.bond_types[springs.bondTypeIndex("s")].param(mme::kStiffness).free = true;
  for (mme::ParamId id : {mme::kStiffness, mme::kRestLength, mme::kDamping})
    springs.bond_types[springs.bondTypeIndex("d")].param(id).free = true;
  // A free rest length of a bond the muscle reads would make its activation unknown.
  Model reads_free = springs;
  reads_free.bond_types[reads_free.bondTypeIndex("s")].param(mme::kRestLength).free = true;
  EXPECT_EQ(mme::solveEquationError(reads_free, data).reason,
            "'s/rest_length' is free and read by a muscle's network");
  const mme::EquationErrorResult sol = mme::solveEquationError(springs, data);
  ASSERT_TRUE(sol.applicable) << sol.reason;
  const std::vector<double> truth = mme::getValues(springs, mme::freeParameters(springs));
  EXPECT_LT(mme::test::maxRelativeError(sol.values, truth), 1e-6);
}

// The muscle's spring part, gain and network (9 parameters, no initial values) from 80 noiseless
// frames. Fitting a network is multimodal: from 6 seeds, 3 (1, 4, 6) recover every parameter to
// round-off and the others stall in local minima (one-step costs 1.4e-7..1.7e-6 m^2), every one
// below the best passive model (the muscle as a plain spring, linear: the equation error solves
// it; 3.0e-6 m^2) but the worst by less than 2x: where a passive fit exists, start the muscles
// from it (muscle_placement.h; test_muscle_placement). Every fit here is on the one-step cost (the
// automatic choice may switch a misfitting model to the output error, a cost on another scale).
// The test asserts exactly that; the default seed is one that recovers.
TEST(MuscleIdentification, TheEvolutionStrategyIdentifiesAMuscleFromNoInitialValues) {
  const Model truth = freeMuscle(true);
  const mme::Trajectory data = mme::simulateTrajectory(truth, 80, 100.0);
  const std::vector<double> want = mme::getValues(truth, mme::freeParameters(truth));
  ASSERT_EQ(want.size(), 9u);

  Model passive = mme::removeMuscles(mme::test::muscleObject());
  mme::BondType& t = passive.bond_types[passive.bondTypeIndex("m")];
  for (mme::ParamId id : {mme::kStiffness, mme::kRestLength, mme::kDamping}) t.param(id).free = true;
  mme::IdentifyOptions passive_options;
  passive_options.generations = 400;
  passive_options.estimate_std = false;
  // One cost for every fit compared: the one-step cost (kAuto may take the passive model's misfit
  // for marker noise and switch to the output error, a cost on another scale).
  passive_options.cost = mme::CostChoice::kShortTerm;
  const double passive_cost =
      mme::identifyModel(mme::test::withoutValues(passive), data, passive_options).global_cost;
  EXPECT_GT(passive_cost, 1e-6);
  EXPECT_LT(passive_cost, 1e-5);

  int recovered = 0, below_passive = 0;
  for (uint64_t seed = 1; seed <= 6; ++seed) {
    mme::IdentifyOptions options;
    options.generations = 400;
    options.patience_generations = 0;  // a network's fit keeps improving after plateaus
    options.es.seed = seed;
    options.estimate_std = false;
    options.cost = mme::CostChoice::kShortTerm;
    const mme::IdentifyResult r = mme::identifyModel(mme::test::withoutValues(truth), data, options);
    const double error = mme::test::maxRelativeError(r.values, want);
    SCOPED_TRACE("seed " + std::to_string(seed) + ": cost " + std::to_string(r.global_cost) +
                 ", largest relative error " + std::to_string(error));
    if (seed == 1) {
      EXPECT_LT(error, 1e-6);
      EXPECT_LT(r.global_cost / data.numFrames(), 1e-26);
    }
    recovered += error < 1e-6;
    below_passive += r.global_cost < passive_cost;
  }
  EXPECT_GE(recovered, 3);
  EXPECT_EQ(below_passive, 6);
}

// The check that muscles do not fit what is not there: data of muscleObject() with the
// muscle's gain 0 (a plain spring: no controller) and 0.1 mm marker noise. The passive model
// (every spring part free) is identified; then the muscle's gain and network are freed too,
// starting from the passive answer. The cost (dominated by the noise) may only fall by what 6
// more parameters can fit of the noise: less than 1 %.
TEST(MuscleIdentification, FreeMusclesOnDataWithoutAControllerChangeTheCostByLessThanOnePercent) {
  Model truth = mme::test::muscleObject();
  mme::BondType& tm = truth.bond_types[truth.bondTypeIndex("m")];
  tm.param(mme::kGain).value = 0.0;
  mme::Trajectory data = mme::simulateTrajectory(truth, 200, 100.0);
  mme::addGaussianNoise(&data, 1e-4, 5);

  Model passive = truth;
  for (const char* name : {"s", "d", "m"})
    for (mme::ParamId id : {mme::kStiffness, mme::kRestLength, mme::kDamping}) {
      mme::Param& p = passive.bond_types[passive.bondTypeIndex(name)].param(id);
      if (p.present) p.free = true;
    }
  mme::IdentifyOptions options;
  options.cost = mme::CostChoice::kShortTerm;
  options.generations = 300;
  options.estimate_std = false;
  const mme::IdentifyResult without = mme::identifyModel(mme::test::withoutValues(passive), data, options);

  Model with_muscles = without.model;  // the passive answer as the start
  mme::BondType& wm = with_muscles.bond_types[with_muscles.bondTypeIndex("m")];
  wm.param(mme::kGain) = mme::test::valueParam(1.0, true);
  for (mme::Param& p : wm.network) p.free = true;
  const mme::IdentifyResult with = mme::identifyModel(with_muscles, data, options);
  ASSERT_GT(without.global_cost, 0.0);
  const double change = (with.global_cost - without.global_cost) / without.global_cost;
  RecordProperty("relative_cost_change", std::to_string(change));
  EXPECT_LT(std::abs(change), 0.01) << "passive " << without.global_cost << " m^2, with muscles "
                                    << with.global_cost << " m^2";
}

// Why the paper's one-step cost cannot identify the walker to 1 % (docs/scenes.md
// "Identifying the walker"): its contact and servos move the markers between frames (80
// substeps), so on its own noiseless frames the one-step cost at the true values is far from
// round-off and the fourth-difference noise estimate reads 0.8 mm: `identify --cost auto`
// treats the data as noisy and goes to the output error, which simulates between frames
// (`bench_paper --only walker_oe,walker_identify`).
TEST(MuscleIdentification, TheWalkersFramesAreNotExactForTheOneStepCost) {
  const mme::Scene scene = mme::makeScene("walker");
  const mme::Trajectory data = mme::simulateTrajectory(scene.model, 50, scene.model.frame_rate_hz);
  mme::ShortTermCost cost(scene.model, data);
  EXPECT_GT(cost.evaluate(mme::getValues(scene.model, cost.freeParameters()), nullptr), 1e-3);
  EXPECT_GT(mme::estimateMarkerNoise(data), mme::IdentifyOptions().auto_noise_threshold_m);
}

}  // namespace
