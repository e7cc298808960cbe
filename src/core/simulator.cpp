// Simulator, and the Engine (compiled motion law) it shares with the cost function.
#include "motion_model_estimation/core/simulator.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <Eigen/Cholesky>

#include "engine.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/muscle.h"
#include "motion_model_estimation/core/spatial_grid.h"

namespace mme {

namespace {
// Flat x,y,z view of a vector of Eigen 3-vectors (contiguous, no padding: see static_assert).
double* flat(std::vector<Eigen::Vector3d>& v) { return v.empty() ? nullptr : v[0].data(); }
const double* flat(const std::vector<Eigen::Vector3d>& v) {
  return v.empty() ? nullptr : v[0].data();
}
}  // namespace

static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double),
              "State vectors are used as flat x,y,z arrays");

namespace detail {

// ------------------------------------------------------------------ laws

void LawTable::load(const Model& model) {
  const size_t nt = model.bond_types.size();
  spring.assign(nt, SpringLaw());
  flexion.assign(nt, FlexionLaw());
  viscosity_nspm.assign(nt, 0.0);
  max_elongation.assign(nt, 0.0);
  floor.assign(nt, FloorLaw());
  muscle.assign(nt, MuscleTypeLaw());
  values.assign(nt * kParamCount, 0.0);
  network.clear();
  // Every law form of every type is derived (absent parameters read their absent value): a kind
  // only reads its own form, and this stays independent of the kind.
  for (size_t t = 0; t < nt; ++t) {
    const BondType& type = model.bond_types[t];
    for (int id = 0; id < kParamCount; ++id) {
      const Param& p = type.param(static_cast<ParamId>(id));
      values[t * kParamCount + id] =
          p.present ? p.value : paramInfo(static_cast<ParamId>(id)).absent_value;
    }
    derive(t);
    MuscleTypeLaw& m = muscle[t];
    m.hidden = type.network_hidden;
    m.network_offset = static_cast<uint32_t>(network.size());
    for (const Param& p : type.network) network.push_back(p.present ? p.value : 0.0);
  }
  const Eigen::Vector3d g = model.gravity();
  for (int k = 0; k < 3; ++k) gravity_mps2[k] = g[k];
}

void LawTable::derive(size_t t) {
  const double* p = valuesOf(t);
  spring[t] = springLawOf(p);
  flexion[t] = flexionLawOf(p);
  floor[t] = floorLawOf(p);
  viscosity_nspm[t] = p[kViscosity];
  max_elongation[t] = p[kMaxElongation];
  muscle[t].gain_n = p[kGain];
  muscle[t].activation_time_s = p[kActivationTime];
}

void LawTable::set(const ParamRef& ref, double value) {
  if (ref.bond_type < 0) {
    gravity_mps2[ref.param] = value;
    return;
  }
  const size_t t = static_cast<size_t>(ref.bond_type);
  if (ref.isNetwork()) {
    network[muscle[t].network_offset + static_cast<uint32_t>(ref.param - kParamCount)] = value;
    return;
  }
  // The value, then every law form derived again from the type's values: a parameter id means
  // the same thing in every form that has it, whatever the type's kind.
  values[t * kParamCount + static_cast<size_t>(ref.param)] = value;
  derive(t);
}

// ------------------------------------------------------------------ engine

Engine::Engine(const Model& model, bool fast_paths) {
  n_ = static_cast<int>(model.particles.size());
  inv_mass3_.assign(3 * n_, 0.0);
  mobile3_.assign(3 * n_, 0.0);
  mass_.assign(n_, 0.0);
  fixed_.assign(n_, 0);
  for (int i = 0; i < n_; ++i) {
    const Particle& p = model.particles[i];
    mass_[i] = p.mass_kg;
    fixed_[i] = p.fixed ? 1 : 0;
    for (int k = 0; k < 3; ++k) {
      inv_mass3_[3 * i + k] = p.fixed ? 0.0 : 1.0 / p.mass_kg;
      mobile3_[3 * i + k] = p.fixed ? 0.0 : 1.0;
    }
  }
  // Springs grouped by type: the law is then loop-invariant and the kernel variant is chosen
  // once per run. Inside a type, bond order is kept.
  const int nt = static_cast<int>(model.bond_types.size());
  for (int t = 0; t < nt; ++t) {
    const BondType& type = model.bond_types[t];
    if (type.kind != BondKind::kSpring || !fast_paths) continue;
    SpringRun run{t, static_cast<uint32_t>(spring_pairs_.size()), 0};
    for (const Bond& b : model.bonds)
      if (b.type == t) spring_pairs_.push_back({b.particles[0], b.particles[1]});
    run.end = static_cast<uint32_t>(spring_pairs_.size());
    if (run.end > run.begin) spring_runs_.push_back(run);
  }
  // The built-in kinds' fast paths (specialised arrays); every other kind, or every kind with a
  // law when `fast_paths` is off, goes through the generic path with its kind's bondLaw().
  for (const Bond& b : model.bonds) {
    const BondType& type = model.bond_types[b.type];
    const BondKind kind = type.kind;
    const BondLaw& law = bondLaw(kind);
    if (kind == BondKind::kSpring && type.param(kMaxElongation).present)
      clamps_.push_back({b.particles[0], b.particles[1], b.type});  // a constraint, not a force
    if (kind == BondKind::kMuscle) {
      MuscleBond m{b.particles[0], b.particles[1], b.type,
                   static_cast<uint32_t>(muscle_inputs_.size()), 0};
      for (int in : b.inputs) {
        const Bond& ib = model.bonds[in];
        muscle_inputs_.push_back({ib.particles[0], ib.particles[1], ib.type});
      }
      m.input_end = static_cast<uint32_t>(muscle_inputs_.size());
      muscles_.push_back(m);
    } else if (fast_paths && kind == BondKind::kSpring) {
      // in spring_runs_ above
    } else if (fast_paths && kind == BondKind::kFlexion) {
      flexions_.push_back({b.particles[0], b.particles[1], b.particles[2], b.type});
    } else if (fast_paths && kind == BondKind::kViscosity) {
      unary_.push_back({b.particles[0], b.type});
    } else if (fast_paths && kind == BondKind::kFloor) {
      floors_.push_back({b.particles[0], b.type});
    } else if (law.force != nullptr) {
      GenericBond g{{b.particles[0], b.particles[0], b.particles[0]}, b.type, &law};
      for (int k = 1; k < kindArity(kind); ++k) g.p[k] = b.particles[k];  // the rest: unread
      generic_.push_back(g);
    } else {
      throw std::logic_error(std::string("Engine: bond kind '") + kindName(kind) +
                             "' has neither a fast path nor a force law (bondLaw)");
    }
  }
}

void Engine::muscleForces(const LawTable& laws, const double* x, const double* v, double* f,
                          const double* activation_n, double* excitation_n) const {
  double z[2 * kMaxMuscleInputs];  // validateModel bounds the input count
  for (size_t index = 0; index < muscles_.size(); ++index) {
    const MuscleBond& m = muscles_[index];
    const MuscleTypeLaw& law = laws.muscle[m.type];
    const int n_in = static_cast<int>(m.input_end - m.input_begin);
    for (int k = 0; k < n_in; ++k) {
      const InputBond& ib = muscle_inputs_[m.input_begin + k];
      const int a = 3 * ib.a, b = 3 * ib.b;
      elongationRaw(laws.spring[ib.type].rest_length, x + a, x + b, v + a, v + b, &z[k],
                    &z[n_in + k]);
    }
    const double excitation = muscleActivation(laws.network.data() + law.network_offset, n_in,
                                               law.hidden, law.gain_n, z);
    if (excitation_n) excitation_n[index] = excitation;
    const double activation =
        activation_n && law.activation_time_s > 0.0 ? activation_n[index] : excitation;
    const int a = 3 * m.a, b = 3 * m.b;
    musclePair(laws.spring[m.type], activation, x + a, x + b, v + a, v + b, f + a, f + b);
  }
}

// Out of line, so that forces() (the hot loop of the built-in kinds) compiles as without it.
__attribute__((noinline)) void Engine::genericForces(const LawTable& laws, const double* x,
                                                     const double* v, double* f) const {
  for (const GenericBond& g : generic_) {
    const double* xs[3] = {x + 3 * g.p[0], x + 3 * g.p[1], x + 3 * g.p[2]};
    const double* vs[3] = {v + 3 * g.p[0], v + 3 * g.p[1], v + 3 * g.p[2]};
    double* fs[3] = {f + 3 * g.p[0], f + 3 * g.p[1], f + 3 * g.p[2]};
    g.law->force(laws.valuesOf(static_cast<size_t>(g.type)), xs, vs, fs);
  }
}

void Engine::forces(const LawTable& laws, const double* x, const double* v, double* f,
                    const SpringLaw* inter_laws, const PairIdx* inter_pairs,
                    const SpringRun* inter_runs, size_t num_inter_runs,
                    const double* activation_n, double* excitation_n) const {
  const double gx = laws.gravity_mps2[0], gy = laws.gravity_mps2[1], gz = laws.gravity_mps2[2];
  for (int i = 0; i < n_; ++i) {
    const double m = mass_[i];
    f[3 * i] = m * gx;
    f[3 * i + 1] = m * gy;
    f[3 * i + 2] = m * gz;
  }
  for (const UnaryBond& u : unary_) {
    const double c = laws.viscosity_nspm[u.type];
    const int p = 3 * u.p;
    f[p] -= c * v[p];
    f[p + 1] -= c * v[p + 1];
    f[p + 2] -= c * v[p + 2];
  }
  for (const SpringRun& run : spring_runs_)
    springRun(laws.spring[run.law], spring_pairs_.data(), run.begin, run.end, x, v, f);
  for (const FlexionBond& b : flexions_) {
    const int a = 3 * b.a, m = 3 * b.b, c = 3 * b.c;
    flexionForceRaw(laws.flexion[b.type], x + a, x + m, x + c, v + a, v + m, v + c, f + a, f + m,
                    f + c);
  }
  if (!muscles_.empty()) muscleForces(laws, x, v, f, activation_n, excitation_n);
  for (const UnaryBond& u : floors_) {
    const int p = 3 * u.p;
    floorForceRaw(laws.floor[u.type], x + p, v + p, f + p);
  }
  if (!generic_.empty()) genericForces(laws, x, v, f);
  for (size_t r = 0; r < num_inter_runs; ++r) {
    const SpringRun& run = inter_runs[r];
    springRun(inter_laws[run.law], inter_pairs, run.begin, run.end, x, v, f);
  }
}

void Engine::integrate(double dt_s, const double* __restrict f, double* __restrict x,
                       double* __restrict v) const {
  // Per-component scale arrays instead of a fixed-flag branch: one vectorisable loop.
  const double* __restrict im = inv_mass3_.data();
  const double* __restrict mob = mobile3_.data();
  const int n3 = 3 * n_;
  for (int k = 0; k < n3; ++k) {
    v[k] += dt_s * (f[k] * im[k]);
    x[k] += (dt_s * mob[k]) * v[k];
  }
}

void Engine::clamp(const LawTable& laws, double* x) const {
  for (const ClampBond& b : clamps_) {
    const double max_len = (1.0 + laws.max_elongation[b.type]) * laws.spring[b.type].rest_length;
    double* xa = x + 3 * b.a;
    double* xb = x + 3 * b.b;
    const double dx = xb[0] - xa[0], dy = xb[1] - xa[1], dz = xb[2] - xa[2];
    const double l = std::sqrt(dx * dx + dy * dy + dz * dz);
    if (!(l > max_len)) continue;
    const bool fa = fixed_[b.a] != 0, fb = fixed_[b.b] != 0;
    if (fa && fb) continue;
    // Fraction of d to remove; split evenly unless one end is fixed.
    const double r = (l - max_len) / l;
    const double wa = fa ? 0.0 : (fb ? 1.0 : 0.5);
    const double wb = fb ? 0.0 : (fa ? 1.0 : 0.5);
    xa[0] += wa * r * dx; xa[1] += wa * r * dy; xa[2] += wa * r * dz;
    xb[0] -= wb * r * dx; xb[1] -= wb * r * dy; xb[2] -= wb * r * dz;
  }
}

double Engine::bondEnergy(const LawTable& laws, const double* x) const {
  double e = 0.0;
  for (const SpringRun& run : spring_runs_)
    for (uint32_t k = run.begin; k < run.end; ++k)
      e += springEnergyRaw(laws.spring[run.law], x + 3 * spring_pairs_[k].a,
                           x + 3 * spring_pairs_[k].b);
  for (const FlexionBond& b : flexions_)
    e += flexionEnergyRaw(laws.flexion[b.type], x + 3 * b.a, x + 3 * b.b, x + 3 * b.c);
  // A muscle's passive part only: its activation is a driving force, not a potential.
  for (const MuscleBond& m : muscles_)
    e += springEnergyRaw(laws.spring[m.type], x + 3 * m.a, x + 3 * m.b);
  for (const GenericBond& g : generic_) {
    if (g.law->energy == nullptr) continue;
    const double* xs[3] = {x + 3 * g.p[0], x + 3 * g.p[1], x + 3 * g.p[2]};
    e += g.law->energy(laws.valuesOf(static_cast<size_t>(g.type)), xs);
  }
  return e;
}

}  // namespace detail

