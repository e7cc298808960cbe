#include "motion_model_estimation/identification/sensor_muscles.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/muscle.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/prediction_error.h"

namespace mme {

namespace {

/// A pair of particles and its distance over the frames where both are seen.
struct PairStats {
  int a = -1, b = -1;
  double mean_m = 0.0, std_m = 0.0;
  int seen = 0;
};

std::vector<PairStats> pairStatistics(const Model& model, const Trajectory& data) {
  const int n = static_cast<int>(model.particles.size());
  std::vector<PairStats> pairs;
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) {
      if (model.particles[a].fixed && model.particles[b].fixed) continue;
      const MarkerDistance d = markerDistance(data, a, b);
      if (d.seen_frames == 0) continue;
      pairs.push_back({a, b, d.mean_m, d.std_m, d.seen_frames});
    }
  return pairs;
}

/// Where the sensors and muscles go.
struct Layout {
  std::vector<PairStats> sensors, muscles;
};

/// The equation error's normal equations in the scaled columns (see the header).
struct System {
  Eigen::MatrixXd ata;
  Eigen::VectorXd atb;
  size_t rows = 0;
  double btb = 0.0;
};

class Fitter {
 public:
  Fitter(const Model& passive, const Trajectory& data, const Layout& layout)
      : passive_(passive), data_(data), layout_(layout), sim_(passive),
        n_(static_cast<int>(passive.particles.size())),
        s_(static_cast<int>(layout.sensors.size())),
        m_(static_cast<int>(layout.muscles.size())), k_(2 * s_ + 3) {
    h_ = 1.0 / passive.frame_rate_hz;
    // Particles whose force depends on particle i's state: every bond's other members, or all
    // of them when bonds are installed on the fly.
    partners_.assign(n_, {});
    for (const Bond& bond : passive.bonds) {
      const int arity = kindArity(passive.bond_types[bond.type].kind);
      for (int p = 0; p < arity; ++p)
        for (int q = 0; q < arity; ++q)
          if (p != q) partners_[bond.particles[p]].push_back(bond.particles[q]);
    }
    all_partners_ = !passive.interactions.empty();
    at_.assign(n_, {});
    for (int m = 0; m < m_; ++m) {
      at_[layout.muscles[m].a].push_back({m, 1.0});
      at_[layout.muscles[m].b].push_back({m, -1.0});
    }
    computeScales();
  }

  int unknowns() const { return m_ * k_; }

  /// Adds the rows of frames t >= t_begin whose frames t-1, t, t+1 all lie before t_end.
  void accumulate(int t_begin, int t_end, System* sys) {
    if (sys->ata.rows() == 0) {
      sys->ata = Eigen::MatrixXd::Zero(unknowns(), unknowns());
      sys->atb = Eigen::VectorXd::Zero(unknowns());
    }
    std::vector<Eigen::Vector3d> forces;
    std::vector<Eigen::Matrix<double, Eigen::Dynamic, 1>> phi(m_);
    std::vector<Eigen::Vector3d> u(m_);
    std::vector<char> muscle_ok(m_);
    for (int t = std::max(1, t_begin); t + 1 < std::min(t_end, data_.numFrames()); ++t) {
      Eigen::VectorXd z;
      if (!sensorInputs(t, &z)) continue;
      const State state = stateAt(t);
      sim_.computeForces(state, &forces);
      for (int m = 0; m < m_; ++m) {
        double e = 0.0, s = 0.0;
        muscle_ok[m] = muscleGeometry(t, m, state, &u[m], &e, &s);
        if (!muscle_ok[m]) continue;
        phi[m].resize(k_);
        phi[m].head(2 * s_) = z.cwiseQuotient(z_scale_);
        phi[m](2 * s_) = 1.0;
        phi[m](2 * s_ + 1) = e / e_scale_[m];
        phi[m](2 * s_ + 2) = s / s_scale_[m];
      }
      for (int i = 0; i < n_; ++i) {
        if (!usable(t, i, muscle_ok)) continue;
        const double mass = passive_.particles[i].mass_kg;
        const Eigen::Vector3d acc =
            (data_.position(t + 1, i) - 2.0 * data_.position(t, i) + data_.position(t - 1, i)) / (h_ * h_);
        const Eigen::Vector3d y = acc - forces[i] / mass;
        sys->btb += y.squaredNorm();
        sys->rows += 3;
        for (const auto& [m, sign] : at_[i]) {
          const double w = sign / mass;
          sys->atb.segment(m * k_, k_) += (w * u[m].dot(y)) * phi[m];
          for (const auto& [m2, sign2] : at_[i]) {
            const double c = w * sign2 / mass * u[m].dot(u[m2]);
            sys->ata.block(m * k_, m2 * k_, k_, k_).noalias() += c * phi[m] * phi[m2].transpose();
          }
        }
      }
    }
  }

