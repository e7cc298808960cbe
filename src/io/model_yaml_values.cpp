// Checked conversions of YAML nodes for the model reader: names, numbers, flags, counts,
// 3-vectors and parameter blocks. They are the one place where a value's type and range are
// checked, so every section reports a bad value with the same wording and line.

#include "model_yaml_values.h"

#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "motion_model_estimation/core/error.h"

namespace mme {
namespace model_yaml {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
}  // namespace

int lineOf(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  return mark.line >= 0 ? mark.line + 1 : 1;
}

void ValueReader::fail(int line, const std::string& key, const std::string& reason) const {
  throw InputError(source_ + ":" + std::to_string(line) + ": key '" + key + "': " + reason);
}

std::vector<Entry> ValueReader::entries(const YAML::Node& map, const std::string& key,
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

const YAML::Node& ValueReader::sequence(const Entry& e) const {
  if (!e.value.IsNull() && !e.value.IsSequence()) fail(e.valueLine(), e.key, "expected a list");
  return e.value;
}

std::string ValueReader::asString(const Entry& e, const std::string& key,
                                  const std::string& where) const {
  if (!e.value.IsScalar()) fail(e.valueLine(), key, "expected a name" + where);
  return e.value.Scalar();
}

double ValueReader::asNumber(const YAML::Node& node, int line, const std::string& key,
                             const std::string& where) const {
  double v = 0.0;
  if (!node.IsScalar() || !YAML::convert<double>::decode(node, v) || std::isnan(v))
    fail(line, key, "expected a number" + describe(node) + where);
  return v;
}

double ValueReader::asNumber(const Entry& e, const std::string& key,
                             const std::string& where) const {
  return asNumber(e.value, e.valueLine(), key, where);
}

double ValueReader::asFinite(const Entry& e, const std::string& key,
                             const std::string& where) const {
  const double v = asNumber(e, key, where);
  if (!std::isfinite(v)) fail(e.valueLine(), key, "must be finite" + where);
  return v;
}

bool ValueReader::asBool(const YAML::Node& node, int line, const std::string& key,
                         const std::string& where) const {
  bool v = false;
  if (!node.IsScalar() || !YAML::convert<bool>::decode(node, v))
    fail(line, key, "expected true or false" + describe(node) + where);
  return v;
}

int ValueReader::asInt(const Entry& e, const std::string& key, const std::string& where) const {
  int v = 0;
  if (!e.value.IsScalar() || !YAML::convert<int>::decode(e.value, v))
    fail(e.valueLine(), key, "expected an integer" + describe(e.value) + where);
  return v;
}

int ValueReader::asCount(const Entry& e, int max, const std::string& where) const {
  const int v = asInt(e, e.key, where);
  if (v < 0 || v > max)
    fail(e.valueLine(), e.key, "must be in [0, " + std::to_string(max) + "]" + where);
  return v;
}

Eigen::Vector3d ValueReader::asVector3(const Entry& e, const std::string& key,
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

std::string ValueReader::describe(const YAML::Node& node) {
  if (node.IsScalar()) return ", got '" + node.Scalar() + "'";
  if (node.IsNull()) return ", got nothing";
  if (node.IsSequence()) return ", got a list";
  if (node.IsMap()) return ", got a map";
  return "";
}

void ValueReader::setBound(Param& p, bool is_min, double v, int line, const std::string& key,
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

Param ValueReader::readParam(const Entry& e, const std::string& where) const {
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

}  // namespace model_yaml
}  // namespace mme
