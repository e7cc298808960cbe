// Throughput of the global one-step cost (the evolution strategy's hot loop).
//
//   bench_throughput [--csv FILE] [--seconds S] [--in-code-scenes] [--case NAME]
//
// Cases: provot_cloth (scene, 100 simulated frames), provot_cloth_static (its single-frame
// equilibrium data set), fluid_jet (scene, 200 frames), linear_cloth64 (64x64 cloth of plain
// linear springs, no flexion, no conditions: the raw spring kernel). --in-code-scenes uses
// this file's own approximations of the two scenes instead of makeScene().
// For each case and 1 and 2 threads: cost evaluations/s, bond evaluations/s, per core and
// ns per bond; then a CSV block "case,threads,bond_evals_per_s,per_core".
#include <chrono>
#include <cmath>
#include <ctime>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "motion_model_estimation/core/model_builder.h"
#include "motion_model_estimation/core/short_term_cost.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/scenes/scenes.h"

namespace {

using mme::Model;
using Vec = Eigen::Vector3d;

/// A free parameter with bounds [v/10, 10 v].
mme::Param freeValue(double v) { return mme::boundedParam(v, v / 10.0, v * 10.0); }

/// Square cloth of side n, period 1/(n-1)... in metres; spring types added by the caller.
/// `types`: struct_h, struct_v, shear_d1, shear_d2, flex_h, flex_v (-1 = not installed).
Model clothModel(int n, double period_m, const int* types, bool flexion) {
  Model m;
  m.frame_rate_hz = 100.0;
  m.gravity_mps2[2] = mme::valueParam(-9.81);
  const double mass = 0.1 / (n * n);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c)
      mme::addParticle(&m, Vec(c * period_m, -r * period_m, 0.0),
                       {"", mass, Vec::Zero(), r == 0 && (c == 0 || c == n - 1)});
  auto id = [n](int r, int c) { return r * n + c; };
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      if (c + 1 < n) mme::addBond(&m, types[0], id(r, c), id(r, c + 1));
      if (r + 1 < n) mme::addBond(&m, types[1], id(r, c), id(r + 1, c));
      if (r + 1 < n && c + 1 < n) {
        mme::addBond(&m, types[2], id(r, c), id(r + 1, c + 1));
        mme::addBond(&m, types[3], id(r, c + 1), id(r + 1, c));
      }
      if (flexion && c + 2 < n) mme::addBond(&m, types[4], id(r, c), id(r, c + 2));
      if (flexion && r + 2 < n) mme::addBond(&m, types[5], id(r, c), id(r + 2, c));
    }
  return m;
}

mme::BondType springType(const std::string& name, double k, double rest, double damping,
                         double k_nl, bool clamped) {
  mme::BondType t;
  t.name = name;
  t.kind = mme::BondKind::kSpring;
  t.param(mme::kStiffness) = freeValue(k);
  t.param(mme::kRestLength) = freeValue(rest);
  if (damping > 0) t.param(mme::kDamping) = mme::valueParam(damping);
  if (k_nl > 0) t.param(mme::kStiffnessNl) = freeValue(k_nl);
  if (clamped) t.param(mme::kMaxElongation) = freeValue(0.1);
  return t;
}

/// In-code stand-in for the provot_cloth scene: 17x17, 6 spring types, 2 corners fixed.
Model inCodeCloth() {
  const double p = 1.5 / 16;
  Model proto;
  const char* names[6] = {"struct_h", "struct_v", "shear_d1", "shear_d2", "flex_h", "flex_v"};
  const double rest[6] = {p, p, p * std::sqrt(2.0), p * std::sqrt(2.0), 2 * p, 2 * p};
  const double k[6] = {4, 4, 2, 2, 1, 1};
  const int types[6] = {0, 1, 2, 3, 4, 5};
  Model m = clothModel(17, p, types, true);
  m.substeps = 20;
  for (int t = 0; t < 6; ++t)
    m.bond_types.push_back(springType(names[t], k[t], rest[t], 0.004, 100.0 * k[t], t < 2));
  return m;
}

