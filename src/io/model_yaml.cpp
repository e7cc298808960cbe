// Model files (SPEC section 2) and exported models (SPEC section 4) in YAML, via yaml-cpp.
//
// Error messages. Every problem in a model document throws InputError with
//     "SOURCE:LINE: key 'KEY': reason"
// SOURCE is the file path (or loadModelString's source_name), LINE the 1-based line of the
// offending node. KEY is the path of the offending key *inside the entry it belongs to*:
// a top-level key ('frame_rate_hz', 'gravity.value'), a key of a list entry ('mass',
// 'particles', 'stiffness.min'); the list entry itself is named at the end of the reason
// ("... in particle 'p0'", "... in bond type 's01'", "... in bonds[3]", "... in
// interactions[0]"; indices 0-based as in the file's order). Example:
//     model.yaml:12: key 'stifness': unknown key in bond type 's01' (allowed for spring: ...)
// The few errors that belong to no key drop the key part:
//     "SOURCE:LINE: YAML syntax error: <yaml-cpp message>"
//     "SOURCE:1: <validateModel reason>"            (consistency check of the finished model)
//     "PATH: cannot read file (<strerror>)"          (loadModelFile)
//     "PATH: cannot write: <strerror>"               (writeFileAtomically)
//
// Loading builds a local Model and returns it only once it is complete and validated, so a
// caller never sees a half-loaded model. Top-level sections are processed in dependency order
// (particles, bond_types, then bonds and interactions) whatever their order in the file,
// because YAML maps are unordered.

#include "motion_model_estimation/io/model_yaml.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <utility>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/muscle.h"

namespace mme {

namespace {

const char* kAxisName[3] = {"x", "y", "z"};
constexpr double kInf = std::numeric_limits<double>::infinity();

// ------------------------------------------------------------------------------------------
// Loading
// ------------------------------------------------------------------------------------------

/// 1-based line of a node. yaml-cpp gives a null mark (-1) for nodes it synthesised; those
/// are reported on line 1 rather than as line 0.
int lineOf(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  return mark.line >= 0 ? mark.line + 1 : 1;
}

/// One "key: value" entry of a YAML map, with both nodes kept for line numbers.
struct Entry {
  std::string key;
  YAML::Node key_node;
  YAML::Node value;
  /// Line to blame for a bad value: an empty value (`mass:`) has its mark after the key, on
  /// the next line, so point at the key instead.
  int valueLine() const { return value.IsNull() ? lineOf(key_node) : lineOf(value); }
};

class Loader {
 public:
  explicit Loader(std::string source) : source_(std::move(source)) {}

  Model load(const std::string& text) {
    YAML::Node root;
    try {
      root = YAML::Load(text);
    } catch (const YAML::Exception& e) {
      const int line = e.mark.line >= 0 ? e.mark.line + 1 : 1;
      throw InputError(source_ + ":" + std::to_string(line) + ": YAML syntax error: " + e.msg);
    }
    try {
      return build(root);
    } catch (const InputError&) {
      throw;
    } catch (const YAML::Exception& e) {
      // Safety net: every conversion below is checked, but a yaml-cpp exception must still
      // come out as a readable InputError, never as a crash.
      const int line = e.mark.line >= 0 ? e.mark.line + 1 : 1;
      throw InputError(source_ + ":" + std::to_string(line) + ": " + e.msg);
    }
  }

 private:
  std::string source_;

  [[noreturn]] void fail(int line, const std::string& key, const std::string& reason) const {
    throw InputError(source_ + ":" + std::to_string(line) + ": key '" + key + "': " + reason);
  }

  /// Reads a map's entries in file order; rejects non-string keys and duplicate keys (yaml-cpp
  /// silently keeps both, and a duplicated key is almost always a copy-paste mistake).
  std::vector<Entry> entries(const YAML::Node& map, const std::string& key,
                             const std::string& where) const {
    if (!map.IsMap()) fail(lineOf(map), key, "expected a map" + where);
    std::vector<Entry> out;
    std::map<std::string, int> seen;
    for (auto it = map.begin(); it != map.end(); ++it) {
      if (!it->first.IsScalar()) fail(lineOf(it->first), key, "map keys must be names" + where);
      Entry e{it->first.Scalar(), it->first, it->second};
      auto [pos, inserted] = seen.emplace(e.key, lineOf(e.key_node));
      if (!inserted)
        fail(lineOf(e.key_node), e.key,
             "duplicate key (first at line " + std::to_string(pos->second) + ")" + where);
      out.push_back(std::move(e));
    }
    return out;
  }

  std::string asString(const Entry& e, const std::string& key, const std::string& where) const {
    if (!e.value.IsScalar()) fail(e.valueLine(), key, "expected a name" + where);
    return e.value.Scalar();
  }

  double asNumber(const YAML::Node& node, int line, const std::string& key,
                  const std::string& where) const {
    double v = 0.0;
    if (!node.IsScalar() || !YAML::convert<double>::decode(node, v) || std::isnan(v))
      fail(line, key, "expected a number" + describe(node) + where);
    return v;
  }
  double asNumber(const Entry& e, const std::string& key, const std::string& where) const {
    return asNumber(e.value, e.valueLine(), key, where);
  }
  double asFinite(const Entry& e, const std::string& key, const std::string& where) const {
    const double v = asNumber(e, key, where);
    if (!std::isfinite(v)) fail(e.valueLine(), key, "must be finite" + where);
    return v;
  }

