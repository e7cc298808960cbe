// The structure selection's report (structure_selection.h): every candidate level tried and
// the model-free guesses, as a text table for people and as CSV for scripts. Kept apart from
// the selection so that the figures' presentation can change without touching how they are
// found.
#include "motion_model_estimation/identification/structure/structure_selection.h"

#include <cstdio>
#include <sstream>

namespace mme {

std::string formatStructureReport(const StructureResult& r) {
  std::ostringstream out;
  char line[320];
  std::snprintf(line, sizeof(line),
                "structure selection: %d candidate bonds; %d frames fitted, %d held out\n",
                r.candidate_bonds, r.fitted_frames, r.held_out_frames);
  out << line;
  std::snprintf(line, sizeof(line), "%-34s %6s %6s %6s %12s %12s %12s %10s %10s %10s %8s %s\n",
                "candidate", "bonds", "types", "params", "fit_rms_m", "bic", "refit_m2",
                "held1_mm", "held5_mm", "held10_mm", "bounded", "");
  out << line;
  for (const StructureCandidate& c : r.candidates) {
    std::snprintf(line, sizeof(line),
                  "%-34s %6d %6d %6d %12.4g %12.6g %12.4g %10.4g %10.4g %10.4g %8s %s%s\n",
                  c.name.c_str(), c.bonds, c.bond_types, c.parameters, c.fit_rms_m, c.bic,
                  c.refit_cost_m2, 1e3 * c.held_out_rms_m[0], 1e3 * c.held_out_rms_m[1],
                  1e3 * c.held_out_rms_m[2], c.rollout_bounded ? "yes" : "no",
                  c.chosen ? "<- chosen" : "",
                  c.same_as.empty() ? "" : ("(= " + c.same_as + ")").c_str());
    out << line;
  }
  const char* guesses[3] = {"constant_velocity", "constant_acceleration", "gravity_only"};
  for (int g = 0; g < 3; ++g) {
    std::snprintf(line, sizeof(line), "%-34s %6s %6s %6s %12s %12s %12s %10.4g %10.4g %10.4g\n",
                  guesses[g], "-", "-", "0", "-", "-", "-", 1e3 * r.guess_rms_m[g][0],
                  1e3 * r.guess_rms_m[g][1], 1e3 * r.guess_rms_m[g][2]);
    out << line;
  }
  for (const std::string& n : r.notes) out << "note: " << n << "\n";
  return out.str();
}

std::string structureReportCsv(const StructureResult& r) {
  std::ostringstream out;
  out << "name,bonds,bond_types,parameters,fit_rms_m,bic,refit_cost_m2,held_out_rms_1_m,"
         "held_out_rms_5_m,held_out_rms_10_m,rollout_bounded,chosen,same_as\n";
  char line[400];
  for (const StructureCandidate& c : r.candidates) {
    std::snprintf(line, sizeof(line), "%s,%d,%d,%d,%.6g,%.9g,%.6g,%.6g,%.6g,%.6g,%d,%d,%s\n",
                  c.name.c_str(), c.bonds, c.bond_types, c.parameters, c.fit_rms_m, c.bic,
                  c.refit_cost_m2, c.held_out_rms_m[0], c.held_out_rms_m[1], c.held_out_rms_m[2],
                  c.rollout_bounded ? 1 : 0, c.chosen ? 1 : 0, c.same_as.c_str());
    out << line;
  }
  const char* guesses[3] = {"constant_velocity", "constant_acceleration", "gravity_only"};
  for (int g = 0; g < 3; ++g) {
    std::snprintf(line, sizeof(line), "%s,,,0,,,,%.6g,%.6g,%.6g,,0,\n", guesses[g],
                  r.guess_rms_m[g][0], r.guess_rms_m[g][1], r.guess_rms_m[g][2]);
    out << line;
  }
  return out.str();
}

}  // namespace mme
