// The catalogue of bond kinds: every fixed fact about a kind (its YAML name, arity, parameter
// list, how the estimators and structure selection treat it) in one table, bondKindInfo().
// Adding a kind is one entry here plus its force law in forces.cpp (bondLaw); the rest of the
// package reads these tables (docs/architecture.md "Adding a bond kind"). The switches that
// remain over BondKind are exhaustive (no `default:`) and the core is built with
// -Werror=switch, so a forgotten kind does not compile; test_bond_kind walks every kind's entry.
#pragma once

#include <string>
#include <vector>

namespace mme {

enum class BondKind { kSpring, kFlexion, kViscosity, kMuscle, kFloor };

/// Every fixed-size parameter a bond type can carry. Which ones apply depends on the kind
/// (BondKindInfo::params). A muscle's network parameters are not here: their number depends on
/// the type (BondType::network, see muscle.h).
enum ParamId : int {
  kStiffness = 0,     ///< spring, muscle, floor [N/m]; flexion [N m/rad]
  kRestLength,        ///< spring, muscle [m]
  kDamping,           ///< spring, muscle, floor [N s/m]; flexion [N m s/rad]
  kStiffnessNl,       ///< spring cubic term [N/m^3]
  kDampingNl,         ///< spring quadratic damping [N s^2/m^2]
  kMinDistance,       ///< spring active only when length >= it [m]
  kMaxDistance,       ///< spring active only when length <= it [m]
  kMaxElongation,     ///< Provot's tau_c [1]: length clamped to (1+tau_c) rest_length
  kRestAngle,         ///< flexion [rad]
  kViscosity,         ///< unary viscosity [N s/m]
  kGain,              ///< muscle output gain [N]: activation = gain * tanh(network output)
  kFriction,          ///< floor: viscous friction along the floor while in contact [N s/m]
  kHeight,            ///< floor: height of the floor plane z = height [m] (world z up)
  /// floor: depth over which damping and friction grow from 0 to full [m]; 0 or absent: full
  /// from the first contact (docs/model_file.md "Ground contact")
  kContactDepth,
  /// muscle: activation dynamics' time constant [s]; 0 or absent: the activation is the
  /// network's output at once (muscle.h)
  kActivationTime,
  kParamCount
};

/// YAML key / parameter-name suffix of a ParamId ("stiffness", "rest_length", ...).
const char* paramKey(ParamId id);

/// What is fixed about one parameter kind: the one table the search space, the equation error,
/// structure selection and the model file read, so that they cannot disagree.
struct ParamInfo {
  ParamId id;
  const char* key;   ///< paramKey()
  const char* unit;  ///< on a pair bond (flexion: per radian instead of per metre)
  /// Searched in log space by the evolution strategy (a magnitude whose scale is unknown: a
  /// value near 0 and one of 1e4 are equally plausible).
  bool log_search;
  /// Physical only when > 0: an estimate <= 0 (e.g. from a linear solve) marks a bond the data
  /// do not support. A cubic stiffness may be negative (a softening spring) although the
  /// search covers the stiffening side only; a rest angle or a floor height has any sign.
  bool physically_positive;
  /// A distance between particles [m]: its default range and start come from the observed
  /// bond lengths.
  bool length_like;
  /// The value the force laws use when the key is absent: 0 (the term is off), or a bound that
  /// never applies (max_distance: no upper condition).
  double absent_value;
};
/// The catalogue entry of a parameter kind (id < kParamCount).
const ParamInfo& paramInfo(ParamId id);

/// How a kind's parameters enter its force linearly: the rows the equation error writes for its
/// bonds, and the values structure selection reads back for a candidate type. Each form fixes
/// the parameters it solves for, so a kind of an existing form needs no estimator code.
enum class LinearForm {
  /// Not linear in its parameters (conditional, or driven by a network): its free parameters are
  /// left to the evolution strategy and the refinements; its fixed ones are known forces.
  kNone,
  /// A pair's tension k (l - rest_length) + c s + k_nl (l - rest_length)^3 + c_nl s|s| along the
  /// pair (s: elongation speed).
  kPair,
  /// A torque -k (theta - rest_angle) - c dtheta/dt about the middle particle's angle.
  kAngle,
  /// A drag -viscosity v on one particle.
  kDrag,
};

/// What is fixed about one bond kind.
struct BondKindInfo {
  BondKind kind;
  const char* name;             ///< the model file's `kind:` value
  int arity;                    ///< particles a bond joins (flexion: the middle one is the vertex)
  std::vector<ParamId> params;  ///< fixed-size parameters allowed, in canonical order
  /// A pair bond with a rest length, so its elongation l - rest_length [m] and elongation
  /// speed [m/s] are defined: strain colouring, the stiffest mode, muscle inputs.
  bool has_elongation;
  /// May be installed on the fly between groups (`interactions:`).
  bool interactions;
  /// Has variable-length network parameters (BondType::network) and per-bond inputs.
  bool network;
  /// How the equation error solves for its parameters (kNone: it does not).
  LinearForm linear_form;
  /// Structure selection's name prefix for its shared types of this kind ("s" gives s00, s01,
  /// ...); nullptr: never a candidate.
  const char* candidate_prefix;
  // Local-cost sites (the evolution strategy's crossover) are, for every kind, the `arity`
  // particles a bond joins: the particles its force acts on.
};

/// The catalogue entry of a kind.
const BondKindInfo& bondKindInfo(BondKind kind);
/// The kind named `name` in a model file; nullptr when there is none.
const BondKindInfo* bondKindByName(const std::string& name);
/// Every kind, in enum order.
const std::vector<BondKind>& allBondKinds();
/// "spring, flexion, viscosity, muscle or floor": for error messages.
std::string bondKindNameList();

}  // namespace mme