/// In-code stand-in for fluid_jet: ~300 gas particles on a unit grid, 60 fast jet particles.
Model inCodeFluid() {
  Model m;
  m.frame_rate_hz = 25.0;
  m.substeps = 10;
  for (int r = 0; r < 15; ++r)
    for (int c = 0; c < 20; ++c) mme::addParticle(&m, Vec(c, r, 0), {"", 1.0, Vec::Zero(), false, "gas"});
  for (int c = 0; c < 20; ++c)
    for (int w = 0; w < 3; ++w)
      mme::addParticle(&m, Vec(-1.5 - c, 6.0 + w, 0), {"", 1.0, Vec(10, 0, 0), false, "jet"});
  auto type = [&](const std::string& name, double k, double rest, double c, double c_nl,
                  double max_d) {
    mme::BondType t;
    t.name = name;
    t.kind = mme::BondKind::kSpring;
    if (k > 0) t.param(mme::kStiffness) = freeValue(k);
    if (rest > 0) t.param(mme::kRestLength) = mme::valueParam(rest);
    if (c > 0) t.param(mme::kDamping) = freeValue(c);
    if (c_nl > 0) t.param(mme::kDampingNl) = freeValue(c_nl);
    t.param(mme::kMaxDistance) = freeValue(max_d);
    t.param(mme::kMaxDistance).min = max_d / 2;
    t.param(mme::kMaxDistance).max = max_d * 2;
    m.bond_types.push_back(t);
    return static_cast<int>(m.bond_types.size()) - 1;
  };
  const int gv = type("gas_visc", 0, 0, 2.5, 1.25, 1.5);
  const int jv = type("jet_visc", 0, 0, 4.0, 2.0, 2.0);
  const int el = type("elast", 2.0, 1.1, 0, 0, 1.1);
  m.interactions = {{gv, "gas", "gas"}, {jv, "jet", "gas"}, {jv, "jet", "jet"},
                    {el, "gas", "gas"}, {el, "gas", "jet"}, {el, "jet", "jet"}};
  return m;
}

/// 64x64 cloth of linear springs only (structural + shear), one substep: the raw kernel.
Model linearCloth64() {
  const double p = 0.02;
  const int types[6] = {0, 0, 1, 1, -1, -1};
  Model m = clothModel(64, p, types, false);
  m.bond_types.push_back(springType("struct", 40.0, p, 0, 0, false));
  m.bond_types.push_back(springType("shear", 20.0, p * std::sqrt(2.0), 0, 0, false));
  return m;
}

struct Case {
  std::string name;
  Model model;
  mme::Trajectory data;
};

struct Result {
  std::string name;
  int threads;
  double evals_per_s, bond_evals_per_s, per_core, ns_per_bond, per_cpu_s;
};

Result measure(const Case& c, const mme::ShortTermCost& cost, int threads, double seconds) {
  const std::vector<double> values = mme::getValues(c.model, cost.freeParameters());
  std::vector<double> local;
  auto once = [&]() {
    return threads == 1 ? cost.evaluate(values, &local)
                        : cost.evaluateParallel(values, &local, threads);
  };
  using Clock = std::chrono::steady_clock;
  volatile double sink = once();  // warm-up: first-touch of scratch buffers
  // Calibrate, then run the main timed loop for about `seconds`.
  auto t0 = Clock::now();
  long calls = 0;
  while (std::chrono::duration<double>(Clock::now() - t0).count() < 0.1) {
    sink = sink + once();
    ++calls;
  }
  const double per_call = std::chrono::duration<double>(Clock::now() - t0).count() / calls;
  const long reps = std::max(1L, static_cast<long>(seconds / per_call));
  t0 = Clock::now();
  const std::clock_t cpu0 = std::clock();
  for (long r = 0; r < reps; ++r) sink = sink + once();
  const double elapsed = std::chrono::duration<double>(Clock::now() - t0).count();
  const double cpu_s = static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC;
  (void)sink;
  Result res;
  res.name = c.name;
  res.threads = threads;
  res.evals_per_s = reps / elapsed;
  // What the loop really computes at these values (candidates beyond max_distance are skipped).
  const double bond_evals = static_cast<double>(cost.bondEvaluationsFor(values));
  res.bond_evals_per_s = res.evals_per_s * bond_evals;
  res.per_core = res.bond_evals_per_s / threads;
  res.ns_per_bond = 1e9 / res.per_core;
  // Process CPU time of all threads: insensitive to other load time-slicing the cores.
  res.per_cpu_s = cpu_s > 0 ? reps * bond_evals / cpu_s : 0;
  return res;
}

}  // namespace