  bool asBool(const YAML::Node& node, int line, const std::string& key,
              const std::string& where) const {
    bool v = false;
    if (!node.IsScalar() || !YAML::convert<bool>::decode(node, v))
      fail(line, key, "expected true or false" + describe(node) + where);
    return v;
  }

  int asInt(const Entry& e, const std::string& key, const std::string& where) const {
    int v = 0;
    if (!e.value.IsScalar() || !YAML::convert<int>::decode(e.value, v))
      fail(e.valueLine(), key, "expected an integer" + describe(e.value) + where);
    return v;
  }

  Eigen::Vector3d asVector3(const Entry& e, const std::string& key,
                            const std::string& where) const {
    if (!e.value.IsSequence() || e.value.size() != 3)
      fail(e.valueLine(), key, "expected a list of 3 numbers [x, y, z]" + where);
    Eigen::Vector3d v;
    for (int k = 0; k < 3; ++k) {
      v[k] = asNumber(e.value[k], lineOf(e.value[k]), key, where);
      if (!std::isfinite(v[k])) fail(lineOf(e.value[k]), key, "must be finite" + where);
    }
    return v;
  }

  /// " (got 'abc')" for scalars, so the user sees what was read.
  static std::string describe(const YAML::Node& node) {
    if (node.IsScalar()) return ", got '" + node.Scalar() + "'";
    if (node.IsNull()) return ", got nothing";
    if (node.IsSequence()) return ", got a list";
    if (node.IsMap()) return ", got a map";
    return "";
  }

  // ---------------------------------------------------------------------------------- model

  Model build(const YAML::Node& root) {
    if (root.IsNull()) throw InputError(source_ + ":1: the model file is empty");
    if (!root.IsMap())
      throw InputError(source_ + ":" + std::to_string(lineOf(root)) +
                       ": the model must be a YAML map (frame_id, particles, bond_types, ...)");
    Model model;
    std::map<std::string, Entry> top;
    for (Entry& e : entries(root, "model", "")) {
      static const std::set<std::string> kKnown = {
          "frame_id", "frame_rate_hz", "substeps",     "gravity",       "particles",
          "bond_types", "bonds",       "interactions", "identification"};
      if (!kKnown.count(e.key))
        fail(lineOf(e.key_node), e.key,
             "unknown top-level key (allowed: frame_id, frame_rate_hz, substeps, gravity, "
             "particles, bond_types, bonds, interactions, identification)");
      top.emplace(e.key, std::move(e));
    }
    auto get = [&](const char* key) -> const Entry* {
      auto it = top.find(key);
      return it == top.end() ? nullptr : &it->second;
    };

    if (const Entry* e = get("frame_id")) {
      model.frame_id = asString(*e, "frame_id", "");
      if (model.frame_id.empty()) fail(e->valueLine(), "frame_id", "must not be empty");
    }
    if (const Entry* e = get("frame_rate_hz")) {
      model.frame_rate_hz = asFinite(*e, "frame_rate_hz", "");
      if (model.frame_rate_hz < 0.0)
        fail(e->valueLine(), "frame_rate_hz", "must be >= 0 (0 = take it from the data)");
    }
    if (const Entry* e = get("substeps")) {
      model.substeps = asInt(*e, "substeps", "");
      if (model.substeps < 1) fail(e->valueLine(), "substeps", "must be >= 1");
    }
    if (const Entry* e = get("gravity")) readGravity(*e, model);
    if (const Entry* e = get("particles")) readParticles(*e, model);
    if (const Entry* e = get("bond_types")) readBondTypes(*e, model);
    if (const Entry* e = get("bonds")) readBonds(*e, model);
    if (const Entry* e = get("interactions")) readInteractions(*e, model);
    // `identification` is what an export adds (SPEC section 4); accepting it lets an exported
    // model be used as a model file again. Its content describes a past run, so it is ignored.
    if (const Entry* e = get("identification"))
      if (!e->value.IsMap()) fail(e->valueLine(), "identification", "expected a map");

    // Everything above is checked with line numbers; this is the safety net for rules that
    // only the finished model can check.
    const std::string reason = validateModel(model);
    if (!reason.empty()) throw InputError(source_ + ":" + std::to_string(lineOf(root)) + ": " + reason);
    return model;
  }

  /// A sequence entry (particles, bond_types, ...); an absent/empty value is an empty list.
  const YAML::Node& sequence(const Entry& e) const {
    if (!e.value.IsNull() && !e.value.IsSequence())
      fail(e.valueLine(), e.key, "expected a list");
    return e.value;
  }

  // -------------------------------------------------------------------------------- gravity

