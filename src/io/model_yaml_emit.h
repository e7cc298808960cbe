// Internal to the model YAML writer (not installed): how single values of a model are written
// (numbers, names, parameter blocks, vectors, gravity). modelToYaml arranges them into the
// document; keeping them apart lets each rule (shortest round-tripping numbers, quoting of
// names a reader would take for something else) be stated once.
#pragma once

#include <yaml-cpp/yaml.h>

#include <array>
#include <map>
#include <string>

#include "motion_model_estimation/core/model.h"

namespace mme {
namespace model_yaml {

/// Emits a number as a plain scalar: the shortest decimal text that reads back to the same
/// double, whatever the locale.
void emitNumber(YAML::Emitter& out, double v);
/// Emits a name, quoted when a YAML reader would take it for something other than this string.
void emitName(YAML::Emitter& out, const std::string& s);
/// Emits a parameter: a plain number when fixed, unbounded and without `std_dev`, else a flow
/// block {value, free, min, max, std}.
void emitParam(YAML::Emitter& out, const Param& p, const double* std_dev);
/// Emits [x, y, z].
void emitVector(YAML::Emitter& out, const Eigen::Vector3d& v);
/// Gravity as [gx, gy, gz] when all three are plain fixed values, otherwise as a block; `stds`
/// by parameter name ("gravity/x", ...).
void emitGravity(YAML::Emitter& out, const std::array<Param, 3>& g,
                 const std::map<std::string, double>& stds);

}  // namespace model_yaml
}  // namespace mme