// ------------------------------------------------------------------ simulator

struct Simulator::Impl {
  detail::Engine engine;
  detail::LawTable laws;
  int substeps = 1;
  struct Inter {
    int type;
    std::vector<uint8_t> in_a, in_b;
  };
  std::vector<Inter> inters;
  SpatialGrid grid;
  std::vector<std::pair<int, int>> found;
  std::vector<detail::PairIdx> inter_pairs;
  std::vector<detail::SpringRun> inter_runs;
  std::vector<double> f;
  std::vector<double> mass;
  State initial;
  size_t last_count = 0;

  /// Interaction springs at positions x: one run per interaction (law = its bond type).
  void findInteractions(const std::vector<Eigen::Vector3d>& x) {
    inter_pairs.clear();
    inter_runs.clear();
    last_count = 0;
    if (inters.empty()) return;
    double cell = 0.0;
    for (const Inter& in : inters) {
      const double c = laws.spring[in.type].max_distance;
      if (c > cell && std::isfinite(c)) cell = c;
    }
    if (!(cell > 0.0)) return;
    grid.build(x, cell);
    for (size_t k = 0; k < inters.size(); ++k) {
      const Inter& in = inters[k];
      const double cutoff = laws.spring[in.type].max_distance;
      if (!(cutoff > 0.0) || !std::isfinite(cutoff)) continue;
      found.clear();
      grid.pairsWithin(x, cutoff, in.in_a, in.in_b, &found);
      detail::SpringRun run{in.type, static_cast<uint32_t>(inter_pairs.size()), 0};
      for (const auto& p : found) inter_pairs.push_back({p.first, p.second});
      run.end = static_cast<uint32_t>(inter_pairs.size());
      inter_runs.push_back(run);
    }
    last_count = inter_pairs.size();
  }