int main(int argc, char** argv) {
  std::string csv_path, only;
  double seconds = 1.5;
  bool in_code = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--csv" && i + 1 < argc) {
      csv_path = argv[++i];
    } else if (a == "--seconds" && i + 1 < argc) {
      seconds = std::atof(argv[++i]);
    } else if (a == "--in-code-scenes") {
      in_code = true;
    } else if (a == "--case" && i + 1 < argc) {
      only = argv[++i];
    } else {
      std::cerr << "usage: bench_throughput [--csv FILE] [--seconds S] [--in-code-scenes] "
                   "[--case NAME]\n";
      return 2;
    }
  }

  std::vector<Case> cases;
  auto wanted = [&](const std::string& n) { return only.empty() || only == n; };
  try {
    if (wanted("provot_cloth") || wanted("provot_cloth_static")) {
      mme::Scene scene;
      if (in_code) {
        scene.model = inCodeCloth();
      } else {
        scene = mme::makeScene("provot_cloth");
      }
      if (wanted("provot_cloth"))
        cases.push_back({"provot_cloth", scene.model,
                         mme::simulateTrajectory(scene.model, 100, scene.model.frame_rate_hz)});
      if (wanted("provot_cloth_static") && scene.reference_data.numFrames() == 1)
        cases.push_back({"provot_cloth_static", scene.model, scene.reference_data});
    }
    if (wanted("fluid_jet")) {
      const Model m = in_code ? inCodeFluid() : mme::makeScene("fluid_jet").model;
      cases.push_back({"fluid_jet", m, mme::simulateTrajectory(m, 200, m.frame_rate_hz)});
    }
    if (wanted("linear_cloth64")) {
      const Model m = linearCloth64();
      cases.push_back({"linear_cloth64", m, mme::simulateTrajectory(m, 20, m.frame_rate_hz)});
    }
  } catch (const std::exception& e) {
    std::cerr << "bench_throughput: " << e.what() << "\n";
    return 1;
  }

  std::vector<Result> results;
  std::printf("%-20s %3s %10s %14s %14s %9s %14s  %s\n", "case", "thr", "evals/s",
              "bond evals/s", "per core", "ns/bond", "per cpu-s", "(bond evals/call, terms)");
  for (const Case& c : cases) {
    const mme::ShortTermCost cost(c.model, c.data);
    // Frames are what evaluateParallel splits: a single-frame data set runs on one thread.
    const int frames = std::max(1, c.data.numFrames() - 2);
    for (int threads : {1, 2}) {
      const int used = std::min(threads, frames);
      if (threads > 1 && used == 1) {
        std::printf("%-20s %3d  (one frame: evaluateParallel runs on one thread; skipped)\n",
                    c.name.c_str(), threads);
        continue;
      }
      const Result r = measure(c, cost, used, seconds);
      results.push_back(r);
      std::printf("%-20s %3d %10.1f %12.2f M %12.2f M %9.2f %12.2f M  (%llu, %llu)\n",
                  r.name.c_str(), r.threads, r.evals_per_s, r.bond_evals_per_s * 1e-6,
                  r.per_core * 1e-6, r.ns_per_bond, r.per_cpu_s * 1e-6,
                  static_cast<unsigned long long>(
                      cost.bondEvaluationsFor(mme::getValues(c.model, cost.freeParameters()))),
                  static_cast<unsigned long long>(cost.termCount()));
      std::fflush(stdout);
    }
  }
  std::printf("\nper core = bond evals/s / threads (wall clock); per cpu-s = bond evals per second "
              "of process CPU time (robust to other load on the machine).\n");
  std::ostringstream csv;
  csv << "case,threads,bond_evals_per_s,per_core,per_cpu_s\n";
  for (const Result& r : results)
    csv << r.name << "," << r.threads << "," << std::llround(r.bond_evals_per_s) << ","
        << std::llround(r.per_core) << "," << std::llround(r.per_cpu_s) << "\n";
  std::printf("\n%s", csv.str().c_str());
  if (!csv_path.empty()) {
    std::ofstream out(csv_path);
    out << csv.str();
    if (!out) {
      std::cerr << "bench_throughput: cannot write " << csv_path << "\n";
      return 1;
    }
  }
  return 0;
}
