#include "motion_model_estimation/identification/search/preset.h"

namespace mme {

bool parsePreset(const std::string& name, Preset* preset) {
  if (name == "default") *preset = Preset::kDefault;
  else if (name == "paper") *preset = Preset::kPaper;
  else return false;
  return true;
}

const char* presetName(Preset preset) {
  switch (preset) {
    case Preset::kDefault: return "default";
    case Preset::kPaper: return "paper";
  }
  return "?";
}

const char* presetNames() { return "default or paper"; }

}  // namespace mme
