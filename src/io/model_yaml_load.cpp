// Loading a model document: parsing the YAML text, the top-level keys and gravity, and handing
// each list to its section reader (particles, bond types, bonds, interactions). Together with
// the section readers this implements loadModelString; loadModelFile (model_file.cpp) reads
// the file and comes here.
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

#include <array>
#include <map>
#include <set>

#include "model_yaml_values.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/io/model_yaml.h"

namespace mme {

namespace model_yaml {

namespace {

const char* kAxisName[3] = {"x", "y", "z"};

using TopLevel = std::map<std::string, Entry>;

/// The document's top-level entries by key; unknown keys are an error.
TopLevel topLevelEntries(const ValueReader& r, const YAML::Node& root) {
  TopLevel top;
  for (Entry& e : r.entries(root, "model", "")) {
    static const std::set<std::string> kKnown = {
        "frame_id", "frame_rate_hz", "substeps",     "gravity",       "particles",
        "bond_types", "bonds",       "interactions", "identification"};
    if (!kKnown.count(e.key))
      r.fail(lineOf(e.key_node), e.key,
             "unknown top-level key (allowed: frame_id, frame_rate_hz, substeps, gravity, "
             "particles, bond_types, bonds, interactions, identification)");
    top.emplace(e.key, std::move(e));
  }
  return top;
}

const Entry* find(const TopLevel& top, const char* key) {
  auto it = top.find(key);
  return it == top.end() ? nullptr : &it->second;
}

/// frame_id, frame_rate_hz and substeps.
void readSettings(const ValueReader& r, const TopLevel& top, Model& model) {
  if (const Entry* e = find(top, "frame_id")) {
    model.frame_id = r.asString(*e, "frame_id", "");
    if (model.frame_id.empty()) r.fail(e->valueLine(), "frame_id", "must not be empty");
  }
  if (const Entry* e = find(top, "frame_rate_hz")) {
    model.frame_rate_hz = r.asFinite(*e, "frame_rate_hz", "");
    if (model.frame_rate_hz < 0.0)
      r.fail(e->valueLine(), "frame_rate_hz", "must be >= 0 (0 = take it from the data)");
  }
  if (const Entry* e = find(top, "substeps")) {
    model.substeps = r.asInt(*e, "substeps", "");
    if (model.substeps < 1) r.fail(e->valueLine(), "substeps", "must be >= 1");
  }
}

Model build(const ValueReader& r, const YAML::Node& root) {
  const std::string& source = r.source();
  if (root.IsNull()) throw InputError(source + ":1: the model file is empty");
  if (!root.IsMap())
    throw InputError(source + ":" + std::to_string(lineOf(root)) +
                     ": the model must be a YAML map (frame_id, particles, bond_types, ...)");
  Model model;
  const TopLevel top = topLevelEntries(r, root);
  readSettings(r, top, model);
  if (const Entry* e = find(top, "gravity")) readGravity(r, *e, model);
  if (const Entry* e = find(top, "particles")) readParticles(r, *e, model);
  if (const Entry* e = find(top, "bond_types")) readBondTypes(r, *e, model);
  if (const Entry* e = find(top, "bonds")) readBonds(r, *e, model);
  if (const Entry* e = find(top, "interactions")) readInteractions(r, *e, model);
  // `identification` is what an export adds (SPEC section 4); accepting it lets an exported
  // model be used as a model file again. Its content describes a past run, so it is ignored.
  if (const Entry* e = find(top, "identification"))
    if (!e->value.IsMap()) r.fail(e->valueLine(), "identification", "expected a map");

  // Everything above is checked with line numbers; this is the safety net for rules that
  // only the finished model can check.
  const std::string reason = validateModel(model);
  if (!reason.empty())
    throw InputError(source + ":" + std::to_string(lineOf(root)) + ": " + reason);
  return model;
}

/// Line of a yaml-cpp exception's mark, 1-based (line 1 when it has none).
int exceptionLine(const YAML::Exception& e) { return e.mark.line >= 0 ? e.mark.line + 1 : 1; }

// ------------------------------------------------------------------------------------------
// Gravity
// ------------------------------------------------------------------------------------------

/// `free:` of the gravity block: a single flag, or one per axis (e.g. only the vertical
/// component identified).
void readGravityFree(const ValueReader& r, const Entry& f, const std::string& key,
                     std::array<Param, 3>& p) {
  if (f.value.IsSequence()) {
    if (f.value.size() != 3) r.fail(f.valueLine(), key, "expected true/false or a list of 3");
    for (int k = 0; k < 3; ++k) p[k].free = r.asBool(f.value[k], lineOf(f.value[k]), key, "");
  } else {
    const bool b = r.asBool(f.value, f.valueLine(), key, "");
    for (Param& c : p) c.free = b;
  }
}

/// `min:` or `max:` of the gravity block: one bound for every axis, or one per axis; `~`
/// leaves that axis unbounded.
void readGravityBound(const ValueReader& r, const Entry& f, const std::string& key,
                      std::array<Param, 3>& p) {
  const bool is_min = f.key == "min";
  // (No YAML::Node reassignment here: `node = other` rebinds the shared underlying node in
  // yaml-cpp and would overwrite the document.)
  if (f.value.IsSequence()) {
    if (f.value.size() != 3) r.fail(f.valueLine(), key, "expected a number or a list of 3");
    for (int k = 0; k < 3; ++k) {
      const YAML::Node item = f.value[k];
      if (item.IsNull()) continue;
      const int line = lineOf(item);
      r.setBound(p[k], is_min, r.asNumber(item, line, key, ""), line, key, "");
    }
  } else {
    const double v = r.asNumber(f.value, f.valueLine(), key, "");
    for (int k = 0; k < 3; ++k) r.setBound(p[k], is_min, v, f.valueLine(), key, "");
  }
}

/// The gravity block {value: [..], free, min, max, std}, checked per axis.
std::array<Param, 3> readGravityBlock(const ValueReader& r, const Entry& e) {
  std::array<Param, 3> p{};
  for (Param& c : p) c.present = true;
  for (const Entry& f : r.entries(e.value, "gravity", "")) {
    const std::string key = "gravity." + f.key;
    if (f.key == "value") {
      const Eigen::Vector3d v = r.asVector3(f, key, "");
      for (int k = 0; k < 3; ++k) {
        p[k].value = v[k];
        p[k].has_value = true;
      }
    } else if (f.key == "free") {
      readGravityFree(r, f, key, p);
    } else if (f.key == "min" || f.key == "max") {
      readGravityBound(r, f, key, p);
    } else if (f.key == "std") {
      // Written by exports; a past run's uncertainty, not an input.
    } else {
      r.fail(lineOf(f.key_node), key,
             "unknown key in the gravity block (allowed: value, free, min, max, std)");
    }
  }
  for (int k = 0; k < 3; ++k) {
    if (!p[k].free && !p[k].has_value)
      r.fail(e.valueLine(), "gravity.value",
             std::string("fixed gravity component ") + kAxisName[k] + " needs a value");
    if (p[k].has_min && p[k].has_max && p[k].min > p[k].max)
      r.fail(e.valueLine(), "gravity", std::string("min > max for component ") + kAxisName[k]);
  }
  return p;
}

}  // namespace

void readGravity(const ValueReader& r, const Entry& e, Model& model) {
  std::array<Param, 3>& g = model.gravity_mps2;
  if (e.value.IsSequence()) {
    const Eigen::Vector3d v = r.asVector3(e, "gravity", "");
    for (int k = 0; k < 3; ++k) {
      g[k] = Param{};
      g[k].value = v[k];
      g[k].present = g[k].has_value = true;
    }
    return;
  }
  if (!e.value.IsMap())
    r.fail(e.valueLine(), "gravity",
           "expected [gx, gy, gz] or a block {value: [..], free, min, max}");
  g = readGravityBlock(r, e);
}

}  // namespace model_yaml

Model loadModelString(const std::string& yaml, const std::string& source_name) {
  using model_yaml::exceptionLine;
  YAML::Node root;
  try {
    root = YAML::Load(yaml);
  } catch (const YAML::Exception& e) {
    throw InputError(source_name + ":" + std::to_string(exceptionLine(e)) +
                     ": YAML syntax error: " + e.msg);
  }
  try {
    return model_yaml::build(model_yaml::ValueReader(source_name), root);
  } catch (const InputError&) {
    throw;
  } catch (const YAML::Exception& e) {
    // Safety net: every conversion is checked, but a yaml-cpp exception must still come out
    // as a readable InputError, never as a crash.
    throw InputError(source_name + ":" + std::to_string(exceptionLine(e)) + ": " + e.msg);
  }
}

}  // namespace mme
