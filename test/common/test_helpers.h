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
#include "motion_model_estimation/core/model_builder.h"
#include "motion_model_estimation/core/short_term_cost.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/identification/estimators/prediction_error.h"

namespace mme {
namespace test {

using mme::addBond;     // core/model_builder.h
using mme::valueParam;  // core/model_builder.h
/// Adds a particle named "p<index>" (core/model_builder.h's addParticle with the arguments the
/// tests use most); returns its index.
int addParticle(Model* model, const Eigen::Vector3d& x, double mass_kg = 1.0, bool fixed = false,
                const std::string& group = "", const Eigen::Vector3d& v = Eigen::Vector3d::Zero());
/// Adds a bond type with the given parameter values (all free or all fixed); returns its index.
int addType(Model* model, const std::string& name, BondKind kind,
            std::initializer_list<std::pair<ParamId, double>> params, bool free = true);
/// Names bond `bond` (so that a muscle can read it); returns the name.
std::string nameBond(Model* model, int bond, const std::string& name);
/// Adds a muscle type: stiffness [N/m], rest length [m], damping [N s/m], gain [N] and the
/// network's parameters in storage order (muscleNetworkSize(inputs, hidden) of them), every
/// one present and free or fixed as `free` says; returns its index.
int addMuscleType(Model* model, const std::string& name, double stiffness, double rest_length,
                  double damping, double gain, int inputs, int hidden,
                  const std::vector<double>& network, bool free = false);
/// Installs a muscle of type `type` between a and b reading the bonds `inputs` (indices).
void addMuscle(Model* model, int type, int a, int b, const std::vector<int>& inputs);

/// A hanging 4-particle object (p0 fixed, gravity) with 5 springs and one muscle (p0-p3) whose
/// parameters are all fixed (tests free what they identify), and whose
/// linear network (hidden 0) reads the springs p0-p1 and p1-p2: its activation changes sign
/// with the swing, so the motion differs from a passive model's. 100 Hz.
Model muscleObject();

/// A small floating object: 5 particles, 3 linear spring types (stiffness and rest length free:
/// 6 parameters, bounded [1, 1000] N/m and [0.05, 0.5] m), 7 bonds, 100 Hz.
Model smallObject();
/// The model as identification sees it: every free parameter's value forgotten (bounds kept).
Model withoutValues(Model model);
/// The particles of `model` alone (no bond, no bond type): what structure selection starts from.
Model particlesOnly(Model model);
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

/// A stiff scene integrated at one substep per frame: paper_object at omega h = 2.5 (semi-implicit
/// Euler's stable range ends at 2), the data (60 frames) from 20 substeps with 0.1 mm noise, the
/// model to search at 1 substep. The one-step cost predicts one frame at a time and stays usable;
/// the output error's rollouts over 10-frame segments blow up.
struct StiffAtOneSubstep {
  StiffAtOneSubstep();
  Model truth;
  Trajectory data;
  Model search;  ///< truth without values, 1 substep
};

/// Largest |a_k - truth_k| / |truth_k|.
double maxRelativeError(const std::vector<double>& a, const std::vector<double>& truth);

/// The RMS of `predictor` at `horizon` in `report` (a test failure and -1 when it has no row).
double predictionRms(const PredictionReport& report, int horizon, Predictor predictor);

}  // namespace test
}  // namespace mme
