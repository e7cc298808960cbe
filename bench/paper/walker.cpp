// The opt-in walker experiments of bench_paper (`walker_oe`, `walker_identify`): the output
// error alone and the default identification on the walker's first 50 frames, scored by the
// parameters within 1 % and the open loop's distance from the data.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "common.h"
#include "experiments.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/estimators/output_error.h"
#include "motion_model_estimation/identification/search/parameter_space.h"
#include "motion_model_estimation/scenes/scenes.h"

namespace paper {


/// The walker's first 50 noiseless frames and its muscle-free parameters (docs/scenes.md).
struct WalkerCase {
  mme::Scene scene = mme::makeScene("walker");
  int frames = 50;
  mme::Trajectory data = mme::simulateTrajectory(scene.model, frames, scene.model.frame_rate_hz);
  std::vector<mme::ParamRef> refs = mme::freeParameters(scene.model);
  std::vector<double> truth = mme::getValues(scene.model, refs);

  /// The true values off by +-`off` (relative). signs_seed 0: alternate signs (- on even
  /// indices); otherwise each sign drawn from std::mt19937(signs_seed).
  std::vector<double> off(double off, unsigned signs_seed = 0) const {
    std::vector<double> v = truth;
    std::mt19937 rng(signs_seed);
    for (size_t k = 0; k < v.size(); ++k) {
      const bool up = signs_seed == 0 ? k % 2 == 1 : (rng() & 1u) == 1u;
      v[k] *= up ? 1.0 + off : 1.0 - off;
    }
    return v;
  }
};

/// How close an answer on the walker is (docs/scenes.md): the parameters within 1 % of the
/// truth, the median and worst relative errors (and the worst's name), and the open loop's RMS
/// distance from the data at the last frame.
struct WalkerScore {
  int within_1pct = 0;
  double median_error = 0.0, worst_error = 0.0, open_loop_rms_m = 0.0;
  std::string worst_name;
};

WalkerScore scoreWalker(const Model& truth_model, const mme::Trajectory& data,
                        const std::vector<double>& values) {
  const std::vector<mme::ParamRef> refs = mme::freeParameters(truth_model);
  const std::vector<double> truth = mme::getValues(truth_model, refs);
  WalkerScore score;
  std::vector<double> errors;
  for (size_t k = 0; k < truth.size(); ++k) errors.push_back(std::fabs(values[k] / truth[k] - 1.0));
  score.within_1pct = static_cast<int>(
      std::count_if(errors.begin(), errors.end(), [](double e) { return e < 0.01; }));
  const size_t worst = static_cast<size_t>(std::max_element(errors.begin(), errors.end()) - errors.begin());
  score.worst_error = errors[worst];
  score.worst_name = refs[worst].name;
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  score.median_error = errors[errors.size() / 2];
  Model fitted = truth_model;
  mme::setValues(fitted, refs, values);
  const int frames = data.numFrames();
  const mme::Trajectory open_loop = mme::simulateTrajectory(fitted, frames, fitted.frame_rate_hz);
  double sum2 = 0.0;
  for (int i = 0; i < data.numMarkers(); ++i)
    sum2 += (open_loop.position(frames - 1, i) - data.position(frames - 1, i)).squaredNorm();
  score.open_loop_rms_m = std::sqrt(sum2 / (3.0 * data.numMarkers()));
  return score;
}

/// The output error alone on the walker (the walker's identification targets): 50 noiseless frames,
/// 10-frame segments, its 40 muscle-free parameters started at the truth and 1 % off (alternate
/// signs), the default options (start states fitted by the model, soft then hard continuity) at
/// most 100 iterations per stage, for comparison 1 % off with hard continuity only, and 1 % off
/// with signs drawn at random (seeds 1 and 2: how much the answer depends on the start), and
/// the three 1 % starts again growing the data (OutputErrorOptions::grow_segments 1: the first
/// segment's frames, then 2, 4, then all). Every
/// parameter's error beside its Cramer-Rao bound at 0.1 mm marker noise (what the 50 frames can
/// tell about it) goes to walker_oe_params.csv. Opt-in (`--only walker_oe`, long): the
/// "Identifying the walker" figures of docs/scenes.md.
void walkerOutputError(const Settings& s) {
  std::FILE* f = openCsv(s.out_dir + "/walker_oe.csv",
                         "start_off,signs,continuity,segment_frames,grow_segments,iterations,"
                         "termination,wall_s,"
                         "start_cost_m2,cost_m2,within_1pct,median_error,worst_error,open_loop_1s_rms_m");
  const WalkerCase walker;
  const mme::Scene& scene = walker.scene;
  const mme::Trajectory& data = walker.data;
  const std::vector<mme::ParamRef>& refs = walker.refs;
  const std::vector<double>& truth = walker.truth;
  const mme::ParameterSpace space(scene.model, data);
  struct Run {
    double off;
    bool soft_first;
    unsigned signs_seed;  // 0: alternate signs
    int grow_segments;    // OutputErrorOptions::grow_segments (0: every frame at once)
  };
  std::vector<std::vector<double>> answers;
  size_t growing = 0;  // the answer from 1 % off (alternate signs) growing the data
  for (const Run run : {Run{0.0, true, 0, 0}, Run{0.01, true, 0, 0}, Run{0.01, false, 0, 0},
                        Run{0.01, true, 1, 0}, Run{0.01, true, 2, 0}, Run{0.01, true, 0, 1},
                        Run{0.01, true, 1, 1}, Run{0.01, true, 2, 1}}) {
    if (s.quick && run.signs_seed != 0) continue;
    const std::vector<double> start = walker.off(run.off, run.signs_seed);
    mme::OutputErrorOptions o;
    o.segment_frames = 10;
    o.max_iterations = s.quick ? 3 : 100;
    o.threads = s.threads;
    o.estimate_std = false;
    o.noise_std_m = 1e-4;  // a weight only: the data are noiseless
    if (!run.soft_first) o.first_continuity_weight = 0.0;
    o.grow_segments = run.grow_segments;
    const mme::OutputErrorResult r =
        mme::estimateOutputError(scene.model, data, space, space.toSearch(start), o);
    answers.push_back(r.values);
    if (run.off > 0.0 && run.soft_first && run.signs_seed == 0 && run.grow_segments > 0)
      growing = answers.size() - 1;
    const WalkerScore score = scoreWalker(scene.model, data, r.values);
    const char* continuity = run.soft_first ? "soft_then_hard" : "hard";
    const std::string signs =
        run.signs_seed == 0 ? "alternate" : "random_seed_" + std::to_string(run.signs_seed);
    std::fprintf(f, "%g,%s,%s,%d,%d,%d,%s,%.2f,%.6g,%.6g,%d,%.6g,%.6g,%.6g\n", run.off,
                 signs.c_str(), continuity, o.segment_frames, run.grow_segments, r.iterations,
                 r.converged ? "converged" : "limit", r.wall_time_s, r.start_cost_m2,
                 r.observation_cost_m2, score.within_1pct, score.median_error, score.worst_error,
                 score.open_loop_rms_m);
    std::fflush(f);
    std::printf("walker_oe: from %g %% off (%s signs), %s continuity, %d-frame segments, "
                "growing from %d segment(s) (0: all at once): %d "
                "iterations (%s), %.1f s; cost %.4g -> %.4g m^2; %d of %zu parameters within 1 %%, "
                "median %.3g %%, worst %.3g %% (%s); open loop after 1 s %.3g m RMS\n",
                100.0 * run.off, signs.c_str(), continuity, o.segment_frames, run.grow_segments,
                r.iterations,
                r.termination.c_str(), r.wall_time_s, r.start_cost_m2, r.observation_cost_m2,
                score.within_1pct, truth.size(), 100.0 * score.median_error,
                100.0 * score.worst_error, score.worst_name.c_str(), score.open_loop_rms_m);
    std::fflush(stdout);
  }
  std::fclose(f);
  // What 50 frames can tell about each parameter: its Cramer-Rao bound at 0.1 mm noise.
  const std::vector<double> bound = mme::cramerRaoBound(scene.model, data, space, 1e-4);
  std::FILE* g = openCsv(s.out_dir + "/walker_oe_params.csv",
                         "parameter,true_value,error_from_truth_percent,error_from_1pct_percent,"
                         "error_hard_only_percent,error_from_1pct_growing_percent,"
                         "cramer_rao_0.1mm_percent");
  for (size_t k = 0; k < truth.size(); ++k) {
    std::fprintf(g, "%s,%.9g", refs[k].name.c_str(), truth[k]);
    for (size_t a : {size_t{0}, size_t{1}, size_t{2}, growing})
      std::fprintf(g, ",%.6g", 100.0 * (answers[a][k] / truth[k] - 1.0));
    std::fprintf(g, ",%.6g\n", 100.0 * bound[k] / std::fabs(truth[k]));
  }
  std::fclose(g);
  std::printf("walker_oe: per-parameter errors and Cramer-Rao bounds in %s/walker_oe_params.csv\n",
              s.out_dir.c_str());
}

/// What a user gets without flags on the walker: the pipeline's identification step with the
/// default preset (the
/// evolution strategy, then the output error) from initial guesses 1 % off (alternate signs),
/// 50 noiseless frames, 100 generations, a 500-s limit. Opt-in (`--only walker_identify`).
void walkerIdentify(const Settings& s) {
  std::FILE* f = openCsv(s.out_dir + "/walker_identify.csv",
                         "frames,generations,estimator,wall_s,within_1pct,median_error,worst_error,"
                         "worst_parameter,open_loop_1s_rms_m");
  const WalkerCase walker;
  Model start = walker.scene.model;
  mme::setValues(start, walker.refs, walker.off(0.01));
  mme::IdentifyOptions o = mme::identifyOptionsFor(s.preset);
  o.generations = s.quick ? 3 : 100;
  o.max_wall_time_s = s.quick ? 60.0 : 500.0;
  o.es.threads = s.threads;
  o.estimate_std = false;
  const auto began = std::chrono::steady_clock::now();
  const mme::IdentifyResult r = mme::identifyPassive(start, walker.data, identifyStep(o));
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  const WalkerScore score = scoreWalker(walker.scene.model, walker.data, r.values);
  std::fprintf(f, "%d,%d,%s,%.1f,%d,%.6g,%.6g,%s,%.6g\n", walker.frames, o.generations, mme::estimatorName(r.estimator),
               wall_s, score.within_1pct, score.median_error, score.worst_error, score.worst_name.c_str(),
               score.open_loop_rms_m);
  std::fclose(f);
  std::printf("walker_identify: %s, %.0f s: %d of %zu parameters within 1 %%, median %.3g %%, worst "
              "%.3g %% (%s); open loop after 1 s %.3g m RMS\n", mme::estimatorName(r.estimator), wall_s,
              score.within_1pct, walker.refs.size(), 100.0 * score.median_error, 100.0 * score.worst_error,
              score.worst_name.c_str(), score.open_loop_rms_m);
}

}  // namespace paper
