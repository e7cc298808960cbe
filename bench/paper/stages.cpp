// The `stages` experiment of bench_paper: what each step of the offline pipeline buys on the real
// recordings. Every recording goes through the pipeline identify runs by default with
// --select-structure (runPipeline, the same named steps), with the sensor muscles always tried so
// that their cost shows; after each step its model predicts 10 frames ahead on the frames after
// the fitted window, which no step has seen, beside the model-free guesses on the same samples
// (the pipeline's judge step; stages.csv; scripts/bench-paper draws stages.png: time against
// held-out error).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "common.h"
#include "experiments.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/io/trajectory_io.h"
#include "motion_model_estimation/pipeline/identify_pipeline.h"

namespace paper {
namespace {

/// A step's model, when the run had it [s from the pipeline's start], and what it fits: its free
/// parameters, with the sensor muscles' linear unknowns where kept.
struct StageModel {
  std::string stage;
  double elapsed_s = 0.0;
  Model model;
  size_t parameters = 0;
};

/// The window identify's quick start fits (the first 240 frames, at most 80 % of a short
/// recording) and the frames after it (at most 1 400), judged with the window as history.
struct Window {
  mme::Trajectory fitted, whole;
  int judged_start = 0;
};

Window windowOf(const mme::Trajectory& data) {
  const int frames = data.numFrames();
  const int fitted = std::min(240, static_cast<int>(0.8 * frames));
  const int end = std::min(frames, fitted + 1400);
  return {mme::sliceFrames(data, 0, fitted), mme::sliceFrames(data, 0, end), fitted};
}

/// identify's defaults with --select-structure, and the sensor muscles always tried.
mme::PipelineOptions pipelineOptions(const Settings& s) {
  mme::PipelineOptions p;
  p.identify = mme::identifyOptionsFor(mme::Preset::kDefault);
  p.identify.es.threads = s.threads;
  p.identify.es.seed = s.seed;
  p.select_structure = true;
  p.sensor_muscles = mme::SensorMuscleOptions{};
  return p;
}

/// Runs the pipeline on the window, keeping the model after each step: the structure's refit,
/// the evolution strategy's best (its last generation, before any output-error fit), the passive
/// identification's answer, and the final model (sensor muscles where kept).
std::vector<StageModel> runStages(const Settings& s, const mme::Trajectory& fitted) {
  using Clock = std::chrono::steady_clock;
  const Clock::time_point t0 = Clock::now();
  const auto elapsed = [&t0] { return std::chrono::duration<double>(Clock::now() - t0).count(); };
  std::vector<StageModel> stages;
  mme::PipelineOptions p = pipelineOptions(s);
  p.structure_chosen = [&](const mme::StructureResult& r) {
    stages.push_back({"structure", elapsed(), r.model, mme::freeParameters(r.model).size()});
  };
  Model searched;
  p.identification_starts = [&searched](const Model& m, const mme::Trajectory&) { searched = m; };
  std::vector<double> best;
  double best_at_s = 0.0;
  p.progress = [&](const mme::Progress& g) {
    if (!g.message.empty() || g.best_values.empty()) return;
    best = g.best_values;
    best_at_s = elapsed();
  };
  p.passive_identified = [&](const mme::PipelineResult& r) {
    if (!best.empty() && best.size() == mme::freeParameters(searched).size()) {
      mme::setValues(searched, mme::freeParameters(searched), best);
      stages.push_back({"search", best_at_s, searched, best.size()});
    }
    stages.push_back({std::string("passive_") + mme::estimatorName(r.identified.estimator), elapsed(),
                      r.model, r.identified.values.size()});
  };
  const mme::PipelineResult r = mme::runPipeline(mme::startingModel(fitted), fitted, p);
  const bool kept = r.sensor_muscles && r.sensor_muscles->better_than_passive;
  stages.push_back({kept ? "sensor_muscles" : "sensor_muscles_not_kept", elapsed(), r.model,
                    r.identified.values.size() + (kept ? r.sensor_muscles->unknowns : 0)});
  return stages;
}

/// The RMS [mm] of `predictor` 10 frames ahead in `report`.
double rmsMm(const mme::PredictionReport& report, mme::Predictor predictor) {
  for (const mme::PredictionError& e : report.rows)
    if (e.predictor == predictor) return 1e3 * e.rms_m;
  return NAN;
}

}  // namespace

void stagesExperiment(const Settings& s) {
  std::FILE* f = openCsv(s.out_dir + "/stages.csv",
                         "file,markers,fitted_frames,judged_frames,stage,elapsed_s,parameters,"
                         "predict10_mm,constant_velocity_mm,constant_acceleration_mm,rollout_bounded");
  for (const char* file : {"arm26_elbow_flex.trc", "Sample01_Eb015pi.c3d", "Sample02_dec_real.c3d",
                           "Sample02_pc_int.c3d", "Sample26_Walking_Hybrid_1_1.c3d",
                           "subject01_walk1.trc", "motion_capture_walk.trc"}) {
    if (s.quick && std::string(file) != "arm26_elbow_flex.trc") continue;
    if (!s.wantsStagesCase(file)) continue;
    const mme::Trajectory data =
        mme::readTrajectoryFile(std::string(MME_TEST_DATA_DIR) + "/real/" + file);
    const Window w = windowOf(data);
    if (w.whole.numFrames() - w.judged_start < 20) {
      std::printf("stages: %s: fewer than 20 frames after the window: skipped\n", file);
      continue;
    }
    std::printf("stages: %s: %d markers, %d frames fitted, %d judged\n", file, data.numMarkers(),
                w.judged_start, w.whole.numFrames() - w.judged_start);
    std::fflush(stdout);
    for (const StageModel& st : runStages(s, w.fitted)) {
      const mme::PredictionReport report = mme::judgePredictions(st.model, w.whole, w.judged_start);
      const double model_mm = rmsMm(report, mme::Predictor::kModel);
      std::fprintf(f, "%s,%d,%d,%d,%s,%.3f,%zu,%.4g,%.4g,%.4g,%d\n", file, data.numMarkers(),
                   w.judged_start, w.whole.numFrames() - w.judged_start, st.stage.c_str(),
                   st.elapsed_s, st.parameters, model_mm,
                   rmsMm(report, mme::Predictor::kConstantVelocity),
                   rmsMm(report, mme::Predictor::kConstantAcceleration), report.rollout_bounded ? 1 : 0);
      std::fflush(f);
      std::printf("stages: %s: %-24s %8.1f s  10 frames ahead %8.3g mm (constant velocity %.3g, "
                  "constant acceleration %.3g)\n",
                  file, st.stage.c_str(), st.elapsed_s, model_mm,
                  rmsMm(report, mme::Predictor::kConstantVelocity),
                  rmsMm(report, mme::Predictor::kConstantAcceleration));
      std::fflush(stdout);
    }
  }
  std::fclose(f);
}

}  // namespace paper
