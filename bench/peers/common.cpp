// The helpers every bench_peers source shares (declared in common.h): time and load, number
// formatting, CSV writing and reading, the worker pool.
#include "common.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <thread>

#include "motion_model_estimation/core/error.h"

namespace peers {

double since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::string loadAverage() {
  std::ifstream f("/proc/loadavg");
  std::string a, b, c;
  f >> a >> b >> c;
  return a.empty() ? "?" : a + " " + b + " " + c;
}

std::string clean(std::string s) {
  std::replace(s.begin(), s.end(), ',', ';');
  std::replace(s.begin(), s.end(), '\n', ' ');
  return s;
}

std::string num(double x, const char* fmt) {
  if (!std::isfinite(x)) return "n/a";
  char b[64];
  std::snprintf(b, sizeof(b), fmt, x);
  return b;
}

std::FILE* openCsv(const Settings& s, const std::string& name, const char* header) {
  const std::string path = s.out + "/" + name;
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) throw mme::InputError(path + ": cannot write");
  std::fprintf(f, "%s\n", header);
  return f;
}

/// Runs jobs on `workers` threads (each job single-threaded), in list order.
void runPool(const std::vector<std::function<void()>>& jobs, int workers) {
  std::atomic<size_t> next{0};
  auto work = [&]() {
    for (size_t j = next++; j < jobs.size(); j = next++) jobs[j]();
  };
  std::vector<std::thread> pool;
  for (int w = 1; w < std::min<int>(workers, static_cast<int>(jobs.size())); ++w) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
}

std::mutex g_print_mutex;

std::string brief(const std::vector<RunResult>& runs) {
  std::string s;
  for (const RunResult& r : runs) {
    s += " " + r.method + ":";
    if (!r.applicable) s += "n/a";
    else s += num(r.errors.max, "%.2g") + "%/" + num(r.wall_s, "%.1f") + "s" +
              (r.estimator == mme::Estimator::kOutputError ? "/oe" : "");
  }
  return s;
}

double median(std::vector<double> v) {
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return !std::isfinite(x); }), v.end());
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

std::vector<Row> readCsv(const std::string& path) {
  std::vector<Row> rows;
  std::ifstream in(path);
  std::string line;
  if (!std::getline(in, line)) return rows;
  std::vector<std::string> header;
  auto split = [](const std::string& l) {
    std::vector<std::string> out;
    std::stringstream ss(l);
    std::string x;
    while (std::getline(ss, x, ',')) out.push_back(x);
    return out;
  };
  header = split(line);
  while (std::getline(in, line)) {
    const std::vector<std::string> v = split(line);
    Row r;
    for (size_t k = 0; k < header.size() && k < v.size(); ++k) r[header[k]] = v[k];
    rows.push_back(r);
  }
  return rows;
}

double toD(const Row& r, const std::string& key) {
  auto it = r.find(key);
  if (it == r.end() || it->second == "n/a" || it->second.empty()) return NAN;
  return std::atof(it->second.c_str());
}

}  // namespace peers
