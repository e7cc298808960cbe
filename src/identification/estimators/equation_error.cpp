// Equation error: for every free particle i and frame t, m_i a_i - F_known(x, v) = sum_j
// theta_j dF_i/dtheta_j, linear in the unknowns theta (see the header). Rows are weighted by
// h^2 / m_i so that with raw differences a row's residual is the one-step prediction error [m].
// The normal equations are accumulated term by term (a row touches only the unknowns of the bonds
// at its particle) and solved with column scaling.
#include "motion_model_estimation/identification/estimators/equation_error.h"
#include "motion_model_estimation/identification/estimators/normal_equations.h"

#include <Eigen/Dense>

#include <cmath>
#include <limits>
#include <map>

#include "motion_model_estimation/core/forces.h"
#include "motion_model_estimation/core/simulator.h"

namespace mme {

namespace {

/// How an unknown column maps back to a free parameter.
enum class Role {
  kDirect,   ///< the coefficient is the parameter (k, c, c_v, g, or L / theta0 with k known)
  kProduct,  ///< the coefficient is k x parameter (k L, k theta0): parameter = it / k's column
  /// A spring's rest length beside a free cubic term, linearised about the model's values (a
  /// Gauss-Newton step): the coefficient is L - L0, parameter = it + L0.
  kLinearized,
};

struct Column {
  int param;        ///< index into freeParameters()
  Role role;
  int partner = -1; ///< kProduct: the stiffness column
  double offset = 0.0;  ///< kLinearized: L0
};

/// Per bond type: the column of each linear unknown (-1 = known).
struct TypeColumns {
  int k = -1;        ///< stiffness, or the stiffness of a (k, kL) / (k, k theta0) pair
  int product = -1;  ///< k L (spring) or k theta0 (flexion), when both are free
  int rest = -1;     ///< L or theta0 alone (stiffness known): coefficient = the parameter
  int rest_step = -1;  ///< L - L0 (kLinearized): k, L and k_nl all free, linearised about L0
  int damping = -1;
  int viscosity = -1;
  int stiffness_nl = -1;  ///< spring cubic term (its rest length known)
  int damping_nl = -1;    ///< spring quadratic damping
};

/// Positions, velocities and accelerations of frame t from the raw frame step or a local
/// quadratic fit; false when a sample needed is occluded.
struct Kinematics {
  int half_width = 0;
  double h = 0.0;
  // Quadratic fit over j = -w..w: x = sum c0_j y_j, v = sum c1_j y_j / h, a = sum c2_j y_j / h^2.
  std::vector<double> c0, c1, c2;

  explicit Kinematics(int w, double h_s) : half_width(w), h(h_s) {
    if (w < 2) return;
    double n = 0, s2 = 0, s4 = 0;
    for (int j = -w; j <= w; ++j) {
      n += 1;
      s2 += j * j;
      s4 += static_cast<double>(j) * j * j * j;
    }
    const double det = n * s4 - s2 * s2;
    for (int j = -w; j <= w; ++j) {
      const double jj = static_cast<double>(j) * j;
      c0.push_back((s4 - s2 * jj) / det);
      c1.push_back(j / s2);
      c2.push_back(2.0 * (n * jj - s2) / det);
    }
  }
  int first(int /*frames*/) const { return half_width < 2 ? 1 : half_width; }
  int last(int frames) const { return frames - 1 - (half_width < 2 ? 1 : half_width); }

