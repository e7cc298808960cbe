// Model builders and checks shared by the core tests (grid_map's test_helpers): one copy of each,
// so a test reads as what it checks, not how it builds its model.
#pragma once

#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include <memory>

#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/short_term_cost.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/identification/prediction_error.h"

namespace mme {
namespace test {

/// A present parameter with a value (free or fixed, no bounds).
Param valueParam(double value, bool free = false);
/// Adds a particle named "p<index>"; returns its index.
int addParticle(Model* model, const Eigen::Vector3d& x, double mass_kg = 1.0, bool fixed = false,
                const std::string& group = "", const Eigen::Vector3d& v = Eigen::Vector3d::Zero());
/// Adds a bond type with the given parameter values (all free or all fixed); returns its index.
int addType(Model* model, const std::string& name, BondKind kind,
            std::initializer_list<std::pair<ParamId, double>> params, bool free = true);
void addBond(Model* model, int type, int a, int b = -1, int c = -1);

/// A small floating object: 5 particles, 3 linear spring types (stiffness and rest length free:
/// 6 parameters, bounded [1, 1000] N/m and [0.05, 0.5] m), 7 bonds, 100 Hz.
Model smallObject();
/// The model as identification sees it: every free parameter's value forgotten (bounds kept).
Model withoutValues(Model model);
/// The model with every bound of every free parameter removed (the defaults must do).
Model withoutBounds(Model model);
/// smallObject() as the identification tests use it: the truth, the model without values,
/// 60 noiseless frames at 100 Hz, its one-step cost and the true values.
struct SmallObjectFixture {
  SmallObjectFixture();
  Model truth;
  Model search;
  Trajectory data;
  std::shared_ptr<ShortTermCost> cost;
  std::vector<double> true_values;
};

/// Largest |a_k - truth_k| / |truth_k|.
double maxRelativeError(const std::vector<double>& a, const std::vector<double>& truth);

/// The RMS of `predictor` at `horizon` in `report` (a test failure and -1 when it has no row).
double predictionRms(const PredictionReport& report, int horizon, Predictor predictor);

}  // namespace test
}  // namespace mme
