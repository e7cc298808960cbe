// The `particles:` list of a model document: name, mass, position, velocity, fixed, group.
// A particle's name is read before its other keys so that every later message can name the
// particle, whatever the key order in the file.

#include <map>

#include "model_yaml_values.h"

namespace mme {
namespace model_yaml {

namespace {

/// The particle's name (required, unique); records it in `name_line` and returns the new
/// `where` (" in particle 'NAME'").
std::string readParticleName(const ValueReader& r, const YAML::Node& item,
                             const std::vector<Entry>& es, const std::string& where,
                             std::map<std::string, int>& name_line, Particle& p) {
  std::string named_where;
  for (const Entry& e : es) {
    if (e.key != "name") continue;
    p.name = r.asString(e, "name", where);
    if (p.name.empty()) r.fail(e.valueLine(), "name", "must not be empty" + where);
    auto [pos, inserted] = name_line.emplace(p.name, e.valueLine());
    if (!inserted)
      r.fail(e.valueLine(), "name",
             "duplicate particle name '" + p.name + "' (first at line " +
                 std::to_string(pos->second) + ")" + where);
    named_where = " in particle '" + p.name + "'";
  }
  if (named_where.empty()) r.fail(lineOf(item), "name", "particle has no name" + where);
  return named_where;
}

/// Every key but the name.
void readParticleKeys(const ValueReader& r, const std::vector<Entry>& es,
                      const std::string& where, Particle& p) {
  for (const Entry& e : es) {
    if (e.key == "name") {
    } else if (e.key == "mass") {
      p.mass_kg = r.asFinite(e, "mass", where);
      if (!(p.mass_kg > 0.0))
        r.fail(e.valueLine(), "mass", "mass must be > 0, got " + e.value.Scalar() + where);
    } else if (e.key == "position") {
      p.position_m = r.asVector3(e, "position", where);
    } else if (e.key == "velocity") {
      p.velocity_mps = r.asVector3(e, "velocity", where);
    } else if (e.key == "fixed") {
      p.fixed = r.asBool(e.value, e.valueLine(), "fixed", where);
    } else if (e.key == "group") {
      p.group = r.asString(e, "group", where);
    } else {
      r.fail(lineOf(e.key_node), e.key,
             "unknown key" + where + " (allowed: name, mass, position, velocity, fixed, group)");
    }
  }
}

}  // namespace

void readParticles(const ValueReader& r, const Entry& list, Model& model) {
  const YAML::Node& seq = r.sequence(list);
  std::map<std::string, int> name_line;
  for (std::size_t i = 0; i < seq.size(); ++i) {
    const YAML::Node item = seq[i];
    const std::string where = " in particles[" + std::to_string(i) + "]";
    if (!item.IsMap())
      r.fail(lineOf(item), "particles",
             "each particle must be a map {name, mass, position, ...}" + where);
    const std::vector<Entry> es = r.entries(item, "particles", where);
    Particle p;
    const std::string named_where = readParticleName(r, item, es, where, name_line, p);
    readParticleKeys(r, es, named_where, p);
    model.particles.push_back(std::move(p));
  }
}

}  // namespace model_yaml
}  // namespace mme