  /// Some muscle's type has an activation time constant: states carry activations.
  bool activation_state = false;
  std::vector<double> excitation;  // every muscle's network output at the last forces()

  void updateActivationState() {
    activation_state = false;
    for (const detail::MuscleBond& m : engine.muscles())
      if (laws.muscle[m.type].activation_time_s > 0.0) activation_state = true;
    excitation.assign(engine.numMuscles(), 0.0);
  }

  /// Forces at s; a state without activations (or one of another model) has its muscles at
  /// their excitation.
  void forces(const State& s) {
    findInteractions(s.x_m);
    f.resize(3 * static_cast<size_t>(engine.numParticles()));
    const bool carried = activation_state && s.activation_n.size() == engine.numMuscles();
    engine.forces(laws, flat(s.x_m), flat(s.v_mps), f.data(), laws.spring.data(),
                  inter_pairs.data(), inter_runs.data(), inter_runs.size(),
                  carried ? s.activation_n.data() : nullptr,
                  activation_state ? excitation.data() : nullptr);
  }
};

Simulator::Simulator(const Model& model) : impl_(new Impl) {
  const std::string err = validateModel(model);
  if (!err.empty()) throw InputError("model: " + err);
  impl_->engine = detail::Engine(model);
  impl_->laws.load(model);
  impl_->substeps = model.substeps;
  const size_t n = model.particles.size();
  for (const Particle& p : model.particles) {
    impl_->mass.push_back(p.mass_kg);
    impl_->initial.x_m.push_back(p.position_m);
    impl_->initial.v_mps.push_back(p.velocity_mps);
  }
  for (const Interaction& in : model.interactions) {
    Impl::Inter c{in.type, std::vector<uint8_t>(n, 0), std::vector<uint8_t>(n, 0)};
    for (size_t i = 0; i < n; ++i) {
      c.in_a[i] = model.particles[i].group == in.group_a;
      c.in_b[i] = model.particles[i].group == in.group_b;
    }
    impl_->inters.push_back(std::move(c));
  }
  impl_->updateActivationState();
}

