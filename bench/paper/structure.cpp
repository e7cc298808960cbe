// The `structure` and `structure_real` experiments of bench_paper: the pipeline's structure step
// on random objects of known structure and on the real recordings (its judge step on held-out
// frames).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "common.h"
#include "experiments.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/structure/structure_selection.h"
#include "motion_model_estimation/io/trajectory_io.h"
#include "motion_model_estimation/scenes/random_object.h"
#include "motion_model_estimation/scenes/scenes.h"

namespace paper {

/// Structure selection: random objects of known structure (15-25 markers, springs
/// only, springs + dampers, hardening springs; bent chains with flexion; noiseless, 10 seeds
/// each), a 40-marker object for the time, and the real recordings (held-out frames as the judge).
void structureExperiment(const Settings& s) {
  std::FILE* f = openCsv(s.out_dir + "/structure.csv",
                         "case,seed,markers,true_bonds,true_types,candidate_bonds,bonds,types,"
                         "f1,components_exact,types_within_10pct,max_error_percent,wall_s");
  const int seeds = s.quick ? 1 : 10;
  mme::PipelineOptions so = structureStep(s);
  if (std::getenv("MME_STRUCTURE_VERBOSE"))
    so.say = [](const std::string& line) { std::printf("  %s\n", line.c_str()); };
  const auto run = [&](const std::string& name, int seed, const Model& truth, int frames,
                       double noise_m) {
    mme::Trajectory data = mme::simulateTrajectory(truth, frames, truth.frame_rate_hz);
    if (noise_m > 0.0) mme::addGaussianNoise(&data, noise_m, 1000 + seed);
    Model particles = truth;
    particles.bonds.clear();
    particles.bond_types.clear();
    const auto start = std::chrono::steady_clock::now();
    const mme::StructureResult r = mme::chooseStructure(particles, data, so);
    const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const mme::StructureScore sc = mme::scoreStructure(truth, r.model);
    // The components: dampers, cubic terms, flexion and drags exactly where the truth has them.
    const mme::StructureScore self = mme::scoreStructure(truth, truth);
    const bool exact = (self.damped_everywhere ? sc.damped_everywhere : sc.damped_nowhere) &&
                       (self.cubic_everywhere ? sc.cubic_everywhere : sc.cubic_nowhere) &&
                       sc.flexion_f1 == 1.0 && sc.viscosity_bonds == self.viscosity_bonds;
    const int true_types = static_cast<int>(truth.bond_types.size());
    const bool types_ok = std::abs(sc.types - true_types) <= 0.1 * true_types;
    std::fprintf(f, "%s,%d,%zu,%zu,%d,%d,%zu,%d,%.4f,%d,%d,%.6g,%.3f\n", name.c_str(), seed,
                 truth.particles.size(), truth.bonds.size(), true_types, r.candidate_bonds,
                 r.model.bonds.size(), sc.types, sc.f1, exact ? 1 : 0, types_ok ? 1 : 0,
                 100.0 * sc.max_relative_error, wall_s);
    std::fflush(f);
    std::printf("structure: %s seed %2d: %zu markers, %d candidates -> %zu bonds (truth %zu), %d "
                "types (truth %d), F1 %.3f, components %s, max error %.2e %%, %.2f s\n",
                name.c_str(), seed, truth.particles.size(), r.candidate_bonds, r.model.bonds.size(),
                truth.bonds.size(), sc.types, true_types, sc.f1, exact ? "exact" : "WRONG",
                100.0 * sc.max_relative_error, wall_s);
  };
  for (const bool damped : {false, true})
    for (int seed = 1; seed <= seeds; ++seed) {
      mme::RandomObjectSpec spec;
      spec.particles = 15 + (7 * seed) % 11;  // 15..25
      spec.bond_types = 8;
      spec.bonds = 2 * spec.particles;
      spec.damping_max_nspm = damped ? 0.5 : 0.0;
      spec.seed = 300 + seed;
      run(damped ? "springs_dampers" : "springs", seed, mme::makeRandomObject(spec), 240, 0.0);
    }
  // Bent chains with flexion (3-5 chains of 4-6 particles, half of them damped) and hardening
  // springs (cubic terms worth 5-10 % of the tension at 10 % strain).
  for (int seed = 1; seed <= seeds; ++seed) {
    mme::ChainObjectSpec spec;
    spec.chains = 3 + seed % 3;
    spec.links = 4 + (seed / 3) % 3;
    spec.damping_max_nspm = seed % 2 ? 0.0 : 0.5;
    spec.seed = 500 + seed;
    run("chains_flexion", seed, mme::makeChainObject(spec), 240, 0.0);
  }
  for (int seed = 1; seed <= seeds; ++seed) {
    mme::RandomObjectSpec spec;
    spec.particles = 15 + (7 * seed) % 11;
    spec.bond_types = 6;
    spec.bonds = 2 * spec.particles;
    spec.stiffness_nl_scale = 10.0;
    spec.seed = 600 + seed;
    run("springs_cubic", seed, mme::makeRandomObject(spec), 240, 0.0);
  }
  // Not a target yet: the same springs-only objects with 10 um of marker noise, 600 frames.
  for (int seed = 1; seed <= (s.quick ? 0 : 5); ++seed) {
    mme::RandomObjectSpec spec;
    spec.particles = 15 + (7 * seed) % 11;
    spec.bond_types = 8;
    spec.bonds = 2 * spec.particles;
    spec.seed = 300 + seed;
    run("springs_noise_10um", seed, mme::makeRandomObject(spec), 600, 1e-5);
  }
  {
    mme::RandomObjectSpec spec;
    spec.particles = 40;
    spec.bond_types = 12;
    spec.bonds = 90;
    spec.seed = 400;
    run("springs_40_markers", 1, mme::makeRandomObject(spec), 240, 0.0);
  }
  std::fclose(f);
}

namespace {

/// The 10-frame open-loop prediction errors (model, constant velocity, constant acceleration,
/// gravity only) of `model` on the held-out frames of `split`, and whether its rollout stays
/// bounded; NaN where nothing could be judged.
bool judgeUnseen(const Model& model, const mme::HeldOutSplit& split, double rms[4]) {
  for (int k = 0; k < 4; ++k) rms[k] = NAN;
  try {
    const mme::PredictionReport pr = mme::judgePredictions(model, split.held, split.held_start);
    for (const mme::PredictionError& row : pr.rows) rms[static_cast<int>(row.predictor)] = row.rms_m;
    return pr.rollout_bounded;
  } catch (const mme::InputError& e) {
    std::printf("structure: %s\n", e.what());
    return false;
  }
}

}  // namespace

/// Structure selection on the real recordings (their first 300 frames): no truth. The selection
/// sees the first 80 % only (and ranks its levels on the end of those); the chosen model is
/// judged on the last 20 %, which no choice has seen. Part of `--only structure`; alone as
/// `--only structure_real`.
void structureRealExperiment(const Settings& s) {
  const mme::PipelineOptions so = structureStep(s);
  std::FILE* g = openCsv(s.out_dir + "/structure_real.csv",
                         "file,markers,frames,candidate_bonds,full_candidate_parameters,chosen,"
                         "bonds,types,parameters,model_rms_10_m,constant_velocity_rms_10_m,"
                         "constant_acceleration_rms_10_m,gravity_only_rms_10_m,bounded,wall_s");
  for (const char* file : {"motion_capture_walk.trc", "subject01_walk1.trc", "arm26_elbow_flex.trc",
                           "Sample01_Eb015pi.c3d", "Sample02_pc_int.c3d",
                           "Sample26_Walking_Hybrid_1_1.c3d"}) {
    if (s.quick && std::string(file) != "arm26_elbow_flex.trc") continue;
    const std::string path = std::string(MME_TEST_DATA_DIR) + "/real/" + file;
    mme::Trajectory data = mme::readTrajectoryFile(path);
    data = mme::sliceFrames(data, 0, std::min(data.numFrames(), 300));
    const auto start = std::chrono::steady_clock::now();
    try {
      const mme::HeldOutSplit split = mme::splitHeldOut(data, mme::StructureOptions().held_out_share, std::string("structure_real ") + file);
      const mme::StructureResult r = selectStructureOnFitted(split, so);
      const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      const mme::StructureCandidate* chosen = nullptr;
      for (const mme::StructureCandidate& c : r.candidates)
        if (c.chosen) chosen = &c;
      double rms[4];
      const bool bounded = judgeUnseen(r.model, split, rms);
      const int full_params = 3 * r.candidate_bonds + 3;
      std::fprintf(g, "%s,%d,%d,%d,%d,%s,%d,%d,%d,%.6g,%.6g,%.6g,%.6g,%d,%.2f\n", file,
                   data.numMarkers(), data.numFrames(), r.candidate_bonds, full_params,
                   chosen->name.c_str(), chosen->bonds, chosen->bond_types, chosen->parameters,
                   rms[0], rms[1], rms[2], rms[3], bounded ? 1 : 0, wall_s);
      std::fflush(g);
      std::printf("structure: %s: %s, %d bonds, %d types, %d parameters (full candidate model %d); "
                  "10 frames ahead on held-out frames no choice saw: model %.2f mm, constant "
                  "velocity %.2f mm, constant acceleration %.2f mm; %.1f s\n", file,
                  chosen->name.c_str(), chosen->bonds, chosen->bond_types, chosen->parameters,
                  full_params, 1e3 * rms[0], 1e3 * rms[1], 1e3 * rms[2], wall_s);
    } catch (const mme::InputError& e) {
      std::printf("structure: %s: %s\n", file, e.what());
    }
  }
  std::fclose(g);
}

}  // namespace paper
