// The helpers every bench_paper experiment shares (declared in common.h): relative errors, one
// identification run with its error trace, the parameter tables, the summary.csv line and the
// options the command line sets.
#include "common.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/identification/search/parameter_space.h"

namespace paper {

Errors relativeErrors(const std::vector<double>& values, const std::vector<double>& truth) {
  std::vector<double> e;
  for (size_t k = 0; k < values.size(); ++k)
    e.push_back(100.0 * std::abs(values[k] - truth[k]) / std::max(std::abs(truth[k]), 1e-300));
  Errors out;
  if (e.empty()) return out;
  for (double x : e) out.mean += x / e.size();
  out.max = *std::max_element(e.begin(), e.end());
  std::sort(e.begin(), e.end());
  out.median = e.size() % 2 ? e[e.size() / 2] : 0.5 * (e[e.size() / 2 - 1] + e[e.size() / 2]);
  return out;
}

Model forgetFreeValues(Model m) {
  for (const mme::ParamRef& r : mme::freeParameters(m)) {
    mme::Param& p = mme::paramOf(m, r);
    p.has_value = false;
  }
  return m;
}

RunResult runEs(const Model& truth, const mme::Trajectory& data, mme::IdentifyOptions options,
                const std::function<void(const mme::Progress&, const Errors&)>& per_generation) {
  const std::vector<double> true_values = mme::getValues(truth, mme::freeParameters(truth));
  RunResult out;
  auto progress = [&](const mme::Progress& p) {
    const Errors e = relativeErrors(p.best_values, true_values);
    if (out.generations_to_target < 0 && e.max < 0.01) out.generations_to_target = p.generation;
    if (per_generation) per_generation(p, e);
  };
  out.result = mme::identifyPassive(forgetFreeValues(truth), data, identifyStep(options, progress));
  out.errors = relativeErrors(out.result.values, true_values);
  return out;
}

std::FILE* openCsv(const std::string& path, const char* header) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) throw mme::InputError(path + ": cannot write");
  std::fprintf(f, "%s\n", header);
  return f;
}

void writeTable(const std::string& path, const RunResult& r, const Model& truth) {
  std::FILE* f = openCsv(path, "parameter,reference,estimate,error_percent,std");
  const std::vector<double> ref = mme::getValues(truth, mme::freeParameters(truth));
  for (size_t k = 0; k < r.result.parameters.size(); ++k)
    std::fprintf(f, "%s,%.9g,%.9g,%.6f,%.3g\n", r.result.parameters[k].name.c_str(), ref[k],
                 r.result.values[k], 100.0 * (r.result.values[k] - ref[k]) / std::abs(ref[k]),
                 r.result.std_devs[k]);
  std::fclose(f);
}

void printTable(const char* title, const RunResult& r, const Model& truth) {
  const std::vector<double> ref = mme::getValues(truth, mme::freeParameters(truth));
  std::printf("\n%s\n%-26s %14s %14s %10s\n", title, "parameter", "reference", "estimate", "error %");
  for (size_t k = 0; k < r.result.parameters.size(); ++k)
    std::printf("%-26s %14.7g %14.7g %10.4f\n", r.result.parameters[k].name.c_str(), ref[k],
                r.result.values[k], 100.0 * (r.result.values[k] - ref[k]) / std::abs(ref[k]));
  std::printf("median error %.5f %%, max %.5f %%, cost %.3e, %d generations, %llu evaluations, "
              "%.1f s\n", r.errors.median, r.errors.max, r.result.global_cost,
              r.result.generations, static_cast<unsigned long long>(r.result.evaluations),
              r.result.wall_time_s);
}

std::FILE* g_summary = nullptr;

void summary(const std::string& experiment, const RunResult& r) {
  std::fprintf(g_summary, "%s,%zu,%.6g,%.6g,%.6g,%d,%d,%llu,%.3f,%.6g\n", experiment.c_str(),
               r.result.parameters.size(), r.errors.mean, r.errors.median, r.errors.max,
               r.result.generations, r.generations_to_target,
               static_cast<unsigned long long>(r.result.evaluations), r.result.wall_time_s,
               r.result.global_cost);
  std::fflush(g_summary);
}

mme::IdentifyOptions esOptions(const Settings& s, int generations) {
  mme::IdentifyOptions o = mme::identifyOptionsFor(s.preset);
  if (s.generations > 0) generations = s.generations;
  o.generations = s.quick ? std::max(20, generations / 20) : generations;
  if (s.refine_start >= 0) o.es.refine_start_generation = s.refine_start;
  if (s.refine_period >= 0) o.es.refine_period = s.refine_period;
  if (s.refine_evaluations >= 0) o.es.refine_max_evaluations = s.refine_evaluations;
  if (!s.refine.empty() && !mme::parseRefineAlgorithm(s.refine, &o.es.refine_algorithm))
    throw mme::InputError(std::string("--refine must be ") + mme::refineAlgorithmNames());
  o.es.threads = s.threads;
  o.es.seed = s.seed;
  return o;
}

mme::PipelineOptions identifyStep(const mme::IdentifyOptions& identify,
                                  std::function<void(const mme::Progress&)> progress) {
  mme::PipelineOptions p;
  p.identify = identify;
  p.progress = std::move(progress);
  return p;
}

mme::PipelineOptions structureStep(const Settings& s) {
  mme::PipelineOptions p;
  p.select_structure = true;
  p.identify = mme::identifyOptionsFor(mme::Preset::kDefault);
  p.identify.es.threads = s.threads;
  p.identify.estimate_std = false;
  return p;
}

mme::StructureResult selectStructureOnFitted(const mme::HeldOutSplit& split,
                                             const mme::PipelineOptions& options) {
  checkUnseen(split.fit, split, "structure selection");
  return mme::chooseStructure(mme::startingModel(split.fit), split.fit, options);
}

void checkUnseen(const mme::Trajectory& seen, const mme::HeldOutSplit& split, const std::string& who) {
  const bool reports = split.held_start < split.held.numFrames();
  if (seen.numFrames() == 0 || !reports) return;
  const double last_seen_s = seen.times_s.back(), first_reported_s = split.held.times_s[split.held_start];
  if (!(last_seen_s < first_reported_s))
    throw std::logic_error(who + " saw frames up to t = " + std::to_string(last_seen_s) +
                           " s, which reach the reported held-out frames (from t = " +
                           std::to_string(first_reported_s) + " s)");
}

}  // namespace paper
