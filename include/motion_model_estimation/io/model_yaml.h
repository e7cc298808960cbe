// Model files (SPEC section 2) and exported models (SPEC section 4) in YAML, via yaml-cpp.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "motion_model_estimation/core/model.h"

namespace mme {

/// Loads a model file. Throws InputError("FILE:LINE: key 'KEY': reason") on any problem
/// (unknown key, unknown particle, wrong arity, negative mass, missing/unknown bond type,
/// malformed value, ...); nothing is returned half-loaded.
Model loadModelFile(const std::string& path);
/// Same from a YAML string; `source_name` is used in messages in place of the file name.
Model loadModelString(const std::string& yaml, const std::string& source_name);

/// Identification results attached to an export (SPEC section 4).
struct IdentificationInfo {
  std::string method;
  /// Which kind of model the file holds ("passive", "sensor_muscles"); written as `model_kind:`
  /// (empty: no key).
  std::string model_kind;
  double global_cost = 0.0;
  int frames = 0;
  int generations = 0;
  double wall_time_s = 0.0;
  std::vector<std::string> std_names;  ///< parameter names that have a std
  std::vector<double> std_values;      ///< 1-sigma per name
  /// Parameters the data left undecided, e.g. {"s01/damping", "at_lower_bound"}: written as the
  /// map `flags:` of the identification block (empty: no key).
  std::vector<std::pair<std::string, std::string>> flags;
  std::vector<std::string> notes;      ///< written as the list `notes:` (empty: no key)
};

/// YAML text of a model (every parameter block with value/free/min/max as present); with
/// `info`, adds `std:` in each listed parameter block and a top-level `identification:` block.
std::string modelToYaml(const Model& model, const IdentificationInfo* info = nullptr);
/// Writes modelToYaml atomically (temp file in the same directory + rename). Throws InputError
/// naming the path when it cannot be written.
void writeModelFile(const std::string& path, const Model& model,
                    const IdentificationInfo* info = nullptr);

/// Writes `content` to `path` atomically (temp + fsync + rename). Throws InputError on failure.
void writeFileAtomically(const std::string& path, const std::string& content);

}  // namespace mme
