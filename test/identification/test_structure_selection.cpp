// Structure selection on synthetic scenes of known structure (random objects from simulate's
// generator): from the particles alone it finds the bonds, whether they are damped, and which
// bonds share a type, with every parameter of the chosen model within 1 % of the truth on
// noiseless data; a springs-only scene gets no damper; the report lists every candidate.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/structure_selection.h"
#include "motion_model_estimation/scenes/random_object.h"

namespace {

/// The particles of `truth` alone (no bond, no type).
mme::Model particlesOnly(const mme::Model& truth) {
  mme::Model m = truth;
  m.bonds.clear();
  m.bond_types.clear();
  return m;
}

mme::StructureResult select(const mme::Model& truth, int frames) {
  const mme::Trajectory data = mme::simulateTrajectory(truth, frames, truth.frame_rate_hz);
  mme::StructureOptions options;
  options.identify.es.threads = 1;
  options.identify.generations = 200;
  if (std::getenv("MME_TEST_VERBOSE"))
    options.progress = [](const std::string& line) { std::printf("%s\n", line.c_str()); };
  return mme::selectStructure(particlesOnly(truth), data, options);
}

TEST(StructureSelection, SpringsOnlyFindsTheBondsAndTypesAndAddsNoDamper) {
  for (uint64_t seed : {1u, 2u}) {
    mme::RandomObjectSpec spec;
    spec.particles = 15;
    spec.bond_types = 6;
    spec.bonds = 30;
    spec.seed = seed;
    const mme::Model truth = mme::makeRandomObject(spec);
    const mme::StructureResult r = select(truth, 240);
    const mme::StructureScore c = mme::scoreStructure(truth, r.model);
    EXPECT_GE(c.f1, 0.95) << "seed " << seed;
    EXPECT_EQ(c.types, spec.bond_types) << "seed " << seed;
    EXPECT_TRUE(c.damped_nowhere) << "seed " << seed;
    EXPECT_LT(c.max_relative_error, 0.01) << "seed " << seed;
    ASSERT_EQ(r.candidates.size(), 2u);
    EXPECT_EQ(r.candidates[0].name, "springs");
    EXPECT_TRUE(r.candidates[0].chosen) << mme::formatStructureReport(r);
    EXPECT_GT(r.candidate_bonds, spec.bonds);  // more candidates than bonds: it chose
    // The chosen model predicts the held-out frames far better than constant velocity.
    EXPECT_LT(r.candidates[0].held_out_rms_m[2], 0.1 * r.guess_rms_m[0][2]);
  }
}

TEST(StructureSelection, SpringsAndDampersFindsTheDampers) {
  for (uint64_t seed : {3u, 4u}) {
    mme::RandomObjectSpec spec;
    spec.particles = 15;
    spec.bond_types = 5;
    spec.bonds = 28;
    spec.damping_max_nspm = 0.5;
    spec.seed = seed;
    const mme::Model truth = mme::makeRandomObject(spec);
    const mme::StructureResult r = select(truth, 240);
    const mme::StructureScore c = mme::scoreStructure(truth, r.model);
    EXPECT_GE(c.f1, 0.95) << "seed " << seed;
    EXPECT_EQ(c.types, spec.bond_types) << "seed " << seed;
    EXPECT_TRUE(c.damped_everywhere) << "seed " << seed << "\n" << mme::formatStructureReport(r);
    EXPECT_LT(c.max_relative_error, 0.01) << "seed " << seed;
    EXPECT_TRUE(r.candidates[1].chosen) << mme::formatStructureReport(r);
  }
}

TEST(StructureSelection, TheReportListsEveryCandidateAndTheGuesses) {
  mme::RandomObjectSpec spec;
  spec.particles = 10;
  spec.bond_types = 3;
  spec.bonds = 15;
  const mme::Model truth = mme::makeRandomObject(spec);
  const mme::StructureResult r = select(truth, 120);
  const std::string csv = mme::structureReportCsv(r);
  EXPECT_EQ(csv.rfind("name,bonds,bond_types,parameters,fit_rms_m,bic,refit_cost_m2,", 0), 0u);
  for (const char* row : {"\nsprings,", "\nsprings+dampers,", "\nconstant_velocity,",
                          "\nconstant_acceleration,", "\ngravity_only,"})
    EXPECT_NE(csv.find(row), std::string::npos) << row;
  EXPECT_NE(mme::formatStructureReport(r).find("<- chosen"), std::string::npos);
  // Too few frames to hold some out: refused by name.
  const mme::Trajectory short_data = mme::simulateTrajectory(truth, 30, truth.frame_rate_hz);
  EXPECT_THROW(mme::selectStructure(particlesOnly(truth), short_data), mme::InputError);
}

}  // namespace
