// The mechanical model: particles, a catalogue of bond types, installed bonds and interactions.
// Plain data (no ROS); built by the YAML loader or by the built-in scenes.
#pragma once

#include <Eigen/Core>
#include <array>
#include <limits>
#include <string>
#include <vector>

#include "motion_model_estimation/core/bond_kind.h"

namespace mme {

/// One scalar parameter of a bond type or of gravity (SPEC section 2 parameter block).
struct Param {
  double value = 0.0;      ///< value; for a free parameter only the initial guess
  bool present = false;    ///< key given in the model (absent optional keys mean 0 / off)
  bool has_value = false;  ///< a value was given (a free parameter may have none)
  bool free = false;       ///< identify it
  double min = -std::numeric_limits<double>::infinity();  ///< lower bound (search space)
  double max = std::numeric_limits<double>::infinity();   ///< upper bound (search space)
  bool has_min = false;
  bool has_max = false;
};

/// Parameters allowed for a bond kind, in canonical order (bondKindInfo(kind).params).
const std::vector<ParamId>& paramsOfKind(BondKind kind);
/// The model file's name of a kind (bondKindInfo(kind).name).
const char* kindName(BondKind kind);
/// Number of particles a bond of this kind joins (spring 2, flexion 3, viscosity 1, muscle 2).
int kindArity(BondKind kind);

struct BondType {
  std::string name;
  BondKind kind = BondKind::kSpring;
  std::array<Param, kParamCount> params{};
  /// Muscles (see muscle.h): input bonds each bond of the type reads, hidden units, and the
  /// network's parameters (muscleNetworkSize(network_inputs, network_hidden) of them, named by
  /// muscleNetworkKey; an absent one is 0 and fixed). Empty for every other kind.
  int network_inputs = 0;
  int network_hidden = 0;
  std::vector<Param> network;
  Param& param(ParamId id) { return params[id]; }
  const Param& param(ParamId id) const { return params[id]; }
  /// Value used by the physics: 0 when absent.
  double value(ParamId id) const { return params[id].present ? params[id].value : 0.0; }
};

struct Particle {
  std::string name;
  double mass_kg = 1.0;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
  bool fixed = false;
  std::string group;
};

/// An installed bond: type index and particle indices (only the first `arity` are used;
/// flexion: middle = vertex).
struct Bond {
  int type = -1;
  std::array<int, 3> particles{{-1, -1, -1}};
  std::string name;         ///< optional; unique when given; needed to be a muscle's input
  std::vector<int> inputs;  ///< muscle bonds: indices of the bonds its network reads
};

/// Bonds installed on the fly between particles of two groups within the type's max_distance.
struct Interaction {
  int type = -1;
  std::string group_a;
  std::string group_b;
};

struct Model {
  std::string frame_id = "world";
  double frame_rate_hz = 0.0;  ///< 0 = take it from the data
  int substeps = 1;
  std::array<Param, 3> gravity_mps2{};  ///< x, y, z; names "gravity/x" ... when free
  std::vector<Particle> particles;
  std::vector<BondType> bond_types;
  std::vector<Bond> bonds;
  std::vector<Interaction> interactions;

  int particleIndex(const std::string& name) const;  ///< -1 when unknown
  int bondTypeIndex(const std::string& name) const;  ///< -1 when unknown
  int bondIndex(const std::string& name) const;      ///< installed bond by name; -1 when unknown
  Eigen::Vector3d gravity() const;
};

/// Where a free parameter lives in the model.
struct ParamRef {
  std::string name;  ///< "<bond_type>/<param>" (muscle network: "<bond_type>/w1_0_2", ...) or "gravity/x|y|z"
  int bond_type = -1;  ///< -1 for gravity
  /// ParamId; kParamCount + k for the k-th network parameter of a muscle type
  /// (BondType::network[k]); or the gravity component 0..2.
  int param = 0;
  bool isNetwork() const { return bond_type >= 0 && param >= kParamCount; }
};

/// All free parameters in canonical order (bond types in catalogue order; in a type its
/// paramsOfKind parameters, then its network parameters in BondType::network order; then
/// gravity x, y, z).
std::vector<ParamRef> freeParameters(const Model& model);
/// All parameters that are present (free or fixed), same order rules.
std::vector<ParamRef> presentParameters(const Model& model);
/// The parameter block a reference points to (a bond type's parameter or a gravity component).
Param& paramOf(Model& model, const ParamRef& ref);
const Param& paramOf(const Model& model, const ParamRef& ref);
double getParam(const Model& model, const ParamRef& ref);
void setParam(Model& model, const ParamRef& ref, double value);
std::vector<double> getValues(const Model& model, const std::vector<ParamRef>& refs);
void setValues(Model& model, const std::vector<ParamRef>& refs, const std::vector<double>& values);

/// Checks the model's consistency (indices, arities, masses, substeps). Empty string = valid,
/// otherwise a readable reason.
std::string validateModel(const Model& model);

}  // namespace mme
