#include "motion_model_estimation/pipeline/result_checks.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace mme {

namespace {

/// A length for a person: "0.35 mm", "25 cm", "338 m".
std::string formatLength(double m) {
  char text[32];
  const double a = std::abs(m);
  if (a < 0.01) std::snprintf(text, sizeof(text), "%.3g mm", m * 1e3);
  else if (a < 1.0) std::snprintf(text, sizeof(text), "%.3g cm", m * 1e2);
  else std::snprintf(text, sizeof(text), "%.3g m", m);
  return text;
}

/// The median distance between markers `a` and `b` over the frames that see both; 0 when none.
double medianDistance(const Trajectory& trajectory, int a, int b) {
  std::vector<double> d;
  for (int t = 0; t < trajectory.numFrames(); ++t)
    if (!trajectory.isOccluded(t, a) && !trajectory.isOccluded(t, b))
      d.push_back((trajectory.position(t, a) - trajectory.position(t, b)).norm());
  if (d.empty()) return 0.0;
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  return d[d.size() / 2];
}

std::string gravityWarning(const Model& model) {
  bool free = false;
  for (const Param& g : model.gravity_mps2) free = free || g.free;
  const double g = model.gravity().norm();
  if (!free || (g >= kGravityLow_mps2 && g <= kGravityHigh_mps2)) return "";
  char line[512];
  if (g > kGravityHigh_mps2)
    std::snprintf(line, sizeof(line),
                  "the identified gravity is %.3g m/s^2, the Earth's is 9.81: are the data's units "
                  "right (millimetres read as metres give about 1000x the motion)? If they are, "
                  "something the model lacks pushes the markers (bonds, the floor)",
                  g);
  else
    std::snprintf(line, sizeof(line),
                  "the identified gravity is %.3g m/s^2, the Earth's is 9.81: the markers do not "
                  "fall as free bodies would (held or driven by something the model lacks: bonds "
                  "to a fixed point, muscles), or the data's units are off (metres read as "
                  "millimetres give 1/1000 of the motion)",
                  g);
  return line;
}

/// One line per bond type whose first bond's rest length is tiny next to its markers' distance.
std::vector<std::string> tinyRestLengthWarnings(const Model& model, const Trajectory& trajectory) {
  std::vector<std::string> out;
  std::vector<bool> told(model.bond_types.size(), false);
  for (const Bond& bond : model.bonds) {
    const BondType& type = model.bond_types[static_cast<size_t>(bond.type)];
    if (told[static_cast<size_t>(bond.type)] || !bondKindInfo(type.kind).has_elongation ||
        !type.param(kRestLength).present)
      continue;
    const Particle& a = model.particles[static_cast<size_t>(bond.particles[0])];
    const Particle& b = model.particles[static_cast<size_t>(bond.particles[1])];
    const int ia = bond.particles[0], ib = bond.particles[1];
    if (ia >= trajectory.numMarkers() || ib >= trajectory.numMarkers()) continue;
    const double distance_m = medianDistance(trajectory, ia, ib);
    const double rest_m = type.value(kRestLength);
    if (!(distance_m > 0.0) || rest_m >= kTinyRestShare * distance_m) continue;
    told[static_cast<size_t>(bond.type)] = true;
    out.push_back("bond type '" + type.name + "' (" + a.name + " - " + b.name + "): rest length " +
                  formatLength(rest_m) + " against a median distance of " + formatLength(distance_m) +
                  " between its markers: it pulls them together with its whole stiffness; the bond "
                  "is likely spurious (leave it out, or give rest_length a min)");
  }
  return out;
}

}  // namespace

std::string parameterUnit(const Model& model, const ParamRef& ref) {
  if (ref.bond_type < 0) return "m/s^2";
  if (ref.isNetwork()) return "1";
  const BondType& type = model.bond_types[static_cast<size_t>(ref.bond_type)];
  const ParamId id = static_cast<ParamId>(ref.param);
  if (type.kind == BondKind::kFlexion) {
    if (id == kStiffness) return "N m/rad";
    if (id == kDamping) return "N m s/rad";
  }
  return paramInfo(id).unit;
}

bool unitMasses(const Model& model) {
  if (model.particles.empty()) return false;
  for (const Particle& p : model.particles)
    if (!p.fixed && p.mass_kg != 1.0) return false;
  return true;
}

std::vector<std::string> identifiedModelWarnings(const Model& identified, const Trajectory& trajectory) {
  std::vector<std::string> out;
  const std::string gravity = gravityWarning(identified);
  if (!gravity.empty()) out.push_back(gravity);
  for (const std::string& line : tinyRestLengthWarnings(identified, trajectory)) out.push_back(line);
  return out;
}

std::vector<std::string> chosenStructureWarnings(const StructureResult& structure) {
  std::vector<std::string> out;
  const int horizons[3] = {1, 5, 10};
  const char* guesses[3] = {"constant velocity", "constant acceleration", "gravity only"};
  for (const StructureCandidate& c : structure.candidates) {
    if (!c.chosen) continue;
    std::string losses;  // "10 frame(s) ahead 2.18 mm against constant velocity 1.91 mm, ..."
    for (int h = 0; h < 3; ++h) {
      std::string beaten_by;
      for (int g = 0; g < 3; ++g) {
        const double guess_m = structure.guess_rms_m[g][h];
        if (!(guess_m < c.held_out_rms_m[h])) continue;  // NaN: nothing judged
        char part[64];
        std::snprintf(part, sizeof(part), "%s%s %.3g mm", beaten_by.empty() ? "" : ", ", guesses[g],
                      guess_m * 1e3);
        beaten_by += part;
      }
      if (beaten_by.empty()) continue;
      char part[256];
      std::snprintf(part, sizeof(part), "%s%d frame(s) ahead %.3g mm against %s", losses.empty() ? "" : "; ",
                    horizons[h], c.held_out_rms_m[h] * 1e3, beaten_by.c_str());
      losses += part;
    }
    if (losses.empty()) continue;
    out.push_back("the chosen model ('" + c.name + "') predicts the held-out frames worse than a guess "
                  "that needs no model (" + losses + "): it does not capture this motion; use its "
                  "figures with care");
  }
  return out;
}

}  // namespace mme
