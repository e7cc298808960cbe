#include "problem.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <set>
#include <utility>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/model_builder.h"
#include "motion_model_estimation/identification/estimators/output_error.h"
#include "motion_model_estimation/scenes/random_object.h"

namespace bench {

Errors relativeErrors(const std::vector<double>& values, const std::vector<double>& truth) {
  std::vector<double> e;
  for (size_t k = 0; k < values.size() && k < truth.size(); ++k) {
    const double x = 100.0 * std::abs(values[k] - truth[k]) / std::max(std::abs(truth[k]), 1e-300);
    e.push_back(std::isfinite(x) ? x : 1e300);
  }
  Errors out;
  if (e.empty()) return out;
  out.max = *std::max_element(e.begin(), e.end());
  std::sort(e.begin(), e.end());
  out.median = e.size() % 2 ? e[e.size() / 2] : 0.5 * (e[e.size() / 2 - 1] + e[e.size() / 2]);
  return out;
}

mme::Model forgetFreeValues(mme::Model m) {
  for (const mme::ParamRef& r : mme::freeParameters(m)) {
    mme::Param& p = mme::paramOf(m, r);
    p.has_value = false;
  }
  return m;
}

namespace {

/// Why the equation-error least squares (linear in k, kL, c per type) does not apply; empty
/// when it does.
std::string llsVerdict(const mme::Model& model) {
  if (model.substeps != 1) return "substeps > 1 (one frame is not one explicit step)";
  if (!model.interactions.empty()) return "conditional interactions (bonds found on the fly)";
  for (int c = 0; c < 3; ++c)
    if (model.gravity_mps2[c].free) return "free gravity";
  for (const mme::BondType& t : model.bond_types) {
    switch (t.kind) {
      case mme::BondKind::kSpring: break;
      case mme::BondKind::kFlexion: return "flexion bonds (non-linear in the angle)";
      case mme::BondKind::kMuscle: return "muscles (a network of other bonds' motion)";
      case mme::BondKind::kFloor: return "ground contact (conditional on the height)";
      case mme::BondKind::kViscosity:
        if (t.param(mme::kViscosity).free) return "free viscosity";
        continue;
    }
    for (mme::ParamId id : {mme::kStiffnessNl, mme::kDampingNl})
      if (t.param(id).present && (t.param(id).free || t.value(id) != 0.0))
        return "non-linear springs (" + t.name + "/" + mme::paramKey(id) + ")";
    for (mme::ParamId id : {mme::kMinDistance, mme::kMaxDistance})
      if (t.param(id).present) return "conditional bonds (" + t.name + "/" + mme::paramKey(id) + ")";
    if (t.param(mme::kMaxElongation).present) return "Provot clamps (" + t.name + ")";
  }
  return "";
}

}  // namespace

mme::Trajectory simulateWindow(const mme::Model& model, int frames, double rate_hz, int first,
                               mme::State* state_at_first) {
  mme::Simulator sim(model);
  mme::State s = sim.initialState();
  mme::Trajectory out;
  for (const mme::Particle& p : model.particles) out.marker_names.push_back(p.name);
  out.frame_rate_hz = rate_hz;
  out.resize(frames - first);
  const int n = static_cast<int>(model.particles.size());
  const double h = 1.0 / rate_hz;
  for (int t = 0; t < frames; ++t) {
    if (t > 0) sim.stepFrame(&s, h);
    if (t == first && state_at_first) *state_at_first = s;
    if (t < first) continue;
    for (int i = 0; i < n; ++i) {
      out.position(t - first, i) = s.x_m[i];
      out.occluded[(t - first) * n + i] = 0;
    }
  }
  return out;
}

Problem makeProblem(const std::string& name, const mme::Model& truth, int identification_substeps,
                    const mme::Trajectory& data, const mme::State& data_state) {
  Problem p;
  p.name = name;
  p.truth = truth;
  p.model = forgetFreeValues(truth);
  p.model.substeps = identification_substeps;
  if (p.model.frame_rate_hz <= 0.0) p.model.frame_rate_hz = data.frame_rate_hz;
  p.data = data;
  p.cost = std::make_shared<mme::ShortTermCost>(p.model, p.data);
  p.space = std::make_shared<mme::ParameterSpace>(p.model, p.data);
  p.truth_values = mme::getValues(truth, p.space->refs());
  const int frames = data.numFrames();
  // Rollout reference: 10 x the window (at least 100 frames); the limit is 10 x the larger of
  // the object's extent and the true motion's largest displacement over the same rollout.
  p.rollout_state = data_state;
  p.rollout_frames = 10 * std::max(frames, 10);
  {
    mme::Model m = truth;
    m.substeps = std::max(truth.substeps, identification_substeps);
    mme::Simulator sim(m);
    mme::State s = data_state;
    const double h = 1.0 / p.model.frame_rate_hz;
    double max_disp = 0.0;
    for (int f = 0; f < p.rollout_frames; ++f) {
      sim.stepFrame(&s, h);
      for (size_t i = 0; i < s.x_m.size(); ++i)
        max_disp = std::max(max_disp, (s.x_m[i] - data_state.x_m[i]).norm());
    }
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
    for (const Eigen::Vector3d& x : data_state.x_m) {
      lo = lo.cwiseMin(x);
      hi = hi.cwiseMax(x);
    }
    const double extent = data_state.x_m.empty() ? 1.0 : (hi - lo).norm();
    p.rollout_limit_m = 10.0 * std::max({extent, max_disp, 1e-3});
  }
  p.lls_reason = llsVerdict(p.model);
  p.lls_applicable = p.lls_reason.empty();
  return p;
}

std::vector<double> cramerRaoPct(const Problem& problem) {
  if (!(problem.noise_std_m > 0.0) || problem.noiseless_data.numFrames() == 0) return {};
  mme::Model m = problem.truth;
  m.substeps = problem.model.substeps;
  m.frame_rate_hz = problem.model.frame_rate_hz;
  std::vector<double> bound;
  try {
    bound = mme::cramerRaoBound(m, problem.noiseless_data, *problem.space, problem.noise_std_m);
  } catch (const std::exception&) {
    bound.clear();
  }
  bound.resize(problem.truth_values.size(), std::numeric_limits<double>::quiet_NaN());
  for (size_t k = 0; k < bound.size(); ++k)
    bound[k] = 100.0 * bound[k] / std::max(std::abs(problem.truth_values[k]), 1e-300);
  return bound;
}

double medianEfficiency(const std::vector<double>& values, const std::vector<double>& truth,
                        const std::vector<double>& bound_pct) {
  std::vector<double> ratio;
  for (size_t k = 0; k < values.size() && k < truth.size() && k < bound_pct.size(); ++k) {
    if (!(std::isfinite(bound_pct[k]) && bound_pct[k] > 0.0)) continue;
    const double error_pct = 100.0 * std::abs(values[k] - truth[k]) / std::max(std::abs(truth[k]), 1e-300);
    if (!std::isfinite(error_pct)) return std::numeric_limits<double>::quiet_NaN();
    ratio.push_back(error_pct / bound_pct[k]);
  }
  if (ratio.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(ratio.begin(), ratio.end());
  const size_t n = ratio.size();
  return n % 2 ? ratio[n / 2] : 0.5 * (ratio[n / 2 - 1] + ratio[n / 2]);
}

double thresholdMiddleErrorPct(const Problem& problem) {
  const mme::ParameterSpace& space = *problem.space;
  const std::vector<double> truth = space.toSearch(problem.truth_values);
  double worst = std::numeric_limits<double>::quiet_NaN();
  for (size_t k = 0; k < space.size(); ++k) {
    const mme::Gene& g = space.gene(k);
    if (g.smooth || g.breakpoints.empty()) continue;
    // The interval around the truth: the neighbouring breakpoints (the bounds at the ends), its
    // middle taken in search space as the threshold search does.
    const auto above = std::upper_bound(g.breakpoints.begin(), g.breakpoints.end(), truth[k]);
    const double hi = above == g.breakpoints.end() ? g.upper : *above;
    const double lo = above == g.breakpoints.begin() ? g.lower : *std::prev(above);
    const double middle = 0.5 * (lo + hi);
    const double value = g.log_scale ? std::exp(middle) : middle;
    const double error = 100.0 * std::abs(value - problem.truth_values[k]) /
                         std::max(std::abs(problem.truth_values[k]), 1e-300);
    worst = std::isfinite(worst) ? std::max(worst, error) : error;
  }
  return worst;
}

void occludeRandomly(mme::Trajectory* data, double share, uint64_t seed) {
  if (share <= 0.0) return;
  mme::Random random(seed);
  for (size_t k = 0; k < data->occluded.size(); ++k)
    if (random.uniform() < share) {
      data->occluded[k] = 1;
      data->positions_m[k].setZero();
    }
}

double stiffestOmega(const mme::Model& model) {
  const int n = static_cast<int>(model.particles.size());
  Eigen::MatrixXd k = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  for (const mme::Bond& b : model.bonds) {
    const mme::BondType& type = model.bond_types[b.type];
    if (type.kind != mme::BondKind::kSpring) continue;
    const int a = b.particles[0], c = b.particles[1];
    Eigen::Vector3d d = model.particles[c].position_m - model.particles[a].position_m;
    if (d.norm() <= 0.0) continue;
    d.normalize();
    const Eigen::Matrix3d block = type.value(mme::kStiffness) * d * d.transpose();
    k.block<3, 3>(3 * a, 3 * a) += block;
    k.block<3, 3>(3 * c, 3 * c) += block;
    k.block<3, 3>(3 * a, 3 * c) -= block;
    k.block<3, 3>(3 * c, 3 * a) -= block;
  }
  Eigen::VectorXd inv_sqrt_m(3 * n);
  for (int i = 0; i < n; ++i)
    inv_sqrt_m.segment<3>(3 * i).setConstant(1.0 / std::sqrt(model.particles[i].mass_kg));
  const Eigen::MatrixXd a = inv_sqrt_m.asDiagonal() * k * inv_sqrt_m.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(a, Eigen::EigenvaluesOnly);
  return std::sqrt(std::max(0.0, eig.eigenvalues().maxCoeff()));
}

Starts::Starts(const Problem& problem, uint64_t seed) : problem_(problem), random_(seed) {}

std::vector<double> Starts::next() {
  const mme::ParameterSpace& space = *problem_.space;
  std::vector<double> genes(space.size());
  const std::vector<double> truth =
      problem_.start_spread < 0.0 ? genes : space.toSearch(problem_.truth_values);
  for (size_t k = 0; k < space.size(); ++k) {
    if (problem_.start_spread < 0.0) {
      genes[k] = space.sampleInitial(k, random_);
    } else {
      const mme::Gene& g = space.gene(k);
      genes[k] = space.reflect(k, truth[k] + problem_.start_spread * (g.upper - g.lower) * random_.normal());
    }
  }
  return genes;
}

double costOfGenes(const Problem& problem, std::vector<double>* genes) {
  for (size_t k = 0; k < genes->size(); ++k) (*genes)[k] = problem.space->reflect(k, (*genes)[k]);
  const double c = problem.cost->evaluate(problem.space->toPhysical(*genes), nullptr);
  return std::isfinite(c) ? c : 1e300;
}

bool rolloutBounded(const Problem& problem, const std::vector<double>& values, int substeps) {
  for (double v : values)
    if (!std::isfinite(v)) return false;
  mme::Model m = problem.truth;
  m.substeps = substeps > 0 ? substeps : problem.model.substeps;
  mme::setValues(m, problem.space->refs(), values);
  try {
    mme::Simulator sim(m);
    mme::State s = problem.rollout_state;
    const double h = 1.0 / problem.model.frame_rate_hz;
    for (int f = 0; f < problem.rollout_frames; ++f) {
      sim.stepFrame(&s, h);
      for (size_t i = 0; i < s.x_m.size(); ++i) {
        const double d = (s.x_m[i] - problem.rollout_state.x_m[i]).norm();
        if (!(d <= problem.rollout_limit_m)) return false;
      }
    }
  } catch (const std::exception&) {
    return false;
  }
  return true;
}


mme::Model makeSheet(int rows, int cols, double rate_hz, uint64_t seed) {
  mme::Random random(seed);
  mme::Model model;
  model.frame_rate_hz = rate_hz;
  const double spacing = 0.05, mass = 0.05;
  char name[32];
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      mme::Particle p;
      std::snprintf(name, sizeof(name), "p%d_%d", r, c);
      p.name = name;
      p.mass_kg = mass;
      p.position_m = Eigen::Vector3d(c * spacing, r * spacing, 0.002 * (random.uniform() - 0.5));
      for (int k = 0; k < 3; ++k) p.velocity_mps[k] = 0.02 * (random.uniform() - 0.5);
      model.particles.push_back(p);
    }
  // Types: structural, shear, bending; rest lengths 4 % off the grid so the sheet vibrates;
  // stiffness keeps omega h small at the frame rate (up to 12 springs on a particle).
  const double h = 1.0 / rate_hz;
  const double k_struct = std::min(50.0, 0.05 * mass / (h * h) / 12.0);
  const double specs[3][2] = {{k_struct, spacing * 0.96},
                              {0.5 * k_struct, spacing * std::sqrt(2.0) * 1.04},
                              {0.25 * k_struct, 2.0 * spacing * 0.97}};
  const char* names[3] = {"structural", "shear", "bending"};
  for (int t = 0; t < 3; ++t) {
    mme::BondType type;
    type.name = names[t];
    type.kind = mme::BondKind::kSpring;
    type.param(mme::kStiffness) = mme::boundedParam(specs[t][0], specs[t][0] / 10, specs[t][0] * 10);
    type.param(mme::kRestLength) = mme::boundedParam(specs[t][1], specs[t][1] / 2, specs[t][1] * 2);
    model.bond_types.push_back(type);
  }
  auto id = [cols](int r, int c) { return r * cols + c; };
  auto bond = [&model](int type, int a, int b) {
    mme::Bond bd;
    bd.type = type;
    bd.particles = {{a, b, -1}};
    model.bonds.push_back(bd);
  };
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      if (c + 1 < cols) bond(0, id(r, c), id(r, c + 1));
      if (r + 1 < rows) bond(0, id(r, c), id(r + 1, c));
      if (r + 1 < rows && c + 1 < cols) {
        bond(1, id(r, c), id(r + 1, c + 1));
        bond(1, id(r, c + 1), id(r + 1, c));
      }
      if (c + 2 < cols) bond(2, id(r, c), id(r, c + 2));
      if (r + 2 < rows) bond(2, id(r, c), id(r + 2, c));
    }
  for (int c = 0; c < 3; ++c) {
    model.gravity_mps2[c].present = model.gravity_mps2[c].has_value = true;
    model.gravity_mps2[c].value = 0.0;
  }
  return model;
}

mme::Model makeCableObject(int bond_types, int cable_types, int particles, int bonds,
                           double rate_hz, uint64_t seed) {
  mme::RandomObjectSpec spec;
  spec.bond_types = bond_types;
  spec.particles = particles;
  spec.bonds = bonds;
  spec.frame_rate_hz = rate_hz;
  spec.seed = seed;
  spec.cable_types = cable_types;
  return mme::makeRandomObject(spec);
}

}  // namespace bench