Simulator::~Simulator() = default;
Simulator::Simulator(Simulator&&) noexcept = default;
Simulator& Simulator::operator=(Simulator&&) noexcept = default;

void Simulator::setParameters(const Model& model) {
  impl_->laws.load(model);
  impl_->updateActivationState();
}

State Simulator::initialState() const { return impl_->initial; }

void Simulator::computeForces(const State& s, std::vector<Eigen::Vector3d>* forces_n) {
  const size_t n = static_cast<size_t>(impl_->engine.numParticles());
  if (s.x_m.size() != n || s.v_mps.size() != n)
    throw std::invalid_argument("Simulator: state size differs from the particle count");
  impl_->forces(s);
  forces_n->resize(n);
  for (size_t i = 0; i < n; ++i)
    (*forces_n)[i] = Eigen::Vector3d(impl_->f[3 * i], impl_->f[3 * i + 1], impl_->f[3 * i + 2]);
}

void Simulator::step(State* s, double dt_s) {
  const size_t n = static_cast<size_t>(impl_->engine.numParticles());
  if (s->x_m.size() != n || s->v_mps.size() != n)
    throw std::invalid_argument("Simulator: state size differs from the particle count");
  const size_t muscles = impl_->engine.numMuscles();
  // A state without activations (or another model's) has every muscle at rest, at its
  // excitation: forces() uses the excitation for it.
  const bool at_rest = impl_->activation_state && s->activation_n.size() != muscles;
  impl_->forces(*s);
  double* x = flat(s->x_m);
  impl_->engine.integrate(dt_s, impl_->f.data(), x, flat(s->v_mps));
  impl_->engine.clamp(impl_->laws, x);
  if (!impl_->activation_state) return;
  // At rest a = u, and the update below leaves it there.
  if (at_rest) {
    s->activation_n = impl_->excitation;
    return;
  }
  // Activation dynamics, exact for the excitation held over the substep:
  // a <- u + (a - u) exp(-dt / tau); a muscle without a time constant follows u at once.
  const std::vector<detail::MuscleBond>& bonds = impl_->engine.muscles();
  for (size_t k = 0; k < muscles; ++k) {
    const double tau_s = impl_->laws.muscle[bonds[k].type].activation_time_s;
    const double u = impl_->excitation[k];
    double& a = s->activation_n[k];
    a = tau_s > 0.0 ? u + (a - u) * std::exp(-dt_s / tau_s) : u;
  }
}