  void readGravity(const Entry& e, Model& model) {
    std::array<Param, 3>& g = model.gravity_mps2;
    if (e.value.IsSequence()) {
      const Eigen::Vector3d v = asVector3(e, "gravity", "");
      for (int k = 0; k < 3; ++k) {
        g[k] = Param{};
        g[k].value = v[k];
        g[k].present = g[k].has_value = true;
      }
      return;
    }
    if (!e.value.IsMap())
      fail(e.valueLine(), "gravity",
           "expected [gx, gy, gz] or a block {value: [..], free, min, max}");
    std::array<Param, 3> p{};
    for (Param& c : p) c.present = true;
    for (const Entry& f : entries(e.value, "gravity", "")) {
      const std::string key = "gravity." + f.key;
      if (f.key == "value") {
        const Eigen::Vector3d v = asVector3(f, key, "");
        for (int k = 0; k < 3; ++k) {
          p[k].value = v[k];
          p[k].has_value = true;
        }
      } else if (f.key == "free") {
        // A single flag, or one per axis (e.g. only the vertical component identified).
        if (f.value.IsSequence()) {
          if (f.value.size() != 3) fail(f.valueLine(), key, "expected true/false or a list of 3");
          for (int k = 0; k < 3; ++k)
            p[k].free = asBool(f.value[k], lineOf(f.value[k]), key, "");
        } else {
          const bool b = asBool(f.value, f.valueLine(), key, "");
          for (Param& c : p) c.free = b;
        }
      } else if (f.key == "min" || f.key == "max") {
        const bool is_min = f.key == "min";
        // One bound for every axis, or one per axis; `~` leaves that axis unbounded.
        // (No YAML::Node reassignment here: `node = other` rebinds the shared underlying
        // node in yaml-cpp and would overwrite the document.)
        if (f.value.IsSequence()) {
          if (f.value.size() != 3) fail(f.valueLine(), key, "expected a number or a list of 3");
          for (int k = 0; k < 3; ++k) {
            const YAML::Node item = f.value[k];
            if (item.IsNull()) continue;
            const int line = lineOf(item);
            setBound(p[k], is_min, asNumber(item, line, key, ""), line, key, "");
          }
        } else {
          const double v = asNumber(f.value, f.valueLine(), key, "");
          for (int k = 0; k < 3; ++k) setBound(p[k], is_min, v, f.valueLine(), key, "");
        }
      } else if (f.key == "std") {
        // Written by exports; a past run's uncertainty, not an input.
      } else {
        fail(lineOf(f.key_node), key,
             "unknown key in the gravity block (allowed: value, free, min, max, std)");
      }
    }
    for (int k = 0; k < 3; ++k) {
      if (!p[k].free && !p[k].has_value)
        fail(e.valueLine(), "gravity.value",
             std::string("fixed gravity component ") + kAxisName[k] + " needs a value");
      if (p[k].has_min && p[k].has_max && p[k].min > p[k].max)
        fail(e.valueLine(), "gravity", std::string("min > max for component ") + kAxisName[k]);
    }
    g = p;
  }

  /// Stores a bound; -inf as min / +inf as max are "no bound" (how exports omit them).
  void setBound(Param& p, bool is_min, double v, int line, const std::string& key,
                const std::string& where) const {
    if (is_min) {
      if (v == -kInf) return;
      if (!std::isfinite(v)) fail(line, key, "min must be finite or -.inf" + where);
      p.min = v;
      p.has_min = true;
    } else {
      if (v == kInf) return;
      if (!std::isfinite(v)) fail(line, key, "max must be finite or .inf" + where);
      p.max = v;
      p.has_max = true;
    }
  }

  // ------------------------------------------------------------------------------ particles

  void readParticles(const Entry& list, Model& model) {
    const YAML::Node& seq = sequence(list);
    std::map<std::string, int> name_line;
    for (std::size_t i = 0; i < seq.size(); ++i) {
      const YAML::Node item = seq[i];
      std::string where = " in particles[" + std::to_string(i) + "]";
      if (!item.IsMap())
        fail(lineOf(item), "particles",
             "each particle must be a map {name, mass, position, ...}" + where);
      const std::vector<Entry> es = entries(item, "particles", where);
      Particle p;
      // The name first, so that later messages can name the particle.
      bool named = false;
      for (const Entry& e : es) {
        if (e.key != "name") continue;
        p.name = asString(e, "name", where);
        if (p.name.empty()) fail(e.valueLine(), "name", "must not be empty" + where);
        auto [pos, inserted] = name_line.emplace(p.name, e.valueLine());
        if (!inserted)
          fail(e.valueLine(), "name",
               "duplicate particle name '" + p.name + "' (first at line " +
                   std::to_string(pos->second) + ")" + where);
        where = " in particle '" + p.name + "'";
        named = true;
      }
      if (!named) fail(lineOf(item), "name", "particle has no name" + where);
      for (const Entry& e : es) {
        if (e.key == "name") {
        } else if (e.key == "mass") {
          p.mass_kg = asFinite(e, "mass", where);
          if (!(p.mass_kg > 0.0))
            fail(e.valueLine(), "mass", "mass must be > 0, got " + e.value.Scalar() + where);
        } else if (e.key == "position") {
          p.position_m = asVector3(e, "position", where);
        } else if (e.key == "velocity") {
          p.velocity_mps = asVector3(e, "velocity", where);
        } else if (e.key == "fixed") {
          p.fixed = asBool(e.value, e.valueLine(), "fixed", where);
        } else if (e.key == "group") {
          p.group = asString(e, "group", where);
        } else {
          fail(lineOf(e.key_node), e.key,
               "unknown key" + where + " (allowed: name, mass, position, velocity, fixed, group)");
        }
      }
      model.particles.push_back(std::move(p));
    }
  }

  // ----------------------------------------------------------------------------- bond types

