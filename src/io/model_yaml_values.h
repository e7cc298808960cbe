// Internal to the model YAML reader (not installed): the checked conversions every section of
// a model document goes through, and the section readers that build a Model from them.
//
// The reader is split by section (top level and gravity, particles, bond types, bonds, muscle
// inputs, interactions) so that each file holds one part of the format; they share this
// header so that every problem is reported the same way, as
//     "SOURCE:LINE: key 'KEY': reason"
// (see model_yaml_load.cpp for the full description of the messages).
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "motion_model_estimation/core/model.h"

namespace mme {
namespace model_yaml {

/// 1-based line of a node. yaml-cpp gives a null mark (-1) for nodes it synthesised; those
/// are reported on line 1 rather than as line 0.
int lineOf(const YAML::Node& node);

/// One "key: value" entry of a YAML map, with both nodes kept for line numbers.
struct Entry {
  std::string key;
  YAML::Node key_node;
  YAML::Node value;
  /// Line to blame for a bad value: an empty value (`mass:`) has its mark after the key, on
  /// the next line, so point at the key instead.
  int valueLine() const { return value.IsNull() ? lineOf(key_node) : lineOf(value); }
};

/// Checked conversions of YAML nodes for one document. Every failure throws InputError naming
/// the document (`source`), the line and the key; `where` is appended to the reason to name
/// the list entry the key belongs to (" in particle 'p0'", "" at the top level).
class ValueReader {
 public:
  explicit ValueReader(std::string source) : source_(std::move(source)) {}

  const std::string& source() const { return source_; }

  [[noreturn]] void fail(int line, const std::string& key, const std::string& reason) const;

  /// Reads a map's entries in file order; rejects non-string keys and duplicate keys (yaml-cpp
  /// silently keeps both, and a duplicated key is almost always a copy-paste mistake).
  std::vector<Entry> entries(const YAML::Node& map, const std::string& key,
                             const std::string& where) const;
  /// A sequence entry (particles, bond_types, ...); an absent/empty value is an empty list.
  const YAML::Node& sequence(const Entry& e) const;

  std::string asString(const Entry& e, const std::string& key, const std::string& where) const;
  double asNumber(const YAML::Node& node, int line, const std::string& key,
                  const std::string& where) const;
  double asNumber(const Entry& e, const std::string& key, const std::string& where) const;
  double asFinite(const Entry& e, const std::string& key, const std::string& where) const;
  bool asBool(const YAML::Node& node, int line, const std::string& key,
              const std::string& where) const;
  int asInt(const Entry& e, const std::string& key, const std::string& where) const;
  /// A non-negative integer no larger than `max` (a muscle's inputs and hidden units).
  int asCount(const Entry& e, int max, const std::string& where) const;
  Eigen::Vector3d asVector3(const Entry& e, const std::string& key,
                            const std::string& where) const;

  /// Stores a bound; -inf as min / +inf as max are "no bound" (how exports omit them).
  void setBound(Param& p, bool is_min, double v, int line, const std::string& key,
                const std::string& where) const;
  /// A parameter: a plain number (present, fixed) or a block {value, free, min, max, std}.
  Param readParam(const Entry& e, const std::string& where) const;

  /// ", got 'abc'" for scalars, so the user sees what was read.
  static std::string describe(const YAML::Node& node);

 private:
  std::string source_;
};

// Section readers, one per top-level list (and gravity), in the order the loader calls them:
// each may use what the earlier ones added to `model` (bonds name particles and bond types).

/// `gravity:` as [gx, gy, gz] or a block {value, free, min, max, std} (model_yaml_load.cpp).
void readGravity(const ValueReader& r, const Entry& e, Model& model);
/// `particles:` (model_yaml_particles.cpp).
void readParticles(const ValueReader& r, const Entry& list, Model& model);
/// `bond_types:` with their parameters and muscles' network layout (model_yaml_bond_types.cpp).
void readBondTypes(const ValueReader& r, const Entry& list, Model& model);
/// `bonds:`, including the muscles' `inputs:` (model_yaml_bonds.cpp).
void readBonds(const ValueReader& r, const Entry& list, Model& model);
/// `interactions:` (model_yaml_interactions.cpp).
void readInteractions(const ValueReader& r, const Entry& list, Model& model);

/// A muscle bond's `inputs:` entry, kept until every bond is read: inputs name bonds that may
/// come later in the list.
struct PendingInputs {
  std::size_t bond;    ///< index of the muscle bond in model.bonds
  const Entry* entry;  ///< its `inputs:` entry (owned by the caller)
  std::string where;   ///< " in bonds[i]"
};
/// Resolves the muscles' input bond names into indices (model_yaml_muscle_inputs.cpp).
void resolveMuscleInputs(const ValueReader& r, const std::vector<PendingInputs>& pending,
                         Model& model);

}  // namespace model_yaml
}  // namespace mme
