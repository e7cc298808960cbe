// Shared by the bench_peers sources: the run's settings (from the command line), the clock and
// load average, the formatting and CSV helpers of the benchmark parts and the summary, the
// worker pool and the thread-safe progress line.
#pragma once

#include <chrono>
#include <cstdio>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "methods.h"
#include "problem.h"

namespace peers {

using bench::Budget;
using bench::Problem;
using bench::RunResult;
using Clock = std::chrono::steady_clock;

/// Seconds since t0.
double since(Clock::time_point t0);

/// The first three fields of /proc/loadavg ("?" when unreadable).
std::string loadAverage();

struct Settings {
  std::string out = "docs/bench";
  bool quick = false;
  bool summary_only = false;
  int workers = 2;
  int seeds = 10;
  int seeds_200 = 3;  ///< seeds of the 200-unknown setting (see the summary's notes)
  std::string only;   ///< speed,map,scaling (empty = all)
  std::vector<std::string> methods;
  std::vector<std::string> scenes;  ///< speed part: these scenes only (empty = all)
  int speed_seeds = 0;              ///< speed part: seeds per scene (0 = each scene's own)
  std::vector<std::string> axes;    ///< map part: these axes only (empty = all)
  bool wants(const std::string& part) const {
    return only.empty() || ("," + only + ",").find("," + part + ",") != std::string::npos;
  }
};

/// Replaces commas (CSV separator) in free text.
std::string clean(std::string s);

/// x formatted with fmt; "n/a" when not finite.
std::string num(double x, const char* fmt = "%.6g");

/// Opens `name` in the output directory for writing and writes its header line.
std::FILE* openCsv(const Settings& s, const std::string& name, const char* header);

/// Runs jobs on `workers` threads (each job single-threaded), in list order.
void runPool(const std::vector<std::function<void()>>& jobs, int workers);

extern std::mutex g_print_mutex;

/// printf to stdout, one line at a time from any worker, flushed.
template <typename... A>
void say(const char* fmt, A... args) {
  std::lock_guard<std::mutex> lock(g_print_mutex);
  std::printf(fmt, args...);
  std::fflush(stdout);
}

/// The methods' outcomes in one progress line: max error / wall time (or n/a).
std::string brief(const std::vector<RunResult>& runs);

/// The median of the finite values (NaN when there is none).
double median(std::vector<double> v);

/// One line of a CSV file read back: column name -> text.
using Row = std::map<std::string, std::string>;

/// A CSV file with a header line as rows (empty when missing).
std::vector<Row> readCsv(const std::string& path);

/// The column as a number (NaN when missing, empty or "n/a").
double toD(const Row& r, const std::string& key);

}  // namespace peers