  void readBondTypes(const Entry& list, Model& model) {
    const YAML::Node& seq = sequence(list);
    std::map<std::string, int> name_line;
    for (std::size_t i = 0; i < seq.size(); ++i) {
      const YAML::Node item = seq[i];
      std::string where = " in bond_types[" + std::to_string(i) + "]";
      if (!item.IsMap())
        fail(lineOf(item), "bond_types", "each bond type must be a map {name, kind, ...}" + where);
      const std::vector<Entry> es = entries(item, "bond_types", where);
      BondType type;
      const Entry* name = nullptr;
      const Entry* kind = nullptr;
      for (const Entry& e : es) {
        if (e.key == "name") name = &e;
        if (e.key == "kind") kind = &e;
      }
      if (!name) fail(lineOf(item), "name", "bond type has no name" + where);
      type.name = asString(*name, "name", where);
      if (type.name.empty()) fail(name->valueLine(), "name", "must not be empty" + where);
      // '/' separates type and parameter in parameter names ("s01/stiffness").
      if (type.name.find('/') != std::string::npos)
        fail(name->valueLine(), "name",
             "bond type names may not contain '/' (it separates type and parameter in "
             "parameter names)" + where);
      auto [pos, inserted] = name_line.emplace(type.name, name->valueLine());
      if (!inserted)
        fail(name->valueLine(), "name",
             "duplicate bond type name '" + type.name + "' (first at line " +
                 std::to_string(pos->second) + ")" + where);
      where = " in bond type '" + type.name + "'";

      if (!kind)
        fail(lineOf(item), "kind", "bond type has no kind (" + bondKindNameList() + ")" + where);
      const std::string k = asString(*kind, "kind", where);
      const BondKindInfo* info = bondKindByName(k);
      if (!info)
        fail(kind->valueLine(), "kind",
             "unknown kind '" + k + "' (expected " + bondKindNameList() + ")" + where);
      type.kind = info->kind;

      // A muscle's network layout first: it decides which parameter keys exist.
      if (info->network) {
        for (const Entry& e : es) {
          if (e.key == "inputs") type.network_inputs = asCount(e, kMaxMuscleInputs, where);
          if (e.key == "hidden") type.network_hidden = asCount(e, kMaxMuscleHidden, where);
        }
        type.network.assign(muscleNetworkSize(type.network_inputs, type.network_hidden), Param());
      }
      const std::vector<ParamId>& allowed = info->params;
      for (const Entry& e : es) {
        if (e.key == "name" || e.key == "kind") continue;
        if (info->network && (e.key == "inputs" || e.key == "hidden")) continue;
        bool found = false;
        for (ParamId id : allowed) {
          if (e.key != paramKey(id)) continue;
          type.params[id] = readParam(e, where);
          found = true;
        }
        if (!found && info->network) {
          const int index = muscleNetworkIndex(type.network_inputs, type.network_hidden, e.key);
          if (index >= 0) {
            type.network[index] = readParam(e, where);
            found = true;
          }
        }
        if (!found) {
          std::string list_of;
          for (ParamId id : allowed) list_of += std::string(list_of.empty() ? "" : ", ") + paramKey(id);
          if (info->network)
            list_of += ", inputs, hidden, and the network's " +
                       muscleNetworkLayout(type.network_inputs, type.network_hidden) +
                       " (inputs " + std::to_string(type.network_inputs) + ", hidden " +
                       std::to_string(type.network_hidden) + ")";
          fail(lineOf(e.key_node), e.key,
               std::string("unknown key for a ") + info->name + where + " (allowed: name, kind, " +
                   list_of + ")");
        }
      }
      model.bond_types.push_back(std::move(type));
    }
  }

  /// A non-negative integer no larger than `max` (a muscle's inputs and hidden units).
  int asCount(const Entry& e, int max, const std::string& where) const {
    const int v = asInt(e, e.key, where);
    if (v < 0 || v > max)
      fail(e.valueLine(), e.key, "must be in [0, " + std::to_string(max) + "]" + where);
    return v;
  }

  /// A parameter: a plain number (present, fixed) or a block {value, free, min, max, std}.
  Param readParam(const Entry& e, const std::string& where) const {
    Param p;
    p.present = true;
    if (!e.value.IsMap()) {
      if (!e.value.IsScalar())
        fail(e.valueLine(), e.key, "expected a number or a block {value, free, min, max}" + where);
      p.value = asFinite(e, e.key, where);
      p.has_value = true;
      return p;
    }
    for (const Entry& f : entries(e.value, e.key, where)) {
      const std::string key = e.key + "." + f.key;
      if (f.key == "value") {
        p.value = asFinite(f, key, where);
        p.has_value = true;
      } else if (f.key == "free") {
        p.free = asBool(f.value, f.valueLine(), key, where);
      } else if (f.key == "min" || f.key == "max") {
        setBound(p, f.key == "min", asNumber(f, key, where), f.valueLine(), key, where);
      } else if (f.key == "std") {
        // Written by exports; a past run's uncertainty, not an input.
      } else {
        fail(lineOf(f.key_node), key,
             "unknown key in a parameter block" + where + " (allowed: value, free, min, max, std)");
      }
    }
    if (!p.free && !p.has_value)
      fail(e.valueLine(), e.key, "a fixed parameter needs a value (or set free: true)" + where);
    if (p.has_min && p.has_max && p.min > p.max) {
      std::ostringstream os;
      os << "min (" << p.min << ") > max (" << p.max << ")" << where;
      fail(e.valueLine(), e.key, os.str());
    }
    return p;
  }

  // ---------------------------------------------------------------------------------- bonds

