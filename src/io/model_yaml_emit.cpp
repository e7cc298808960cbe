// Writing single values of a model as YAML: numbers (shortest text that reads back to the
// same double), names (quoted only when needed), parameters (plain number or a block), vectors
// and gravity (a plain vector, or a block with per-axis flags and bounds). These rules make an
// exported model load back to the same model.

#include "model_yaml_emit.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <set>

namespace mme {
namespace model_yaml {

namespace {

const char* kAxisName[3] = {"x", "y", "z"};

/// Shortest decimal text that reads back to the same double (std::to_chars guarantees the
/// round trip and is locale-independent, unlike printf/iostreams under a German locale).
std::string formatNumber(double v) {
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, res.ptr);
}

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

bool bounded(bool has, double v) { return has && std::isfinite(v); }

/// Gravity's std per axis ("gravity/x", ...; null when it has none).
std::array<const double*, 3> gravityStds(const std::map<std::string, double>& stds) {
  std::array<const double*, 3> sd{};
  for (int k = 0; k < 3; ++k) {
    auto it = stds.find(std::string("gravity/") + kAxisName[k]);
    if (it != stds.end()) sd[k] = &it->second;
  }
  return sd;
}

/// True when gravity can be written as a plain [gx, gy, gz].
bool gravityIsPlain(const std::array<Param, 3>& g, bool any_std) {
  bool simple = !any_std;
  for (const Param& p : g)
    if (p.free || bounded(p.has_min, p.min) || bounded(p.has_max, p.max) || !p.has_value)
      simple = false;
  return simple;
}

/// A 3-list of numbers with `~` for the axes without one.
void emitAxisList(YAML::Emitter& out, const std::array<const double*, 3>& v) {
  out << YAML::Flow << YAML::BeginSeq;
  for (int k = 0; k < 3; ++k) {
    if (v[k])
      emitNumber(out, *v[k]);
    else
      out << YAML::Null;
  }
  out << YAML::EndSeq;
}

/// One key per bound: a single number when all axes agree, else a 3-list (~ = unbounded).
void emitGravityBound(YAML::Emitter& out, const std::array<Param, 3>& g, const char* key,
                      bool is_min) {
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
  emitAxisList(out, b);
}

}  // namespace

void emitNumber(YAML::Emitter& out, double v) { out << formatNumber(v); }

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
  const bool min_b = bounded(p.has_min, p.min);
  const bool max_b = bounded(p.has_max, p.max);
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

/// Per-axis differences (free flags, bounds, std) are written as 3-lists with `~` for "none".
void emitGravity(YAML::Emitter& out, const std::array<Param, 3>& g,
                 const std::map<std::string, double>& stds) {
  const std::array<const double*, 3> sd = gravityStds(stds);
  const bool any_std = sd[0] || sd[1] || sd[2];
  if (gravityIsPlain(g, any_std)) {
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
  emitGravityBound(out, g, "min", true);
  emitGravityBound(out, g, "max", false);
  if (any_std) {
    out << YAML::Key << "std" << YAML::Value;
    emitAxisList(out, sd);
  }
  out << YAML::EndMap;
}

}  // namespace model_yaml
}  // namespace mme