bool Simulator::hasActivationState() const { return impl_->activation_state; }

int Simulator::estimateActivations(State* s, const std::vector<Eigen::Vector3d>& acceleration_mps2,
                                   const std::vector<char>& known) {
  const size_t n = static_cast<size_t>(impl_->engine.numParticles());
  if (s->x_m.size() != n || s->v_mps.size() != n || acceleration_mps2.size() != n ||
      known.size() != n)
    throw std::invalid_argument("Simulator: state or acceleration size differs from the particle count");
  s->activation_n.clear();
  if (!impl_->activation_state) return 0;
  impl_->forces(*s);  // every muscle at its excitation: the forces to be corrected
  const std::vector<detail::MuscleBond>& bonds = impl_->engine.muscles();
  std::vector<int> row_of(n, -1);
  int rows = 0;
  for (size_t i = 0; i < n; ++i)
    if (known[i] && !impl_->engine.fixed()[i] && acceleration_mps2[i].allFinite()) row_of[i] = 3 * rows++;
  std::vector<size_t> columns;  // the muscles with an activation state
  for (size_t k = 0; k < bonds.size(); ++k)
    if (impl_->laws.muscle[bonds[k].type].activation_time_s > 0.0) columns.push_back(k);
  s->activation_n = impl_->excitation;
  if (rows == 0 || columns.empty()) return 0;
  // The rest of each seen particle's observed m a, and each activation's force on it.
  Eigen::VectorXd r(3 * rows);
  for (size_t i = 0; i < n; ++i)
    if (row_of[i] >= 0)
      for (int c = 0; c < 3; ++c)
        r(row_of[i] + c) = impl_->mass[i] * acceleration_mps2[i][c] - impl_->f[3 * i + c];
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(3 * rows, static_cast<Eigen::Index>(columns.size()));
  for (size_t j = 0; j < columns.size(); ++j) {
    const detail::MuscleBond& m = bonds[columns[j]];
    const Eigen::Vector3d d = s->x_m[m.b] - s->x_m[m.a];
    const double l = d.norm();
    if (!(l > 0.0)) continue;
    const Eigen::Vector3d u = d / l;  // a positive activation pulls a towards b and b towards a
    if (row_of[m.a] >= 0) a.block<3, 1>(row_of[m.a], static_cast<Eigen::Index>(j)) += u;
    if (row_of[m.b] >= 0) a.block<3, 1>(row_of[m.b], static_cast<Eigen::Index>(j)) -= u;
  }
  // The least change of the activations that explains the rest (minimum norm; a tiny ridge
  // keeps rows no muscle reaches from making the system singular).
  Eigen::MatrixXd g = a * a.transpose();
  const double ridge = 1e-9 * std::max(g.trace() / g.rows(), 1e-300);
  g.diagonal().array() += ridge;
  const Eigen::VectorXd delta = a.transpose() * g.ldlt().solve(r);
  if (!delta.allFinite()) return 0;
  for (size_t j = 0; j < columns.size(); ++j) s->activation_n[columns[j]] += delta(static_cast<Eigen::Index>(j));
  return static_cast<int>(columns.size());
}