  /// theta for a relative ridge; false when the solve fails.
  static bool solve(const System& sys, double ridge, Eigen::VectorXd* theta) {
    const double mean_diagonal = std::max(sys.ata.diagonal().mean(), 1e-300);
    Eigen::MatrixXd a = sys.ata;
    a.diagonal().array() += ridge * mean_diagonal;
    Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(a);  // in place: one copy of the matrix
    if (llt.info() != Eigen::Success) return false;
    *theta = llt.solve(sys.atb);
    return theta->allFinite();
  }

  /// RMS of a system's rows at theta [m/s^2].
  static double residualRms(const System& sys, const Eigen::VectorXd& theta) {
    if (sys.rows == 0) return 0.0;
    const double r2 = sys.btb - 2.0 * theta.dot(sys.atb) + theta.dot(sys.ata * theta);
    return std::sqrt(std::max(0.0, r2) / static_cast<double>(sys.rows));
  }

  /// The passive model with sensors and muscles carrying theta (scaled columns), every gain
  /// `margin` x its muscle's largest linear activation over frames [0, t_end).
  Model build(const Eigen::VectorXd& theta, double margin, int t_end) const {
    Model model = passive_;
    std::set<std::string> type_names, bond_names;
    for (const BondType& type : model.bond_types) type_names.insert(type.name);
    for (const Bond& bond : model.bonds)
      if (!bond.name.empty()) bond_names.insert(bond.name);
    auto unique = [](std::set<std::string>* names, std::string name) {
      while (names->count(name)) name += "_";
      names->insert(name);
      return name;
    };
    auto fixed = [](double value) {
      Param p;
      p.present = p.has_value = true;
      p.free = false;
      p.value = value;
      return p;
    };
    std::vector<int> sensor_bonds;
    for (int s = 0; s < s_; ++s) {
      const PairStats& pair = layout_.sensors[s];
      const std::string stem = "sensor_" + model.particles[pair.a].name + "_" + model.particles[pair.b].name;
      BondType type;
      type.name = unique(&type_names, stem);
      type.kind = BondKind::kSpring;
      type.param(kStiffness) = fixed(0.0);
      type.param(kRestLength) = fixed(pair.mean_m);
      model.bond_types.push_back(type);
      Bond bond;
      bond.type = static_cast<int>(model.bond_types.size()) - 1;
      bond.particles = {{pair.a, pair.b, -1}};
      bond.name = unique(&bond_names, stem);
      model.bonds.push_back(bond);
      sensor_bonds.push_back(static_cast<int>(model.bonds.size()) - 1);
    }
    // Each muscle's largest linear activation over the fitted frames sets its gain.
    std::vector<double> largest(m_, 0.0);
    for (int t = 1; t < std::min(t_end, data_.numFrames()); ++t) {
      Eigen::VectorXd z;
      if (!sensorInputs(t, &z)) continue;
      const Eigen::VectorXd scaled = z.cwiseQuotient(z_scale_);
      for (int m = 0; m < m_; ++m) {
        const double y = theta.segment(m * k_, 2 * s_).dot(scaled) + theta(m * k_ + 2 * s_);
        largest[m] = std::max(largest[m], std::abs(y));
      }
    }
    for (int m = 0; m < m_; ++m) {
      const PairStats& pair = layout_.muscles[m];
      const Eigen::VectorXd th = theta.segment(m * k_, k_);
      const double gain = largest[m] > 0.0 ? margin * largest[m] : 1.0;
      BondType type;
      type.name = unique(&type_names, "muscle_" + model.particles[pair.a].name + "_" +
                                          model.particles[pair.b].name);
      type.kind = BondKind::kMuscle;
      type.param(kStiffness) = fixed(th(2 * s_ + 1) / e_scale_[m]);
      type.param(kRestLength) = fixed(pair.mean_m);
      type.param(kDamping) = fixed(th(2 * s_ + 2) / s_scale_[m]);
      type.param(kGain) = fixed(gain);
      type.network_inputs = s_;
      type.network_hidden = 0;
      type.network.assign(muscleNetworkSize(s_, 0), Param{});
      for (int j = 0; j < 2 * s_; ++j) type.network[j] = fixed(th(j) / z_scale_(j) / gain);
      type.network[2 * s_] = fixed(th(2 * s_) / gain);
      model.bond_types.push_back(type);
      Bond bond;
      bond.type = static_cast<int>(model.bond_types.size()) - 1;
      bond.particles = {{pair.a, pair.b, -1}};
      bond.inputs = sensor_bonds;
      model.bonds.push_back(bond);
    }
    const std::string problem = validateModel(model);
    if (!problem.empty()) throw InputError("sensor muscles: " + problem);
    return model;
  }

