// What a user gets by default (random and hanging objects through TRC files, no values and no
// bounds given) and the accuracy under noise against the Cramer-Rao bound: the `defaults` and
// `accuracy` experiments of bench_paper.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "common.h"
#include "experiments.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/estimators/output_error.h"
#include "motion_model_estimation/identification/search/parameter_space.h"
#include "motion_model_estimation/io/trajectory_io.h"
#include "motion_model_estimation/io/trc.h"
#include "motion_model_estimation/scenes/random_object.h"
#include "motion_model_estimation/scenes/scenes.h"

namespace paper {

/// What a user gets by default: random objects like random18 and soft objects hanging
/// under gravity (springs stretched 2.4-20x their rest length), 10 seeds each, noiseless, each
/// through a TRC file in millimetres, with a model file that gives no value and no bound for any
/// free parameter; `identify`'s default engine (Preset::kDefault, whatever --preset says).
void defaultsExperiment(const Settings& s) {
  std::FILE* f = openCsv(s.out_dir + "/defaults.csv",
                         "object,seed,unknowns,median_error_percent,max_error_percent,wall_s,"
                         "generations,evaluations,bound_widenings,flagged,stop");
  const int seeds = s.quick ? 2 : 10;
  const std::string trc = s.out_dir + "/defaults_tmp.trc";
  for (const std::string object : {"random18", "hanging16"}) {
    std::vector<double> worst, times;
    for (int seed = 1; seed <= seeds; ++seed) {
      Model truth;
      int frames = 0;
      if (object == "random18") {
        mme::RandomObjectSpec spec;  // 18 markers, 12 types, 40 bonds, 120 Hz
        spec.seed = 100 + seed;
        truth = mme::makeRandomObject(spec);
        frames = 120;
      } else {
        mme::HangingObjectSpec spec;  // 16 markers (2 fixed), 8 damped types, 30 bonds, 120 Hz
        spec.seed = 200 + seed;
        truth = mme::makeHangingObject(spec);
        frames = 300;
      }
      mme::writeTrc(trc, mme::simulateTrajectory(truth, frames, truth.frame_rate_hz), "mm");
      const mme::Trajectory data = mme::readTrajectoryFile(trc);
      Model blank = truth;
      for (mme::BondType& t : blank.bond_types)
        for (mme::Param& p : t.params) {
          p.has_min = p.has_max = false;
          p.min = -INFINITY;
          p.max = INFINITY;
        }
      mme::IdentifyOptions o = mme::identifyOptionsFor(mme::Preset::kDefault);
      o.es.threads = s.threads;
      o.es.seed = s.seed;
      o.estimate_std = false;
      const RunResult r = runEs(blank, data, o, nullptr);
      size_t flagged = 0;
      for (mme::ParameterFlag flag : r.result.flags) flagged += flag != mme::ParameterFlag::kNone;
      std::fprintf(f, "%s,%d,%zu,%.6g,%.6g,%.3f,%d,%llu,%d,%zu,%s\n", object.c_str(), seed,
                   r.result.parameters.size(), r.errors.median, r.errors.max, r.result.wall_time_s,
                   r.result.generations, static_cast<unsigned long long>(r.result.evaluations),
                   r.result.bound_widenings, flagged, mme::identifyStopName(r.result.stop));
      std::fflush(f);
      std::printf("defaults: %s seed %2d: %zu unknowns, median %.2e %%, max %.2e %%, %.2f s, "
                  "%d generations, %d widenings\n", object.c_str(), seed, r.result.parameters.size(),
                  r.errors.median, r.errors.max, r.result.wall_time_s, r.result.generations,
                  r.result.bound_widenings);
      worst.push_back(r.errors.max);
      times.push_back(r.result.wall_time_s);
    }
    std::printf("defaults: %s: worst max error %.2e %%, slowest %.2f s over %d seeds\n",
                object.c_str(), *std::max_element(worst.begin(), worst.end()),
                *std::max_element(times.begin(), times.end()), seeds);
  }
  std::remove(trc.c_str());
  std::fclose(f);
}

/// Accuracy under noise against the Cramer-Rao bound: paper_object, 100 frames, the
/// default engine (identify's defaults: the output-error estimator on noisy data), seeds 1..N
/// per noise level. Per run: median and max error, the bound's median and max, how many
/// parameters lie within 3 reported std, the largest std / bound ratio.
void accuracyExperiment(const Settings& s) {
  std::FILE* f = openCsv(s.out_dir + "/accuracy.csv",
                         "noise_std_m,seed,estimator,median_error_percent,max_error_percent,"
                         "bound_median_percent,bound_max_percent,within_3std,parameters,"
                         "max_std_over_bound,noise_estimate_m,wall_s");
  // Every parameter's reported std and its bound at full precision: a change of the covariance
  // computation is checked against these, not against the rounded ratio above.
  std::FILE* stds = openCsv(s.out_dir + "/accuracy_std.csv",
                            "noise_std_m,seed,estimator,parameter,std,bound");
  const mme::Scene scene = mme::makeScene("paper_object");
  const mme::Trajectory clean = mme::simulateTrajectory(scene.model, 100, scene.model.frame_rate_hz);
  const std::vector<double> truth = mme::getValues(scene.model, mme::freeParameters(scene.model));
  const int seeds = s.quick ? 2 : 20;
  for (double noise : {1e-5, 1e-4, 1e-3}) {
    const mme::ParameterSpace space(scene.model, clean);
    const std::vector<double> bound = mme::cramerRaoBound(scene.model, clean, space, noise);
    std::vector<double> bound_pct;
    for (size_t k = 0; k < bound.size(); ++k) bound_pct.push_back(100.0 * bound[k] / std::abs(truth[k]));
    Errors b;  // the bound's median and max [%]
    {
      std::vector<double> sorted = bound_pct;
      std::sort(sorted.begin(), sorted.end());
      const size_t m = sorted.size();
      b.median = m % 2 ? sorted[m / 2] : 0.5 * (sorted[m / 2 - 1] + sorted[m / 2]);
      b.max = sorted.back();
    }
    std::vector<double> medians, maxima;
    int within = 0, total = 0;
    double worst_ratio = 0.0;
    for (int seed = 1; seed <= seeds; ++seed) {
      mme::Trajectory data = clean;
      mme::addGaussianNoise(&data, noise, 500 + seed);
      mme::IdentifyOptions o = mme::identifyOptionsFor(mme::Preset::kDefault);
      o.es.threads = s.threads;
      o.es.seed = s.seed;
      const RunResult r = runEs(scene.model, data, o, nullptr);
      int run_within = 0;
      double ratio = 0.0;
      for (size_t k = 0; k < truth.size(); ++k) {
        const double sd = r.result.std_devs[k];
        if (std::isfinite(sd) && std::abs(r.result.values[k] - truth[k]) <= 3.0 * sd) ++run_within;
        if (std::isfinite(sd) && bound[k] > 0.0) ratio = std::max(ratio, sd / bound[k]);
        std::fprintf(stds, "%g,%d,%s,%zu,%.17g,%.17g\n", noise, seed, mme::estimatorName(r.result.estimator),
                     k, sd, bound[k]);
      }
      within += run_within;
      total += static_cast<int>(truth.size());
      worst_ratio = std::max(worst_ratio, ratio);
      medians.push_back(r.errors.median);
      maxima.push_back(r.errors.max);
      std::fprintf(f, "%g,%d,%s,%.6g,%.6g,%.6g,%.6g,%d,%zu,%.4g,%.4g,%.3f\n", noise, seed,
                   mme::estimatorName(r.result.estimator), r.errors.median, r.errors.max, b.median, b.max,
                   run_within, truth.size(), ratio, r.result.noise_estimate_m, r.result.wall_time_s);
      std::fflush(f);
    }
    std::sort(medians.begin(), medians.end());
    std::printf("accuracy: noise %g m, %d seeds: median of median errors %.4f %% (bound median "
                "%.4f %%, ratio %.2f), worst max error %.4f %% (bound max %.4f %%); |error| <= 3 std "
                "for %d of %d parameters (%.1f %%); largest std / bound %.2f\n",
                noise, seeds, medians[medians.size() / 2], b.median,
                medians[medians.size() / 2] / b.median, *std::max_element(maxima.begin(), maxima.end()),
                b.max, within, total, 100.0 * within / total, worst_ratio);
  }
  std::fclose(stds);
  std::fclose(f);
}

}  // namespace paper