void Simulator::stepFrame(State* s, double frame_period_s) {
  const double dt_s = frame_period_s / impl_->substeps;
  for (int k = 0; k < impl_->substeps; ++k) step(s, dt_s);
}

double Simulator::totalEnergy(const State& s) {
  const size_t n = static_cast<size_t>(impl_->engine.numParticles());
  if (s.x_m.size() != n || s.v_mps.size() != n)
    throw std::invalid_argument("Simulator: state size differs from the particle count");
  const double* x = flat(s.x_m);
  double kinetic = 0.0, gravitational = 0.0;
  const double* g = impl_->laws.gravity_mps2;
  for (size_t i = 0; i < n; ++i) {
    const double m = impl_->mass[i];
    kinetic += 0.5 * m * s.v_mps[i].squaredNorm();
    gravitational -= m * (g[0] * x[3 * i] + g[1] * x[3 * i + 1] + g[2] * x[3 * i + 2]);
  }
  double elastic = impl_->engine.bondEnergy(impl_->laws, x);
  impl_->findInteractions(s.x_m);
  for (const detail::SpringRun& run : impl_->inter_runs)
    for (uint32_t k = run.begin; k < run.end; ++k)
      elastic += detail::springEnergyRaw(impl_->laws.spring[run.law],
                                         x + 3 * impl_->inter_pairs[k].a,
                                         x + 3 * impl_->inter_pairs[k].b);
  return kinetic + elastic + gravitational;
}

size_t Simulator::lastInteractionBondCount() const { return impl_->last_count; }

Trajectory simulateTrajectory(const Model& model, int num_frames, double frame_rate_hz) {
  if (!(frame_rate_hz > 0.0) || !std::isfinite(frame_rate_hz))
    throw InputError("simulate: frame rate must be > 0");
  if (num_frames < 0) throw InputError("simulate: frame count must be >= 0");
  Simulator sim(model);
  Trajectory traj;
  for (const Particle& p : model.particles) traj.marker_names.push_back(p.name);
  traj.frame_rate_hz = frame_rate_hz;
  traj.resize(num_frames);
  std::fill(traj.occluded.begin(), traj.occluded.end(), 0);
  State s = sim.initialState();
  const int n = static_cast<int>(model.particles.size());
  const double period_s = 1.0 / frame_rate_hz;
  for (int t = 0; t < num_frames; ++t) {
    if (t > 0) sim.stepFrame(&s, period_s);
    for (int i = 0; i < n; ++i) traj.position(t, i) = s.x_m[i];
  }
  return traj;
}

}  // namespace mme