 private:
  bool seen(int t, int i) const { return t >= 0 && t < data_.numFrames() && !data_.isOccluded(t, i); }

  /// Positions at t and velocities (x(t) - x(t-1)) / h where seen; zeros elsewhere.
  State stateAt(int t) const {
    State s;
    s.x_m.assign(n_, Eigen::Vector3d::Zero());
    s.v_mps.assign(n_, Eigen::Vector3d::Zero());
    for (int i = 0; i < n_; ++i) {
      if (!seen(t, i)) continue;
      s.x_m[i] = data_.position(t, i);
      if (seen(t - 1, i)) s.v_mps[i] = (data_.position(t, i) - data_.position(t - 1, i)) / h_;
    }
    return s;
  }

  /// The 2S network inputs at frame t (elongations from the sensors' rest lengths, then speeds
  /// along them); false when a sensor's particle is unseen at t or t-1.
  bool sensorInputs(int t, Eigen::VectorXd* z) const {
    z->resize(2 * s_);
    for (int s = 0; s < s_; ++s) {
      const PairStats& p = layout_.sensors[s];
      if (!seen(t, p.a) || !seen(t, p.b) || !seen(t - 1, p.a) || !seen(t - 1, p.b)) return false;
      const Eigen::Vector3d d = data_.position(t, p.b) - data_.position(t, p.a);
      const double l = d.norm();
      if (!(l > 0.0)) return false;
      const Eigen::Vector3d u = d / l;
      const Eigen::Vector3d dv = (data_.position(t, p.b) - data_.position(t - 1, p.b) -
                                  data_.position(t, p.a) + data_.position(t - 1, p.a)) / h_;
      (*z)(s) = l - p.mean_m;
      (*z)(s_ + s) = dv.dot(u);
    }
    return true;
  }

  /// Unit vector a->b, elongation from the mean length and speed of muscle m at frame t; false
  /// when an end is unseen at t or t-1.
  bool muscleGeometry(int t, int m, const State& state, Eigen::Vector3d* u, double* e, double* s) const {
    const PairStats& p = layout_.muscles[m];
    if (!seen(t, p.a) || !seen(t, p.b) || !seen(t - 1, p.a) || !seen(t - 1, p.b)) return false;
    const Eigen::Vector3d d = state.x_m[p.b] - state.x_m[p.a];
    const double l = d.norm();
    if (!(l > 0.0)) return false;
    *u = d / l;
    *e = l - p.mean_m;
    *s = (state.v_mps[p.b] - state.v_mps[p.a]).dot(*u);
    return true;
  }