  void readBonds(const Entry& list, Model& model) {
    const YAML::Node& seq = sequence(list);
    // Muscle inputs name bonds that may come later in the list: resolved after all are read.
    struct PendingInputs {
      std::size_t bond;
      const Entry* entry;
      std::string where;
    };
    std::vector<std::vector<Entry>> all_entries(seq.size());
    std::vector<PendingInputs> pending;
    std::map<std::string, int> name_line;
    for (std::size_t i = 0; i < seq.size(); ++i) {
      const YAML::Node item = seq[i];
      const std::string where = " in bonds[" + std::to_string(i) + "]";
      if (!item.IsMap())
        fail(lineOf(item), "bonds", "each bond must be a map {type, particles}" + where);
      const Entry* type_e = nullptr;
      const Entry* parts_e = nullptr;
      const Entry* name_e = nullptr;
      const Entry* inputs_e = nullptr;
      all_entries[i] = entries(item, "bonds", where);
      const std::vector<Entry>& es = all_entries[i];
      for (const Entry& e : es) {
        if (e.key == "type") {
          type_e = &e;
        } else if (e.key == "particles") {
          parts_e = &e;
        } else if (e.key == "name") {
          name_e = &e;
        } else if (e.key == "inputs") {
          inputs_e = &e;
        } else {
          fail(lineOf(e.key_node), e.key,
               "unknown key" + where + " (allowed: type, particles, name, inputs)");
        }
      }
      if (!type_e) fail(lineOf(item), "type", "bond type missing" + where);
      Bond bond;
      const std::string type_name = asString(*type_e, "type", where);
      bond.type = model.bondTypeIndex(type_name);
      if (bond.type < 0)
        fail(type_e->valueLine(), "type", "unknown bond type '" + type_name + "'" + where);
      const BondType& type = model.bond_types[bond.type];
      if (!parts_e) fail(lineOf(item), "particles", "bond particles missing" + where);
      const YAML::Node& names = parts_e->value;
      const int arity = kindArity(type.kind);
      if (!names.IsSequence())
        fail(parts_e->valueLine(), "particles", "expected a list of particle names" + where);
      if (static_cast<int>(names.size()) != arity)
        fail(parts_e->valueLine(), "particles",
             std::string("a ") + kindName(type.kind) + " bond (type '" + type.name + "') joins " +
                 std::to_string(arity) + " particle" + (arity == 1 ? "" : "s") + ", got " +
                 std::to_string(names.size()) + where);
      for (int k = 0; k < arity; ++k) {
        const YAML::Node n = names[k];
        if (!n.IsScalar()) fail(lineOf(n), "particles", "expected a particle name" + where);
        const int idx = model.particleIndex(n.Scalar());
        if (idx < 0) fail(lineOf(n), "particles", "unknown particle '" + n.Scalar() + "'" + where);
        for (int l = 0; l < k; ++l)
          if (bond.particles[l] == idx)
            fail(lineOf(n), "particles",
                 "bond joins particle '" + n.Scalar() + "' to itself" + where);
        bond.particles[k] = idx;
      }
      if (name_e) {
        bond.name = asString(*name_e, "name", where);
        if (bond.name.empty()) fail(name_e->valueLine(), "name", "must not be empty" + where);
        auto [pos, inserted] = name_line.emplace(bond.name, name_e->valueLine());
        if (!inserted)
          fail(name_e->valueLine(), "name",
               "duplicate bond name '" + bond.name + "' (first at line " +
                   std::to_string(pos->second) + ")" + where);
      }
      if (bondKindInfo(type.kind).network) {
        if (inputs_e)
          pending.push_back({model.bonds.size(), inputs_e, where});
        else if (type.network_inputs > 0)  // a muscle reading nothing may leave the key out
          fail(lineOf(item), "inputs",
               "a muscle bond (type '" + type.name + "') names its " +
                   std::to_string(type.network_inputs) + " input bond(s): inputs: [bond names]" +
                   where);
      } else if (inputs_e) {
        fail(lineOf(inputs_e->key_node), "inputs",
             std::string("only muscle bonds have inputs (type '") + type.name + "' is a " +
                 kindName(type.kind) + ")" + where);
      }
      model.bonds.push_back(bond);
    }
    for (const PendingInputs& p : pending) {
      Bond& bond = model.bonds[p.bond];
      const BondType& type = model.bond_types[bond.type];
      const YAML::Node& names = p.entry->value;
      if (!names.IsSequence())
        fail(p.entry->valueLine(), "inputs", "expected a list of bond names" + p.where);
      if (static_cast<int>(names.size()) != type.network_inputs)
        fail(p.entry->valueLine(), "inputs",
             "muscle type '" + type.name + "' reads " + std::to_string(type.network_inputs) +
                 " input bond(s), got " + std::to_string(names.size()) + p.where);
      for (std::size_t k = 0; k < names.size(); ++k) {
        const YAML::Node n = names[k];
        if (!n.IsScalar()) fail(lineOf(n), "inputs", "expected a bond name" + p.where);
        const int idx = model.bondIndex(n.Scalar());
        if (idx < 0)
          fail(lineOf(n), "inputs",
               "unknown input bond '" + n.Scalar() + "' (no bond has that name)" + p.where);
        if (idx == static_cast<int>(p.bond))
          fail(lineOf(n), "inputs", "a muscle cannot read its own bond" + p.where);
        const BondType& in_type = model.bond_types[model.bonds[idx].type];
        if (!bondKindInfo(in_type.kind).has_elongation)
          fail(lineOf(n), "inputs",
               "input bond '" + n.Scalar() + "' is a " + kindName(in_type.kind) +
                   " (inputs must be springs or muscles: bonds with an elongation)" + p.where);
        bond.inputs.push_back(idx);
      }
    }
  }

  // --------------------------------------------------------------------------- interactions

