// Named sets of engine settings. The default is what the benchmarks measured best; the paper's
// own settings stay reproducible as a preset (docs/paper is made with it).
#pragma once

#include <string>

namespace mme {

enum class Preset {
  kDefault,  ///< the measured best (see EsOptions, IdentifyOptions, OnlineEstimatorOptions)
  kPaper,    ///< Stanciulescu & Louchet's schedule: BOBYQA from generation 400, every 100
};

/// "default" | "paper" -> the enum; false when unknown.
bool parsePreset(const std::string& name, Preset* preset);
const char* presetName(Preset preset);
/// For messages: "default or paper".
const char* presetNames();

}  // namespace mme