  /// Particle i gives an equation at t: seen at t-1, t, t+1, not fixed, its passive partners
  /// and every muscle at it seen at t-1 and t.
  bool usable(int t, int i, const std::vector<char>& muscle_ok) const {
    if (passive_.particles[i].fixed || at_[i].empty()) return false;
    if (!seen(t - 1, i) || !seen(t, i) || !seen(t + 1, i)) return false;
    if (all_partners_) {
      for (int j = 0; j < n_; ++j)
        if (!seen(t, j) || !seen(t - 1, j)) return false;
    }
    for (int j : partners_[i])
      if (!seen(t, j) || !seen(t - 1, j)) return false;
    for (const auto& entry : at_[i])
      if (!muscle_ok[entry.first]) return false;
    return true;
  }

  /// Column scales: the RMS of each sensor input and of each muscle's elongation and speed over
  /// the frames (1 where they are 0 or unseen).
  void computeScales() {
    Eigen::VectorXd z2 = Eigen::VectorXd::Zero(2 * s_);
    int frames = 0;
    std::vector<double> e2(m_, 0.0), s2(m_, 0.0);
    std::vector<int> count(m_, 0);
    for (int t = 1; t < data_.numFrames(); ++t) {
      Eigen::VectorXd z;
      if (sensorInputs(t, &z)) {
        z2 += z.cwiseAbs2();
        ++frames;
      }
      const State state = stateAt(t);
      for (int m = 0; m < m_; ++m) {
        Eigen::Vector3d u;
        double e = 0.0, s = 0.0;
        if (!muscleGeometry(t, m, state, &u, &e, &s)) continue;
        e2[m] += e * e;
        s2[m] += s * s;
        ++count[m];
      }
    }
    auto scale = [](double sum2, int count) {
      const double rms = count > 0 ? std::sqrt(sum2 / count) : 0.0;
      return rms > 1e-12 ? rms : 1.0;
    };
    z_scale_.resize(2 * s_);
    for (int j = 0; j < 2 * s_; ++j) z_scale_(j) = scale(z2(j), frames);
    e_scale_.resize(m_);
    s_scale_.resize(m_);
    for (int m = 0; m < m_; ++m) {
      e_scale_[m] = scale(e2[m], count[m]);
      s_scale_[m] = scale(s2[m], count[m]);
    }
  }

  const Model& passive_;
  const Trajectory& data_;
  const Layout& layout_;
  Simulator sim_;
  int n_, s_, m_, k_;
  double h_ = 0.0;
  std::vector<std::vector<int>> partners_;
  bool all_partners_ = false;
  std::vector<std::vector<std::pair<int, double>>> at_;  ///< per particle: (muscle, sign)
  Eigen::VectorXd z_scale_;
  std::vector<double> e_scale_, s_scale_;
};

/// Unknowns at most: the normal matrix and its factor are two dense squares of this size
/// (2 x 1.6 GB at 14000).
constexpr size_t kMaxUnknowns = 14000;

Layout chooseLayout(const Model& passive, const Trajectory& data, const SensorMuscleOptions& o) {
  const std::vector<PairStats> pairs = pairStatistics(passive, data);
  const int well_seen = static_cast<int>(std::ceil(o.min_seen_share * data.numFrames()));
  Layout layout;
  std::vector<PairStats> ranked;
  for (const PairStats& p : pairs)
    if (p.seen >= well_seen) ranked.push_back(p);
  std::stable_sort(ranked.begin(), ranked.end(),
                   [](const PairStats& x, const PairStats& y) { return x.std_m > y.std_m; });
  for (int k = 0; k < o.sensors && k < static_cast<int>(ranked.size()); ++k)
    layout.sensors.push_back(ranked[k]);
  // Muscles: the model's two-particle bonds with an elongation, the sensor pairs, and every
  // particle to its nearest neighbours; one muscle per pair.
  std::set<std::pair<int, int>> taken;
  auto stats = [&](int a, int b) -> const PairStats* {
    if (a > b) std::swap(a, b);
    for (const PairStats& p : pairs)
      if (p.a == a && p.b == b) return &p;
    return nullptr;
  };
  auto add = [&](int a, int b) {
    if (a == b) return;
    if (a > b) std::swap(a, b);
    if (taken.count({a, b})) return;
    const PairStats* p = stats(a, b);
    if (!p || !(p->mean_m > 0.0)) return;
    taken.insert({a, b});
    layout.muscles.push_back(*p);
  };
  for (const Bond& bond : passive.bonds)
    if (bondKindInfo(passive.bond_types[bond.type].kind).has_elongation)
      add(bond.particles[0], bond.particles[1]);
  for (const PairStats& p : layout.sensors) add(p.a, p.b);
  const int n = static_cast<int>(passive.particles.size());
  for (int i = 0; i < n; ++i) {
    if (passive.particles[i].fixed) continue;
    std::vector<std::pair<double, int>> near;
    for (const PairStats& p : pairs)
      if (p.seen >= well_seen && (p.a == i || p.b == i)) near.push_back({p.mean_m, p.a == i ? p.b : p.a});
    std::sort(near.begin(), near.end());
    for (int k = 0; k < o.neighbours && k < static_cast<int>(near.size()); ++k) add(i, near[k].second);
  }
  return layout;
}

}  // namespace