  void readInteractions(const Entry& list, Model& model) {
    const YAML::Node& seq = sequence(list);
    std::set<std::string> groups;
    for (const Particle& p : model.particles) groups.insert(p.group);
    for (std::size_t i = 0; i < seq.size(); ++i) {
      const YAML::Node item = seq[i];
      const std::string where = " in interactions[" + std::to_string(i) + "]";
      if (!item.IsMap())
        fail(lineOf(item), "interactions", "each interaction must be a map {type, groups}" + where);
      const Entry* type_e = nullptr;
      const Entry* groups_e = nullptr;
      const std::vector<Entry> es = entries(item, "interactions", where);
      for (const Entry& e : es) {
        if (e.key == "type") {
          type_e = &e;
        } else if (e.key == "groups") {
          groups_e = &e;
        } else {
          fail(lineOf(e.key_node), e.key, "unknown key" + where + " (allowed: type, groups)");
        }
      }
      if (!type_e) fail(lineOf(item), "type", "interaction type missing" + where);
      Interaction in;
      const std::string type_name = asString(*type_e, "type", where);
      in.type = model.bondTypeIndex(type_name);
      if (in.type < 0)
        fail(type_e->valueLine(), "type", "unknown bond type '" + type_name + "'" + where);
      const BondType& type = model.bond_types[in.type];
      // Interactions are installed between nearby particles, so they need a spring with a
      // range; without max_distance every pair in the groups would be bonded.
      if (!bondKindInfo(type.kind).interactions || !type.param(kMaxDistance).present)
        fail(type_e->valueLine(), "type",
             "interaction type '" + type.name + "' must be a spring with max_distance" + where);
      if (!groups_e) fail(lineOf(item), "groups", "interaction groups missing" + where);
      const YAML::Node& g = groups_e->value;
      if (!g.IsSequence() || g.size() != 2)
        fail(groups_e->valueLine(), "groups", "expected two group names [a, b]" + where);
      for (int k = 0; k < 2; ++k) {
        if (!g[k].IsScalar()) fail(lineOf(g[k]), "groups", "expected a group name" + where);
        const std::string name = g[k].Scalar();
        if (!groups.count(name))
          fail(lineOf(g[k]), "groups", "no particle is in group '" + name + "'" + where);
        (k == 0 ? in.group_a : in.group_b) = name;
      }
      model.interactions.push_back(std::move(in));
    }
  }
};

// ------------------------------------------------------------------------------------------
// Writing
// ------------------------------------------------------------------------------------------

/// Shortest decimal text that reads back to the same double (std::to_chars guarantees the
/// round trip and is locale-independent, unlike printf/iostreams under a German locale).
std::string formatNumber(double v) {
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, res.ptr);
}

/// Emits a number as a plain scalar (the emitter writes such strings unquoted).
void emitNumber(YAML::Emitter& out, double v) { out << formatNumber(v); }

/// True when `s` written as a plain scalar reads back as the same string. Not so for control
/// characters (a lone carriage return, found by fuzz_model_yaml, read back as a line break),
/// leading or trailing blanks, and other text the emitter passes through unquoted.
/// Tried where names appear: a block map's value and a flow sequence's item (a lone "\r" reads
/// back fine as a whole document, not as a map value).
bool plainRoundTrips(const std::string& s) {
  YAML::Emitter probe;
  probe << YAML::BeginMap << YAML::Key << "block" << YAML::Value << s << YAML::Key << "flow"
        << YAML::Value << YAML::Flow << YAML::BeginSeq << s << s << YAML::EndSeq << YAML::EndMap;
  if (!probe.good()) return false;
  try {
    const YAML::Node back = YAML::Load(probe.c_str());
    const YAML::Node block = back["block"], flow = back["flow"];
    return block.IsScalar() && block.Scalar() == s && flow.IsSequence() && flow.size() == 2 &&
           flow[0].IsScalar() && flow[0].Scalar() == s && flow[1].IsScalar() && flow[1].Scalar() == s;
  } catch (const YAML::Exception&) {
    return false;
  }
}

/// Names are written plain unless a YAML reader would take them for something other than a
/// string (true, null, 12, ...): quoting keeps the file readable by other tools as well.
void emitName(YAML::Emitter& out, const std::string& s) {
  static const std::set<std::string> kSpecial = {
      "true", "false", "yes", "no", "on", "off", "y", "n", "null", "~", ""};
  std::string lower;
  for (char c : s) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  double d = 0.0;
  const bool numeric = !s.empty() && YAML::convert<double>::decode(YAML::Node(s), d);
  if (kSpecial.count(lower) || numeric || !plainRoundTrips(s))
    out << YAML::DoubleQuoted << s;
  else
    out << s;
}

void emitParam(YAML::Emitter& out, const Param& p, const double* std_dev) {
  const bool min_b = p.has_min && std::isfinite(p.min);
  const bool max_b = p.has_max && std::isfinite(p.max);
  if (!p.free && !min_b && !max_b && p.has_value && !std_dev) {
    emitNumber(out, p.value);
    return;
  }
  out << YAML::Flow << YAML::BeginMap;
  if (p.has_value) {
    out << YAML::Key << "value" << YAML::Value;
    emitNumber(out, p.value);
  }
  out << YAML::Key << "free" << YAML::Value << p.free;
  // Infinite bounds mean "unbounded" and are simply left out.
  if (min_b) {
    out << YAML::Key << "min" << YAML::Value;
    emitNumber(out, p.min);
  }
  if (max_b) {
    out << YAML::Key << "max" << YAML::Value;
    emitNumber(out, p.max);
  }
  if (std_dev) {
    out << YAML::Key << "std" << YAML::Value;
    emitNumber(out, *std_dev);
  }
  out << YAML::EndMap;
}

void emitVector(YAML::Emitter& out, const Eigen::Vector3d& v) {
  out << YAML::Flow << YAML::BeginSeq;
  for (int k = 0; k < 3; ++k) emitNumber(out, v[k]);
  out << YAML::EndSeq;
}

/// Gravity as [gx, gy, gz] when all three are plain fixed values, otherwise as a block.
/// Per-axis differences (free flags, bounds, std) are written as 3-lists with `~` for "none".
void emitGravity(YAML::Emitter& out, const std::array<Param, 3>& g,
                 const std::map<std::string, double>& stds) {
  std::array<const double*, 3> sd{};
  bool any_std = false;
  for (int k = 0; k < 3; ++k) {
    auto it = stds.find(std::string("gravity/") + kAxisName[k]);
    if (it != stds.end()) {
      sd[k] = &it->second;
      any_std = true;
    }
  }
  bool simple = !any_std;
  for (const Param& p : g)
    if (p.free || (p.has_min && std::isfinite(p.min)) || (p.has_max && std::isfinite(p.max)) ||
        !p.has_value)
      simple = false;
  if (simple) {
    emitVector(out, Eigen::Vector3d(g[0].value, g[1].value, g[2].value));
    return;
  }
  out << YAML::Flow << YAML::BeginMap;
  if (g[0].has_value || g[1].has_value || g[2].has_value) {
    out << YAML::Key << "value" << YAML::Value;
    emitVector(out, Eigen::Vector3d(g[0].value, g[1].value, g[2].value));
  }
  out << YAML::Key << "free" << YAML::Value;
  if (g[0].free == g[1].free && g[1].free == g[2].free) {
    out << g[0].free;
  } else {
    out << YAML::Flow << YAML::BeginSeq << g[0].free << g[1].free << g[2].free << YAML::EndSeq;
  }
  // One key per bound: a single number when all axes agree, else a 3-list (~ = unbounded).
  auto bound = [&](const char* key, bool is_min) {
    std::array<const double*, 3> b{};
    for (int k = 0; k < 3; ++k) {
      const Param& p = g[k];
      const bool has = is_min ? p.has_min : p.has_max;
      const double& v = is_min ? p.min : p.max;
      if (has && std::isfinite(v)) b[k] = &v;
    }
    if (!b[0] && !b[1] && !b[2]) return;
    out << YAML::Key << key << YAML::Value;
    if (b[0] && b[1] && b[2] && *b[0] == *b[1] && *b[1] == *b[2] &&
        std::signbit(*b[0]) == std::signbit(*b[1]) && std::signbit(*b[1]) == std::signbit(*b[2])) {
      emitNumber(out, *b[0]);
      return;
    }
    out << YAML::Flow << YAML::BeginSeq;
    for (int k = 0; k < 3; ++k) {
      if (b[k])
        emitNumber(out, *b[k]);
      else
        out << YAML::Null;
    }
    out << YAML::EndSeq;
  };
  bound("min", true);
  bound("max", false);
  if (any_std) {
    out << YAML::Key << "std" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (int k = 0; k < 3; ++k) {
      if (sd[k])
        emitNumber(out, *sd[k]);
      else
        out << YAML::Null;
    }
    out << YAML::EndSeq;
  }
  out << YAML::EndMap;
}

/// Closes `fd` and removes `tmp` after a failure, then throws with the saved errno.
[[noreturn]] void failWrite(const std::string& path, const std::string& tmp, int fd, int err) {
  if (fd >= 0) ::close(fd);
  if (!tmp.empty()) ::unlink(tmp.c_str());
  throw InputError(path + ": cannot write: " + std::strerror(err));
}

}  // namespace