  bool at(const Trajectory& d, int t, int i, Eigen::Vector3d* x, Eigen::Vector3d* v,
          Eigen::Vector3d* a) const {
    if (half_width < 2) {
      if (d.isOccluded(t - 1, i) || d.isOccluded(t, i) || d.isOccluded(t + 1, i)) return false;
      *x = d.position(t, i);
      *v = (d.position(t, i) - d.position(t - 1, i)) / h;
      *a = (d.position(t + 1, i) - 2.0 * d.position(t, i) + d.position(t - 1, i)) / (h * h);
      return true;
    }
    x->setZero();
    v->setZero();
    a->setZero();
    for (int j = -half_width; j <= half_width; ++j) {
      if (d.isOccluded(t + j, i)) return false;
      const Eigen::Vector3d& y = d.position(t + j, i);
      *x += c0[j + half_width] * y;
      *v += c1[j + half_width] * y;
      *a += c2[j + half_width] * y;
    }
    *v /= h;
    *a /= h * h;
    return true;
  }
};

/// The unknowns' columns: per bond type, and gravity's.
struct ColumnLayout {
  std::vector<TypeColumns> types;
  std::vector<Column> columns;
  int gravity[3] = {-1, -1, -1};

  int add(int param, Role role, int partner = -1, double offset = 0.0) {
    columns.push_back({param, role, partner, offset});
    return static_cast<int>(columns.size()) - 1;
  }
};

/// The rest parameter a form solves for (kParamCount: none).
ParamId restParamOf(LinearForm form) {
  switch (form) {
    case LinearForm::kPair: return kRestLength;
    case LinearForm::kAngle: return kRestAngle;
    case LinearForm::kDrag:
    case LinearForm::kNone: break;
  }
  return kParamCount;
}

/// The column of free parameter `k` of a pair or an angle bond (a rest parameter is placed
/// later, by placeRestColumns, once the stiffness' column is known). "" or why it is not linear.
std::string placePairOrAngleParameter(const BondType& type, const ParamRef& r, int k,
                                      const EquationErrorOptions& options, TypeColumns* tc,
                                      ColumnLayout* layout) {
  const LinearForm form = bondKindInfo(type.kind).linear_form;
  const bool spring = form == LinearForm::kPair;
  const int rest_param = restParamOf(form);
  if (r.param == kStiffness) {
    tc->k = layout->add(k, Role::kDirect);
  } else if (r.param == rest_param) {
    const bool cubic = spring && (type.value(kStiffnessNl) != 0.0 || type.param(kStiffnessNl).free);
    const bool linearizable = cubic && options.linearize_rest_length && type.param(kStiffness).free &&
                              type.param(kStiffnessNl).free && type.param(kRestLength).has_value;
    if (cubic && !linearizable)
      return "'" + r.name + "' enters non-linearly (the type has a cubic stiffness_nl)";
  } else if (r.param == kDamping) {
    tc->damping = layout->add(k, Role::kDirect);
  } else if (r.param == kStiffnessNl && spring &&
             (!type.param(kRestLength).free || options.linearize_rest_length)) {
    tc->stiffness_nl = layout->add(k, Role::kDirect);  // k_nl (l - L)^3, L known (or L0)
  } else if (r.param == kDampingNl && spring) {
    tc->damping_nl = layout->add(k, Role::kDirect);    // c_nl s |s|
  } else {
    return "'" + r.name + "' does not enter the forces linearly";
  }
  return "";
}

/// A column for every free parameter but the rest parameters. "" or why the model does not fit
/// the form.
std::string placeParameterColumns(const Model& model, const std::vector<ParamRef>& refs,
                                  const EquationErrorOptions& options, ColumnLayout* layout) {
  for (size_t k = 0; k < refs.size(); ++k) {
    const ParamRef& r = refs[k];
    const int index = static_cast<int>(k);
    if (r.bond_type < 0) {
      layout->gravity[r.param] = layout->add(index, Role::kDirect);
      continue;
    }
    const BondType& type = model.bond_types[r.bond_type];
    TypeColumns& tc = layout->types[r.bond_type];
    std::string why = "'" + r.name + "' does not enter the forces linearly";
    switch (bondKindInfo(type.kind).linear_form) {
      case LinearForm::kPair:
      case LinearForm::kAngle:
        why = placePairOrAngleParameter(type, r, index, options, &tc, layout);
        break;
      case LinearForm::kDrag:
        if (r.param == kViscosity) {
          tc.viscosity = layout->add(index, Role::kDirect);
          why.clear();
        }
        break;
      case LinearForm::kNone:
        // Not linear (a muscle's activation is a network of other bonds' motion, a floor is
        // conditional on contact): left to the evolution strategy and the refinements.
        break;
    }
    if (!why.empty()) return why;
  }
  return "";
}

/// The rest parameters' columns: L - L0 beside a free cubic term (linearised), k L beside a free
/// stiffness, L alone when the stiffness is known.
void placeRestColumns(const Model& model, const std::vector<ParamRef>& refs, ColumnLayout* layout) {
  const auto freeIndex = [&](int type, int param) {
    for (size_t k = 0; k < refs.size(); ++k)
      if (refs[k].bond_type == type && refs[k].param == param) return static_cast<int>(k);
    return -1;
  };
  for (size_t t = 0; t < model.bond_types.size(); ++t) {
    const BondType& type = model.bond_types[t];
    const ParamId rest_param = restParamOf(bondKindInfo(type.kind).linear_form);
    if (rest_param == kParamCount) continue;  // no rest parameter solved for
    const int rest = freeIndex(static_cast<int>(t), rest_param);
    if (rest < 0) continue;
    TypeColumns& tc = layout->types[t];
    if (tc.stiffness_nl >= 0)  // linearised (checked by placePairOrAngleParameter)
      tc.rest_step = layout->add(rest, Role::kLinearized, -1, type.param(kRestLength).value);
    else if (tc.k >= 0)
      tc.product = layout->add(rest, Role::kProduct, tc.k);
    else
      tc.rest = layout->add(rest, Role::kDirect);
  }
}

/// What else keeps the model out of the form: a free rest length read by a muscle's network
/// (the known forces, free values set to 0, would be wrong), free interaction parameters.
std::string checkKnownForces(const Model& model) {
  for (const Bond& b : model.bonds)
    for (int in : b.inputs) {
      const BondType& in_type = model.bond_types[model.bonds[in].type];
      if (in_type.param(kRestLength).free)
        return "'" + in_type.name + "/rest_length' is free and read by a muscle's network";
    }
  for (const Interaction& in : model.interactions)
    for (ParamId id : paramsOfKind(model.bond_types[in.type].kind))
      if (model.bond_types[in.type].param(id).free)
        return "free parameters of interactions (bonds found on the fly)";
  return "";
}

/// Which particles each particle's row needs (itself, its bond partners, and for a muscle's
/// ends its input bonds' ends).
std::vector<std::vector<int>> rowNeeds(const Model& model) {
  const int n = static_cast<int>(model.particles.size());
  std::vector<std::vector<int>> needs(n);
  for (int i = 0; i < n; ++i) needs[i].push_back(i);
  for (const Bond& b : model.bonds) {
    const int arity = kindArity(model.bond_types[b.type].kind);
    for (int p = 0; p < arity; ++p)
      for (int q = 0; q < arity; ++q)
        if (p != q) needs[b.particles[p]].push_back(b.particles[q]);
    for (int in : b.inputs)
      for (int p = 0; p < arity; ++p)
        for (int q = 0; q < 2; ++q) needs[b.particles[p]].push_back(model.bonds[in].particles[q]);
  }
  return needs;
}

/// One frame's rows: per particle, the column entries (3 components each) of its unknowns.
class FrameEntries {
 public:
  explicit FrameEntries(int particles) : entries_(particles) {}
  void clear() {
    for (auto& e : entries_) e.clear();
  }
  void add(int particle, int column, const Eigen::Vector3d& f) {
    if (column < 0) return;
    auto it = entries_[particle].find(column);
    if (it == entries_[particle].end()) entries_[particle].emplace(column, f);
    else it->second += f;
  }
  const std::map<int, Eigen::Vector3d>& of(int particle) const { return entries_[particle]; }