SensorMuscleResult addSensorMuscles(const Model& passive, const Trajectory& data,
                                    const SensorMuscleOptions& o) {
  if (o.sensors < 1 || o.sensors > kMaxMuscleInputs)
    throw InputError("sensor muscles: sensors must be 1.." + std::to_string(kMaxMuscleInputs) +
                     ", got " + std::to_string(o.sensors));
  if (o.neighbours < 0 || o.neighbours > 64)
    throw InputError("sensor muscles: neighbours must be 0..64, got " + std::to_string(o.neighbours));
  if (o.ridges.empty())
    throw InputError("sensor muscles: no candidate ridge");
  for (double r : o.ridges)
    if (!(r > 0.0) || !std::isfinite(r))
      throw InputError("sensor muscles: every ridge must be a finite number > 0");
  if (!(o.validation_fraction > 0.0 && o.validation_fraction < 0.5))
    throw InputError("sensor muscles: the validation fraction must be in (0, 0.5)");
  if (o.horizon_frames < 1) throw InputError("sensor muscles: the horizon must be >= 1 frame");
  if (!(o.gain_margin >= 1.0) || !std::isfinite(o.gain_margin))
    throw InputError("sensor muscles: the gain margin must be a finite number >= 1");
  if (!(o.min_seen_share >= 0.0 && o.min_seen_share <= 1.0))
    throw InputError("sensor muscles: min_seen_share must be in [0, 1]");
  if (!(passive.frame_rate_hz > 0.0)) throw InputError("sensor muscles: the model has no frame rate");
  const int n = static_cast<int>(passive.particles.size());
  if (data.numMarkers() != n)
    throw InputError("sensor muscles: the data have " + std::to_string(data.numMarkers()) +
                     " markers, the model " + std::to_string(n) + " particles");
  for (int i = 0; i < n; ++i)
    if (data.marker_names[i] != passive.particles[i].name)
      throw InputError("sensor muscles: marker " + std::to_string(i) + " is '" + data.marker_names[i] +
                       "', the model's particle '" + passive.particles[i].name + "'");
  for (const ParamRef& ref : freeParameters(passive))
    if (!paramOf(passive, ref).has_value)
      throw InputError("sensor muscles: the passive model's '" + ref.name + "' has no value (identify it first)");
  const int frames = data.numFrames();
  const int validation_start = static_cast<int>(std::floor((1.0 - o.validation_fraction) * frames));
  if (validation_start < 4 || frames - validation_start < o.horizon_frames + 1)
    throw InputError("sensor muscles: " + std::to_string(frames) + " frames are too few to hold out " +
                     "a validation of " + std::to_string(o.horizon_frames) + " frames ahead");
  auto say = [&](const std::string& line) {
    if (o.progress) o.progress(line);
  };

  const Layout layout = chooseLayout(passive, data, o);
  if (layout.sensors.empty())
    throw InputError("sensor muscles: no pair of particles is seen together in " +
                     std::to_string(static_cast<int>(100 * o.min_seen_share)) + " % of the frames");
  if (layout.muscles.empty()) throw InputError("sensor muscles: no pair of particles to put a muscle on");
  const size_t unknowns = layout.muscles.size() * (2 * layout.sensors.size() + 3);
  if (unknowns > kMaxUnknowns)
    throw InputError("sensor muscles: " + std::to_string(layout.muscles.size()) + " muscles reading " +
                     std::to_string(layout.sensors.size()) + " sensors are " + std::to_string(unknowns) +
                     " unknowns, more than " + std::to_string(kMaxUnknowns) +
                     " (two dense matrices of that size): fewer sensors or neighbours");
  Fitter fitter(passive, data, layout);
  SensorMuscleResult result;
  result.sensors = static_cast<int>(layout.sensors.size());
  result.muscles = static_cast<int>(layout.muscles.size());
  result.unknowns = unknowns;
  {
    char line[200];
    std::snprintf(line, sizeof(line), "sensor muscles: %d sensors, %d muscles, %zu unknowns",
                  result.sensors, result.muscles, result.unknowns);
    say(line);
  }

  // The ridge: fitted on the frames before validation_start, judged on the rest.
  System sys;
  fitter.accumulate(1, validation_start, &sys);  // rows t <= validation_start - 2
  if (sys.rows == 0) throw InputError("sensor muscles: no frame gives an equation (gaps everywhere)");
  const std::vector<int> horizons = {o.horizon_frames};
  auto judge = [&](const Model& model, double* rms, double* cv, bool* bounded) {
    const PredictionReport report = evaluatePredictions(model, data, horizons, 10.0, validation_start);
    for (const PredictionError& row : report.rows) {
      if (row.predictor == Predictor::kModel) *rms = row.rms_m;
      if (row.predictor == Predictor::kConstantVelocity && cv) *cv = row.rms_m;
    }
    if (bounded) *bounded = report.rollout_bounded;
  };
  judge(passive, &result.passive_rms_m, &result.constant_velocity_rms_m, nullptr);
  int best = -1;
  double best_rms = std::numeric_limits<double>::infinity();
  bool best_bounded = false;
  for (double ridge : o.ridges) {
    Eigen::VectorXd theta;
    double rms = std::nan("");
    bool bounded = false;
    if (Fitter::solve(sys, ridge, &theta)) {
      try {
        judge(fitter.build(theta, o.gain_margin, validation_start), &rms, nullptr, &bounded);
      } catch (const InputError&) {
        rms = std::nan("");
      }
    }
    if (!std::isfinite(rms)) bounded = false;
    result.ridge_rms_m.push_back(rms);
    result.ridge_bounded.push_back(bounded ? 1 : 0);
    char line[200];
    std::snprintf(line, sizeof(line), "sensor muscles: ridge %.0e: %d frames ahead on the last %d "
                  "frames %.2f mm (passive %.2f mm, constant velocity %.2f mm), rollout %s",
                  ridge, o.horizon_frames, frames - validation_start, 1e3 * rms,
                  1e3 * result.passive_rms_m, 1e3 * result.constant_velocity_rms_m,
                  bounded ? "bounded" : "unbounded");
    say(line);
    // Bounded candidates first, then the lowest error.
    const bool better = std::isfinite(rms) &&
                        (best < 0 || (bounded && !best_bounded) || (bounded == best_bounded && rms < best_rms));
    if (better) {
      best = static_cast<int>(result.ridge_rms_m.size()) - 1;
      best_rms = rms;
      best_bounded = bounded;
    }
  }
  if (best < 0) throw InputError("sensor muscles: no candidate ridge gave a model (every solve failed)");
  result.ridge = o.ridges[best];
  result.validation_rms_m = best_rms;
  result.better_than_passive = best_bounded && best_rms < result.passive_rms_m;

  // The chosen ridge on every frame.
  fitter.accumulate(validation_start - 1, frames, &sys);
  Eigen::VectorXd theta;
  if (!Fitter::solve(sys, result.ridge, &theta))
    throw InputError("sensor muscles: the final solve failed");
  result.rows = sys.rows;
  result.residual_rms_m = Fitter::residualRms(sys, theta) / (passive.frame_rate_hz * passive.frame_rate_hz);
  result.model = fitter.build(theta, o.gain_margin, frames);
  return result;
}

}  // namespace mme
