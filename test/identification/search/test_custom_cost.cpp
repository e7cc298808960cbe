// A cost written outside the package, plugged into the search through the Cost interface
// (core/cost.h) alone: the worked example of docs/architecture.md ("adding a cost") done for
// real. The toy cost is the free fall of every marker: per particle and frame, the second
// difference of its positions minus gravity times the frame period squared. The evolution
// strategy, with its refinement, finds the gravity a simulated fall was made with.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "motion_model_estimation/core/cost.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/search/evolution_strategy.h"
#include "motion_model_estimation/identification/search/parameter_space.h"
#include "test_helpers.h"

namespace {

/// Residuals x[t+1] - 2 x[t] + x[t-1] - g h^2 [m], 3 per particle and inner frame; the local
/// cost of a particle is the sum of its squares.
class FreeFallCost : public mme::Cost {
 public:
  FreeFallCost(const mme::Model& model, mme::Trajectory data)
      : refs_(mme::freeParameters(model)), data_(std::move(data)),
        h_s_(1.0 / data_.frame_rate_hz) {}

  const std::vector<mme::ParamRef>& freeParameters() const override { return refs_; }
  double evaluate(const std::vector<double>& values, std::vector<double>* local_costs) const override {
    std::vector<double> r;
    residuals(values, &r);
    if (local_costs) local_costs->assign(numParticles(), 0.0);
    double total = 0.0;
    for (size_t k = 0; k < r.size(); ++k) {
      total += r[k] * r[k];
      if (local_costs) (*local_costs)[(k / 3) % numParticles()] += r[k] * r[k];
    }
    return total;
  }
  double residuals(const std::vector<double>& values, std::vector<double>* out) const override {
    const Eigen::Vector3d g(values[0], values[1], values[2]);  // gravity/x, y, z: the only free ones
    out->clear();
    double total = 0.0;
    for (int t = 1; t + 1 < data_.numFrames(); ++t)
      for (int i = 0; i < numParticles(); ++i) {
        const Eigen::Vector3d e = data_.position(t + 1, i) - 2.0 * data_.position(t, i) +
                                  data_.position(t - 1, i) - g * h_s_ * h_s_;
        for (int c = 0; c < 3; ++c) {
          out->push_back(e[c]);
          total += e[c] * e[c];
        }
      }
    return total;
  }
  size_t residualCount() const override { return 3u * numParticles() * (data_.numFrames() - 2); }
  uint64_t termCount() const override { return static_cast<uint64_t>(numParticles()) * (data_.numFrames() - 2); }
  int numParticles() const override { return data_.numMarkers(); }
  const char* name() const override { return "free_fall"; }

 private:
  std::vector<mme::ParamRef> refs_;
  mme::Trajectory data_;
  double h_s_;
};

TEST(CustomCost, TheSearchFindsGravityThroughTheCostInterfaceAlone) {
  mme::Model model;
  model.frame_rate_hz = 100.0;
  for (int i = 0; i < 4; ++i) mme::test::addParticle(&model, Eigen::Vector3d(0.3 * i, 0.1 * i, 2.0));
  const Eigen::Vector3d truth(0.4, -0.7, -9.81);
  for (int c = 0; c < 3; ++c) {
    model.gravity_mps2[c].value = truth[c];
    model.gravity_mps2[c].has_value = model.gravity_mps2[c].present = true;
    model.gravity_mps2[c].free = true;
  }
  const mme::Trajectory data = mme::simulateTrajectory(model, 30, model.frame_rate_hz);
  mme::Model search = mme::test::withoutValues(model);
  ASSERT_EQ(mme::freeParameters(search).size(), 3u);

  mme::EsOptions options;
  options.population = 30;
  options.offspring = 30;
  mme::EvolutionStrategy es(mme::ParameterSpace(search, data), options);
  es.setCost(std::make_shared<FreeFallCost>(search, data));
  for (int generation = 0; generation < 40; ++generation) es.step();
  const std::vector<double> found = es.bestValues();
  ASSERT_EQ(found.size(), 3u);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(found[c], truth[c], 1e-6 * 9.81) << "component " << c;
}

}  // namespace