Model loadModelString(const std::string& yaml, const std::string& source_name) {
  return Loader(source_name).load(yaml);
}

Model loadModelFile(const std::string& path) {
  // POSIX read rather than ifstream: it reports a directory or a permission problem as an
  // error (with errno) instead of an empty read.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw InputError(path + ": cannot read file (" + std::strerror(errno) + ")");
  std::string text;
  char buf[65536];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n == 0) break;
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      ::close(fd);
      throw InputError(path + ": cannot read file (" + std::strerror(err) + ")");
    }
    text.append(buf, static_cast<std::size_t>(n));
  }
  ::close(fd);
  return loadModelString(text, path);
}

std::string modelToYaml(const Model& model, const IdentificationInfo* info) {
  // Writing an inconsistent model would produce a file that cannot be loaded back, and bad
  // indices would be read out of range below.
  const std::string reason = validateModel(model);
  if (!reason.empty()) throw InputError("cannot export an invalid model: " + reason);

  std::map<std::string, double> stds;
  if (info) {
    const std::size_t n = std::min(info->std_names.size(), info->std_values.size());
    for (std::size_t i = 0; i < n; ++i)
      if (std::isfinite(info->std_values[i])) stds[info->std_names[i]] = info->std_values[i];
  }
  auto stdOf = [&](const std::string& name) -> const double* {
    auto it = stds.find(name);
    return it == stds.end() ? nullptr : &it->second;
  };

  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "frame_id" << YAML::Value;
  emitName(out, model.frame_id);
  out << YAML::Key << "frame_rate_hz" << YAML::Value;
  emitNumber(out, model.frame_rate_hz);
  out << YAML::Key << "substeps" << YAML::Value << model.substeps;
  const auto& g = model.gravity_mps2;
  if (g[0].present || g[1].present || g[2].present) {
    out << YAML::Key << "gravity" << YAML::Value;
    emitGravity(out, g, stds);
  }

  // Empty lists are written as [] on the key's line (block style would put it on the next).
  auto beginList = [&](const char* key, bool empty) {
    out << YAML::Key << key << YAML::Value;
    if (empty) out << YAML::Flow;
    out << YAML::BeginSeq;
  };

  beginList("particles", model.particles.empty());
  for (const Particle& p : model.particles) {
    out << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "name" << YAML::Value;
    emitName(out, p.name);
    out << YAML::Key << "mass" << YAML::Value;
    emitNumber(out, p.mass_kg);
    out << YAML::Key << "position" << YAML::Value;
    emitVector(out, p.position_m);
    out << YAML::Key << "velocity" << YAML::Value;
    emitVector(out, p.velocity_mps);
    out << YAML::Key << "fixed" << YAML::Value << p.fixed;
    out << YAML::Key << "group" << YAML::Value;
    emitName(out, p.group);
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;

  beginList("bond_types", model.bond_types.empty());
  for (const BondType& t : model.bond_types) {
    out << YAML::BeginMap;
    out << YAML::Key << "name" << YAML::Value;
    emitName(out, t.name);
    out << YAML::Key << "kind" << YAML::Value << kindName(t.kind);
    for (ParamId id : paramsOfKind(t.kind)) {
      const Param& p = t.params[id];
      if (!p.present) continue;
      out << YAML::Key << paramKey(id) << YAML::Value;
      emitParam(out, p, stdOf(t.name + "/" + paramKey(id)));
    }
    if (bondKindInfo(t.kind).network) {
      out << YAML::Key << "inputs" << YAML::Value << t.network_inputs;
      out << YAML::Key << "hidden" << YAML::Value << t.network_hidden;
      for (std::size_t k = 0; k < t.network.size(); ++k) {
        const Param& p = t.network[k];
        if (!p.present) continue;
        const std::string key =
            muscleNetworkKey(t.network_inputs, t.network_hidden, static_cast<int>(k));
        out << YAML::Key << key << YAML::Value;
        emitParam(out, p, stdOf(t.name + "/" + key));
      }
    }
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;

  beginList("bonds", model.bonds.empty());
  for (const Bond& b : model.bonds) {
    const BondType& t = model.bond_types[b.type];
    out << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "type" << YAML::Value;
    emitName(out, t.name);
    out << YAML::Key << "particles" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (int k = 0; k < kindArity(t.kind); ++k) emitName(out, model.particles[b.particles[k]].name);
    out << YAML::EndSeq;
    if (!b.name.empty()) {
      out << YAML::Key << "name" << YAML::Value;
      emitName(out, b.name);
    }
    if (bondKindInfo(t.kind).network) {
      out << YAML::Key << "inputs" << YAML::Value << YAML::Flow << YAML::BeginSeq;
      for (int in : b.inputs) emitName(out, model.bonds[in].name);
      out << YAML::EndSeq;
    }
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;

  beginList("interactions", model.interactions.empty());
  for (const Interaction& in : model.interactions) {
    out << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "type" << YAML::Value;
    emitName(out, model.bond_types[in.type].name);
    out << YAML::Key << "groups" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    emitName(out, in.group_a);
    emitName(out, in.group_b);
    out << YAML::EndSeq << YAML::EndMap;
  }
  out << YAML::EndSeq;

  if (info) {
    out << YAML::Key << "identification" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "method" << YAML::Value;
    emitName(out, info->method);
    out << YAML::Key << "global_cost" << YAML::Value;
    emitNumber(out, info->global_cost);
    out << YAML::Key << "frames" << YAML::Value << info->frames;
    out << YAML::Key << "generations" << YAML::Value << info->generations;
    out << YAML::Key << "wall_time_s" << YAML::Value;
    emitNumber(out, info->wall_time_s);
    if (!info->flags.empty()) {
      out << YAML::Key << "flags" << YAML::Value << YAML::BeginMap;
      for (const auto& [name, flag] : info->flags) {
        out << YAML::Key;
        emitName(out, name);
        out << YAML::Value;
        emitName(out, flag);
      }
      out << YAML::EndMap;
    }
    if (!info->notes.empty()) {
      out << YAML::Key << "notes" << YAML::Value << YAML::BeginSeq;
      for (const std::string& text : info->notes) out << YAML::DoubleQuoted << text;
      out << YAML::EndSeq;
    }
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  if (!out.good()) throw InputError("cannot export the model: " + out.GetLastError());
  return std::string(out.c_str()) + "\n";
}

void writeFileAtomically(const std::string& path, const std::string& content) {
  // The temp file is in the target's directory so that rename() is atomic (same filesystem):
  // a reader sees either the old file or the complete new one, never a partial write.
  std::string tmp = path + ".tmp.XXXXXX";
  std::vector<char> templ(tmp.begin(), tmp.end());
  templ.push_back('\0');
  const int fd = ::mkstemp(templ.data());
  if (fd < 0) failWrite(path, "", -1, errno);
  tmp = templ.data();
  // mkstemp creates 0600; a model file is meant to be shared like any other output.
  if (::fchmod(fd, 0644) != 0) failWrite(path, tmp, fd, errno);
  const char* data = content.data();
  std::size_t left = content.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, data, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      failWrite(path, tmp, fd, errno);
    }
    data += n;
    left -= static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0) failWrite(path, tmp, fd, errno);
  if (::close(fd) != 0) failWrite(path, tmp, -1, errno);
  if (::rename(tmp.c_str(), path.c_str()) != 0) failWrite(path, tmp, -1, errno);
}

void writeModelFile(const std::string& path, const Model& model, const IdentificationInfo* info) {
  writeFileAtomically(path, modelToYaml(model, info));
}

}  // namespace mme
