// The `online` experiment of bench_paper: the online estimator against the offline
// identification of the same window.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "common.h"
#include "experiments.h"
#include "motion_model_estimation/identification/structure/marker_model.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/identification/online/online_estimator.h"
#include "motion_model_estimation/io/trajectory_io.h"
#include "motion_model_estimation/scenes/random_object.h"
#include "motion_model_estimation/scenes/scenes.h"

namespace paper {

/// The online estimator against the offline identification of the same window (within
/// 2x once converged): frames fed at the data's rate, an update every 1/10 s of frames, then the
/// window stops and updates run until a refinement finished on it; the pipeline's identification
/// step on that window.
void onlineExperiment(const Settings& s) {
  std::FILE* f = openCsv(s.out_dir + "/online.csv",
                         "case,markers,unknowns,window_frames,online_estimator,online_cost_m2,"
                         "identify_estimator,identify_cost_m2,ratio,online_updates,identify_wall_s");
  struct Case {
    std::string name;
    Model model;
    mme::Trajectory data;
  };
  std::vector<Case> cases;
  {
    mme::RandomObjectSpec spec;  // the big soak model: 43 markers, 91 damped types
    spec.particles = 43;
    spec.bond_types = 91;
    spec.bonds = 91;
    spec.damping_max_nspm = 0.05;
    const Model truth = mme::makeRandomObject(spec);
    mme::Trajectory data = mme::simulateTrajectory(truth, 240, truth.frame_rate_hz);
    mme::addGaussianNoise(&data, 2e-4, 17);
    cases.push_back({"random43_noise0.2mm", forgetFreeValues(truth), data});
  }
  {
    const std::string path = std::string(MME_TEST_DATA_DIR) + "/real/motion_capture_walk.trc";
    const mme::Trajectory data = mme::readTrajectoryFile(path);
    cases.push_back({"motion_capture_walk", mme::markerModel(data, 91), data});
  }
  for (const Case& c : cases) {
    mme::OnlineEstimatorOptions o;
    o.window_frames = 100;
    o.es.threads = s.threads;
    mme::OnlineEstimator online(c.model, o);
    const int n = c.data.numMarkers();
    const int per_update = std::max(1, static_cast<int>(c.data.frame_rate_hz / 10.0));
    int updates = 0;
    for (int t = 0; t < c.data.numFrames(); ++t) {
      std::vector<Eigen::Vector3d> x(c.data.positions_m.begin() + t * n, c.data.positions_m.begin() + (t + 1) * n);
      std::vector<uint8_t> occluded(c.data.occluded.begin() + t * n, c.data.occluded.begin() + (t + 1) * n);
      online.addFrame(c.data.times_s[t], x, occluded);
      if ((t + 1) % per_update == 0 && online.update()) ++updates;
    }
    // The window stands still: refinements and output-error fits (each at most ~refine_max_s,
    // warm from the last) go on until the estimate's cost stops falling (1 % over 3 rounds).
    std::vector<double> costs;
    for (int k = 0; k < 30; ++k) {
      online.waitForRefinement();
      if (online.update()) ++updates;
      costs.push_back(online.estimate().global_cost);
      const size_t m = costs.size();
      if (m > 4 && costs[m - 4] - costs[m - 1] <= 0.01 * costs[m - 4]) break;
    }
    online.waitForRefinement();
    if (online.update()) ++updates;
    const mme::Estimate e = online.estimate();
    const mme::Trajectory window = online.window();
    mme::IdentifyOptions io = mme::identifyOptionsFor(mme::Preset::kDefault);
    io.es.threads = s.threads;
    io.estimate_std = false;
    Model model = c.model;
    if (!(model.frame_rate_hz > 0)) model.frame_rate_hz = window.frame_rate_hz;
    const mme::IdentifyResult r = mme::identifyPassive(model, window, identifyStep(io));
    const double ratio = e.global_cost / r.global_cost;
    std::fprintf(f, "%s,%d,%zu,%d,%s,%.6g,%s,%.6g,%.4g,%d,%.2f\n", c.name.c_str(), n,
                 r.parameters.size(), window.numFrames(), mme::estimatorName(e.estimator), e.global_cost,
                 mme::estimatorName(r.estimator), r.global_cost, ratio, updates, r.wall_time_s);
    std::fflush(f);
    std::printf("online: %s (%d markers, %zu unknowns): online %s cost %.4g m^2, identify %s cost "
                "%.4g m^2 on the same %d frames: ratio %.3g (%d updates)\n", c.name.c_str(), n,
                r.parameters.size(), mme::estimatorName(e.estimator), e.global_cost, mme::estimatorName(r.estimator),
                r.global_cost, window.numFrames(), ratio, updates);
  }
  std::fclose(f);
}

}  // namespace paper
