// Muscles in identification: the local-cost sites of a muscle type are its own ends, the
// search space keeps network parameters signed (linear coordinates, symmetric default bounds),
// the equation-error start declines muscle parameters with a reason, and the evolution
// strategy identifies a small scene with one muscle type.
#include <gtest/gtest.h>

#include <cmath>

#include "motion_model_estimation/core/short_term_cost.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/equation_error.h"
#include "motion_model_estimation/identification/identifier.h"
#include "motion_model_estimation/identification/parameter_space.h"
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

TEST(MuscleIdentification, TheEvolutionStrategyIdentifiesAMuscle) {
  const Model truth = freeMuscle(true);
  const mme::Trajectory data = mme::simulateTrajectory(truth, 80, 100.0);
  const Model search = mme::test::withoutValues(truth);
  mme::IdentifyOptions options;
  options.generations = 300;
  options.estimate_std = false;
  const mme::IdentifyResult r = mme::identifyModel(search, data, options);
  const std::vector<double> want = mme::getValues(truth, mme::freeParameters(truth));
  for (size_t k = 0; k < want.size(); ++k)
    std::printf("%-12s %12.6g %12.6g\n", r.parameters[k].name.c_str(), want[k], r.values[k]);
  std::printf("cost %g generations %d evaluations %llu wall %.2f s\n", r.global_cost, r.generations,
              static_cast<unsigned long long>(r.evaluations), r.wall_time_s);
}

}  // namespace