 private:
  std::vector<std::map<int, Eigen::Vector3d>> entries_;
};

/// A pair bond's columns at the frame's state (LinearForm::kPair): tension f along u,
/// F_a += f u, F_b -= f u.
void addPairEntries(const Bond& b, const BondType& type, const TypeColumns& tc, const State& state,
                    FrameEntries* entries) {
  const int a = b.particles[0], c = b.particles[1];
  const Eigen::Vector3d d = state.x_m[c] - state.x_m[a];
  const double l = d.norm();
  if (!(l > 0.0)) return;
  const double lo = type.value(kMinDistance);
  const double hi = type.param(kMaxDistance).present ? type.value(kMaxDistance) : 1e300;
  if (!(l >= lo && l <= hi)) return;
  const Eigen::Vector3d u = d / l;
  const double s = (state.v_mps[c] - state.v_mps[a]).dot(u);
  const double k = type.value(kStiffness), rest = type.value(kRestLength);
  const auto pair = [&](int column, double f) {
    entries->add(a, column, f * u);
    entries->add(c, column, -f * u);
  };
  if (tc.rest_step >= 0) {        // f = k (l - L0) + k_nl (l - L0)^3 - (k0 + 3 k_nl0 (l - L0)^2) (L - L0)
    const double e = l - rest;
    pair(tc.rest_step, -(k + 3.0 * type.value(kStiffnessNl) * e * e));
    pair(tc.k, e);
  } else if (tc.product >= 0) {   // f = k l - (k L)
    pair(tc.k, l);
    pair(tc.product, -1.0);
  } else if (tc.k >= 0) {         // f = k (l - L), L known
    pair(tc.k, l - rest);
  } else if (tc.rest >= 0) {      // f = k l - k L, k known
    pair(tc.rest, -k);
  }
  pair(tc.damping, s);
  if (tc.stiffness_nl >= 0) {
    const double e = l - rest;
    pair(tc.stiffness_nl, e * e * e);
  }
  pair(tc.damping_nl, s * std::fabs(s));
}

/// An angle bond's columns (LinearForm::kAngle): torque T about the angle,
/// F_p = T grad_p(theta).
void addAngleEntries(const Bond& b, const BondType& type, const TypeColumns& tc, const State& state,
                     FrameEntries* entries) {
  const int a = b.particles[0], v = b.particles[1], c = b.particles[2];
  const double theta = flexionAngle(state.x_m[a], state.x_m[v], state.x_m[c]);
  // grad(theta) at each particle: the force of a law whose torque is exactly 1.
  FlexionLaw unit;
  unit.stiffness = 1.0;
  unit.rest_angle = theta + 1.0;
  Eigen::Vector3d ga = Eigen::Vector3d::Zero(), gv = ga, gc = ga;
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  addFlexionForce(unit, state.x_m[a], state.x_m[v], state.x_m[c], zero, zero, zero, &ga, &gv, &gc);
  const double theta_dot = ga.dot(state.v_mps[a]) + gv.dot(state.v_mps[v]) + gc.dot(state.v_mps[c]);
  const double k = type.value(kStiffness), rest = type.value(kRestAngle);
  const auto torque = [&](int column, double tq) {
    entries->add(a, column, tq * ga);
    entries->add(v, column, tq * gv);
    entries->add(c, column, tq * gc);
  };
  if (tc.product >= 0) {          // T = -k theta + (k theta0)
    torque(tc.k, -theta);
    torque(tc.product, 1.0);
  } else if (tc.k >= 0) {
    torque(tc.k, -(theta - rest));
  } else if (tc.rest >= 0) {
    torque(tc.rest, k);
  }
  torque(tc.damping, -theta_dot);
}

void addBondEntries(const Model& model, const ColumnLayout& layout, const State& state,
                    FrameEntries* entries) {
  for (const Bond& b : model.bonds) {
    const BondType& type = model.bond_types[b.type];
    const TypeColumns& tc = layout.types[b.type];
    switch (bondKindInfo(type.kind).linear_form) {
      case LinearForm::kPair: addPairEntries(b, type, tc, state, entries); break;
      case LinearForm::kAngle: addAngleEntries(b, type, tc, state, entries); break;
      case LinearForm::kDrag:  // F = -c v
        entries->add(b.particles[0], tc.viscosity, -state.v_mps[b.particles[0]]);
        break;
      case LinearForm::kNone:  // no unknowns: its force is in the known forces
        break;
    }
  }
}

/// Adds particle i's three rows, weighted by h^2 / m (residuals in metres: the one-step error
/// with raw differences), to the normal equations.
void accumulateRows(const std::map<int, Eigen::Vector3d>& entries, double w, const Eigen::Vector3d& rhs,
                    EquationErrorSystem* out) {
  std::vector<std::pair<int, Eigen::Vector3d>> row(entries.begin(), entries.end());
  for (auto& e : row) e.second *= w;
  for (size_t p = 0; p < row.size(); ++p) {
    out->atb[row[p].first] += row[p].second.dot(rhs);
    for (size_t q = 0; q <= p; ++q) {
      const double v = row[p].second.dot(row[q].second);
      out->ata(row[p].first, row[q].first) += v;
      if (q != p) out->ata(row[q].first, row[p].first) += v;
    }
  }
  out->btb += rhs.squaredNorm();
  out->rows += 3;
}

/// The frame's state from the data: where a sample is missing, the model's position and rest
/// (that particle's rows are skipped). seen[i]: particle i's kinematics are known.
void frameState(const Model& model, const Trajectory& trajectory, const Kinematics& kin, int t,
                State* state, std::vector<Eigen::Vector3d>* acc, std::vector<uint8_t>* seen) {
  for (size_t i = 0; i < model.particles.size(); ++i) {
    (*seen)[i] = kin.at(trajectory, t, static_cast<int>(i), &state->x_m[i], &state->v_mps[i], &(*acc)[i]);
    if (!(*seen)[i]) {
      state->x_m[i] = model.particles[i].position_m;
      state->v_mps[i].setZero();
    }
    if (model.particles[i].fixed) state->v_mps[i] = model.particles[i].velocity_mps;
  }
}

/// Every frame's rows into out's normal equations.
void accumulateFrames(const Model& model, const Trajectory& trajectory, const ColumnLayout& layout,
                      const Kinematics& kin, double h, EquationErrorSystem* out) {
  const int n = static_cast<int>(model.particles.size());
  // Known forces: the model with every free value set to 0 (what is left does not depend on
  // the unknowns; each unknown's own contribution is its column).
  Model known = model;
  for (const ParamRef& r : freeParameters(model)) setParam(known, r, 0.0);
  Simulator simulator(known);
  const std::vector<std::vector<int>> needs = rowNeeds(model);
  State state;
  state.x_m.resize(n);
  state.v_mps.resize(n);
  std::vector<Eigen::Vector3d> acc(n), known_force;
  std::vector<uint8_t> seen(n);
  FrameEntries entries(n);
  const int frames = trajectory.numFrames();
  for (int t = kin.first(frames); t <= kin.last(frames); ++t) {
    frameState(model, trajectory, kin, t, &state, &acc, &seen);
    entries.clear();
    simulator.computeForces(state, &known_force);
    addBondEntries(model, layout, state, &entries);
    for (int i = 0; i < n; ++i) {
      if (model.particles[i].fixed) continue;
      bool complete = true;
      for (int j : needs[i]) complete = complete && seen[j];
      if (!complete) continue;
      const double m = model.particles[i].mass_kg;
      for (int c = 0; c < 3; ++c) {
        Eigen::Vector3d unit = Eigen::Vector3d::Zero();
        unit[c] = m;
        entries.add(i, layout.gravity[c], unit);
      }
      const double w = h * h / m;
      accumulateRows(entries.of(i), w, w * (m * acc[i] - known_force[i]), out);
    }
  }
}

}  // namespace

EquationErrorSystem buildEquationErrorSystem(const Model& model, const Trajectory& trajectory,
                                             const EquationErrorOptions& options) {
  EquationErrorSystem out;
  const std::vector<ParamRef> refs = freeParameters(model);
  const double rate_hz = model.frame_rate_hz > 0.0 ? model.frame_rate_hz : trajectory.frame_rate_hz;
  if (!(rate_hz > 0.0) || trajectory.numMarkers() != static_cast<int>(model.particles.size())) {
    out.reason = "no frame rate, or the trajectory's markers are not the model's particles";
    return out;
  }
  ColumnLayout layout;
  layout.types.resize(model.bond_types.size());
  out.reason = placeParameterColumns(model, refs, options, &layout);
  if (out.reason.empty()) out.reason = checkKnownForces(model);
  if (!out.reason.empty()) return out;
  placeRestColumns(model, refs, &layout);

  const double h = 1.0 / rate_hz;
  const size_t nc = layout.columns.size();
  out.ata = Eigen::MatrixXd::Zero(nc, nc);
  out.atb = Eigen::VectorXd::Zero(nc);
  accumulateFrames(model, trajectory, layout, Kinematics(options.smoothing_half_width, h), h, &out);
  if (out.rows == 0) {
    out.reason = "no frame with every sample a row needs";
    return out;
  }
  for (const Column& c : layout.columns) {
    out.column_param.push_back(c.param);
    out.column_partner.push_back(c.role == Role::kProduct ? c.partner : -1);
    out.column_offset.push_back(c.offset);
  }
  return out;
}

bool physicalOnlyPositive(ParamId id) {
  return id < kParamCount && paramInfo(id).physically_positive;
}

EquationErrorResult solveEquationError(const Model& model, const Trajectory& trajectory,
                                       const EquationErrorOptions& options) {
  EquationErrorResult out;
  const std::vector<ParamRef> refs = freeParameters(model);
  out.values.assign(refs.size(), std::numeric_limits<double>::quiet_NaN());
  EquationErrorSystem system = buildEquationErrorSystem(model, trajectory, options);
  if (!system.reason.empty()) {
    out.reason = system.reason;
    return out;
  }
  out.rows = system.rows;
  const Eigen::MatrixXd& ata = system.ata;
  const Eigen::VectorXd& atb = system.atb;
  const double btb = system.btb;
  const size_t nc = system.column_param.size();
  // A column no row touches stays undetermined (normal_equations.h holds it at 0).
  const NormalEquationsSolution solved = solveNormalEquations(ata, atb, btb);
  if (!solved.trusted) {
    out.reason = "the equation error's " + std::to_string(nc) +
                 " unknowns could not be solved reliably (not finite, or the residual stayed above "
                 "the right-hand side at every ridge)";
    return out;
  }
  const Eigen::VectorXd& theta = solved.theta;
  out.residual_rms_m = std::sqrt(solved.rss / out.rows);
  for (size_t j = 0; j < nc; ++j) {
    if (!(ata(j, j) > 0.0)) continue;
    double value = theta[j] + system.column_offset[j];
    if (system.column_partner[j] >= 0) value = theta[j] / theta[system.column_partner[j]];
    out.values[system.column_param[j]] = value;
  }
  // Non-physical values (a negative stiffness, damping or length) are not a start; a negative
  // cubic stiffness is (a softening spring).
  for (size_t k = 0; k < refs.size(); ++k) {
    const ParamRef& r = refs[k];
    if (r.bond_type >= 0 && physicalOnlyPositive(static_cast<ParamId>(r.param)) && !(out.values[k] > 0.0))
      out.values[k] = std::numeric_limits<double>::quiet_NaN();
    if (!std::isfinite(out.values[k])) out.values[k] = std::numeric_limits<double>::quiet_NaN();
  }
  out.applicable = true;
  return out;
}

}  // namespace mme
