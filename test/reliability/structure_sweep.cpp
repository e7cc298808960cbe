// structure_sweep: structure selection on windows of real captures, as a user's stream or a
// short file would give it (docs/reliability.md). Each capture is cut into windows of the given
// lengths at evenly spaced offsets; each window's markers become the particles and the
// structure is selected under a time limit. A run ends with a chosen level or with a clear
// refusal (InputError); anything else (another exception) is a failure. A crash or a sanitizer
// report ends the program itself: that is what the sweep is for.
//
//   structure_sweep [--max-time-s S] [--lengths 40,80,100,240] [--offsets N] [--csv OUT]
//                   CAPTURE.trc|.c3d ...
// Prints one line per run and a summary; exit 0 when every run chose or refused cleanly, 1 when
// one failed otherwise, 2 on bad arguments. Times are printed, not judged: the benchmark script
// (scripts/sweep-structure) reads them against the limit.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <string>
#include <vector>

#include "../../src/tools/cli_args.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/identification/structure/marker_model.h"
#include "motion_model_estimation/identification/structure/structure_selection.h"
#include "motion_model_estimation/io/trajectory_io.h"

namespace {

struct Options {
  double max_time_s = 20.0;
  std::vector<int> lengths = {40, 80, 100, 240};
  int offsets = 3;
  std::string csv;
  std::vector<std::string> captures;
};

Options parseArgs(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw mme::InputError(a + " needs a value");
      return argv[++i];
    };
    if (a == "--max-time-s") {
      const std::string v = value();
      char* end = nullptr;
      o.max_time_s = std::strtod(v.c_str(), &end);
      if (*end != '\0' || !(o.max_time_s >= 0.0)) throw mme::InputError("--max-time-s: '" + v + "' is not >= 0");
    } else if (a == "--lengths") {
      o.lengths = mme::parseCountList(value(), "--lengths", 1000000, "40,80,100,240");
    } else if (a == "--offsets") {
      const std::vector<int> n = mme::parseCountList(value(), "--offsets", 1000, "3");
      if (n.size() != 1) throw mme::InputError("--offsets takes one count");
      o.offsets = n[0];
    } else if (a == "--csv") {
      o.csv = value();
    } else if (!a.empty() && a[0] == '-') {
      throw mme::InputError("unknown option " + a);
    } else {
      o.captures.push_back(a);
    }
  }
  if (o.captures.empty()) throw mme::InputError("no capture given");
  return o;
}

struct Run {
  std::string capture;
  int first = 0, frames = 0, markers = 0;
  std::string outcome;  ///< "chosen", "refused", "failed"
  std::string detail;   ///< the chosen level, or the message
  bool cut = false;
  double seconds = 0.0;
};

std::string baseName(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

Run selectOn(const std::string& capture, const mme::Trajectory& data, int first, int frames,
             double max_time_s) {
  Run run;
  run.capture = baseName(capture);
  run.first = first;
  run.frames = frames;
  run.markers = data.numMarkers();
  const auto began = std::chrono::steady_clock::now();
  try {
    const mme::Trajectory window = mme::sliceFrames(data, first, frames);
    mme::StructureOptions options;
    options.identify.es.threads = 1;  // the same result on every machine
    options.max_wall_time_s = max_time_s;
    if (std::getenv("MME_SWEEP_VERBOSE"))  // each step with its time since the run began
      options.progress = [began](const std::string& line) {
        std::printf("  %7.3f s  %s\n",
                    std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count(),
                    line.c_str());
      };
    const mme::StructureResult r = mme::selectStructure(mme::markerModel(window), window, options);
    run.outcome = "chosen";
    for (const mme::StructureCandidate& c : r.candidates)
      if (c.chosen) run.detail = c.name + " (" + std::to_string(c.bonds) + " bonds)";
    run.cut = r.stopped_by_time;
  } catch (const mme::InputError& e) {
    run.outcome = "refused";
    run.detail = e.what();
  } catch (const std::exception& e) {
    run.outcome = "failed";
    run.detail = std::string("unexpected ") + e.what();
  }
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  return run;
}

void record(const Run& r, std::vector<Run>* runs) {
  std::printf("%-34s frames %4d+%-4d %2d markers  %-7s %6.1f s%s  %s\n", r.capture.c_str(), r.first,
              r.frames, r.markers, r.outcome.c_str(), r.seconds, r.cut ? " (cut)" : "", r.detail.c_str());
  std::fflush(stdout);
  runs->push_back(r);
}

std::string csvField(std::string text) {
  std::replace(text.begin(), text.end(), '"', '\'');
  return "\"" + text + "\"";
}

int sweep(const Options& o) {
  std::vector<Run> runs;
  std::printf("structure_sweep: time limit %.3g s per selection\n", o.max_time_s);
  for (const std::string& capture : o.captures) {
    mme::Trajectory data;
    try {
      data = mme::readTrajectoryFile(capture);
    } catch (const mme::InputError& e) {
      std::fprintf(stderr, "structure_sweep: %s\n", e.what());
      return 2;
    }
    for (int length : o.lengths) {
      const int total = data.numFrames();
      if (length > total) {
        Run r;
        r.capture = baseName(capture);
        r.frames = length;
        r.markers = data.numMarkers();
        r.outcome = "skipped";
        r.detail = "a window of " + std::to_string(length) + " frames cannot be cut from " +
                   std::to_string(total) + " frames";
        record(r, &runs);
        continue;
      }
      const int spread = total - length;
      int last_first = -1;
      for (int k = 0; k < o.offsets; ++k) {
        const int first = o.offsets > 1 ? static_cast<int>(static_cast<long>(spread) * k / (o.offsets - 1)) : 0;
        if (first == last_first) continue;
        last_first = first;
        record(selectOn(capture, data, first, length, o.max_time_s), &runs);
      }
    }
  }
  int chosen = 0, refused = 0, failed = 0, cut = 0, skipped = 0;
  double worst_ratio = 0.0;
  for (const Run& r : runs) {
    chosen += r.outcome == "chosen";
    refused += r.outcome == "refused";
    failed += r.outcome == "failed";
    skipped += r.outcome == "skipped";
    cut += r.cut;
    if (o.max_time_s > 0.0) worst_ratio = std::max(worst_ratio, r.seconds / o.max_time_s);
  }
  std::printf("structure_sweep: %zu runs: %d chosen (%d cut by the time limit), %d refused with a "
              "reason, %d failed, %d window(s) longer than their capture; longest run %.2fx the "
              "limit\n", runs.size() - skipped, chosen, cut, refused, failed, skipped, worst_ratio);
  if (!o.csv.empty()) {
    std::ofstream out(o.csv);
    out << "capture,first_frame,frames,markers,outcome,cut,seconds,limit_s,detail\n";
    for (const Run& r : runs)
      out << r.capture << "," << r.first << "," << r.frames << "," << r.markers << "," << r.outcome
          << "," << (r.cut ? 1 : 0) << "," << r.seconds << "," << o.max_time_s << ","
          << csvField(r.detail) << "\n";
    if (!out) {
      std::fprintf(stderr, "structure_sweep: cannot write %s\n", o.csv.c_str());
      return 2;
    }
  }
  return failed == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  try {
    options = parseArgs(argc, argv);
  } catch (const mme::InputError& e) {
    std::fprintf(stderr, "structure_sweep: %s\nusage: structure_sweep [--max-time-s S] [--lengths "
                 "40,80,100,240] [--offsets N] [--csv OUT] CAPTURE...\n", e.what());
    return 2;
  }
  return sweep(options);
}
