// soak_publisher: drives the estimator_node soak test (scripts/soak, docs/reliability.md).
//
//   soak_publisher --write-model PATH [--particles 43] [--bonds 86] [--bond-types 12]
//                  [--damping-max C] [--seed 1]
//       writes a random floating object (mme::makeRandomObject, 120 Hz) as a model file whose
//       free parameters carry their true values, and exits. --damping-max > 0 gives every type a
//       free damping too (the big soak model: 91 bonds of 91 types, 273 free parameters).
//   soak_publisher --model PATH --minutes M --estimator-pid PID --csv FILE --summary FILE
//                  [--estimator NS (/estimator)] [--clip-seconds 60] [--seed 1]
//       simulates a clip of the model and publishes it as MarkerFrame on `markers` at the
//       model's rate, looping like `rosbag play --loop` (the stamps jump back at each loop),
//       with random occlusions, NaN positions, shuffled/missing/unknown marker names, bursts
//       (0.5 s of frames held back and sent at once) and a few deliberately invalid frames
//       (duplicates, stale stamps, mismatched array lengths). Every 5 s it samples the
//       estimator's VmRSS (/proc/PID/status) and its ~stats and ~estimate into the CSV.
//       At the end it compares the frames published valid with the node's accepted count and
//       the invalid ones with its rejected count, checks that the RSS stayed flat and the
//       estimate rate steady, writes the summary and exits 0 only when all hold. The longest
//       gap between estimate updates (~stats max_update_gap_ms, max_update_gap_10s_ms) is
//       reported against the 0.5 s target but is not part of the verdict.
#include <ros/ros.h>
#include <std_msgs/String.h>
#include <unistd.h>
#include <visualization_msgs/MarkerArray.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <limits>
#include <mutex>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "motion_model_estimation/MarkerFrame.h"
#include "motion_model_estimation/ModelEstimate.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/io/model_yaml.h"
#include "motion_model_estimation/scenes/random_object.h"

namespace {

struct Args {
  std::string write_model, model, estimator = "/estimator", csv, summary;
  int particles = 43;
  int bonds = 0;        // 0 = 2 x particles
  int bond_types = 12;
  double damping_max_nspm = 0.0;
  double minutes = 10.0, clip_seconds = 60.0;
  long estimator_pid = 0;
  uint64_t seed = 1;
};

long readRssKb(long pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::atol(line.c_str() + 6);
  return -1;  // process gone
}

/// utime + stime of a process in seconds (/proc/PID/stat), -1 when it is gone.
double readCpuSeconds(long pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t close = text.rfind(')');  // the command name may hold spaces
  if (close == std::string::npos) return -1.0;
  std::istringstream fields(text.substr(close + 2));
  std::string field;
  double utime = 0, stime = 0;
  for (int k = 3; k <= 15 && fields >> field; ++k) {  // fields 14 and 15: utime, stime
    if (k == 14) utime = std::atof(field.c_str());
    if (k == 15) stime = std::atof(field.c_str());
  }
  return (utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

/// Where the value of "key=value" starts in the ~stats string (nullptr when absent).
const char* statField(const std::string& stats, const std::string& key) {
  const std::string k = key + "=";
  size_t p = stats.find(k);
  while (p != std::string::npos && p > 0 && stats[p - 1] != ' ') p = stats.find(k, p + 1);
  return p == std::string::npos ? nullptr : stats.c_str() + p + k.size();
}

/// "key=value" from the ~stats string as a double (NaN when absent).
double statDouble(const std::string& stats, const std::string& key) {
  const char* v = statField(stats, key);
  return v ? std::atof(v) : std::numeric_limits<double>::quiet_NaN();
}

/// "key=value" from the ~stats string (-1 when absent).
long long statValue(const std::string& stats, const std::string& key) {
  const char* v = statField(stats, key);
  return v ? std::atoll(v) : -1;
}

struct Observed {
  std::mutex mutex;
  std::string stats;
  uint64_t estimates = 0;
  uint64_t marker_arrays = 0;
  uint32_t generation = 0;
  double global_cost = std::numeric_limits<double>::quiet_NaN();
};

int writeModel(const Args& a) {
  mme::RandomObjectSpec spec;
  spec.particles = a.particles;
  spec.bond_types = a.bond_types;
  spec.bonds = a.bonds > 0 ? a.bonds : 2 * a.particles;
  spec.damping_max_nspm = a.damping_max_nspm;
  spec.frame_rate_hz = 120.0;
  spec.seed = a.seed;
  mme::writeModelFile(a.write_model, mme::makeRandomObject(spec));
  std::printf("soak_publisher: wrote %s (%d particles, %d bonds, %d bond types)\n",
              a.write_model.c_str(), spec.particles, spec.bonds, spec.bond_types);
  return 0;
}

int run(const Args& a) {
  const mme::Model model = mme::loadModelFile(a.model);
  const double rate_hz = model.frame_rate_hz;
  const int clip_frames = static_cast<int>(a.clip_seconds * rate_hz);
  const mme::Trajectory clip = mme::simulateTrajectory(model, clip_frames, rate_hz);
  const int n = clip.numMarkers();

  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<motion_model_estimation::MarkerFrame>("markers", 1000);
  Observed obs;
  ros::Subscriber stats_sub = nh.subscribe<std_msgs::String>(
      a.estimator + "/stats", 10, [&](const std_msgs::String::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(obs.mutex);
        obs.stats = m->data;
      });
  ros::Subscriber est_sub = nh.subscribe<motion_model_estimation::ModelEstimate>(
      a.estimator + "/estimate", 100,
      [&](const motion_model_estimation::ModelEstimate::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(obs.mutex);
        ++obs.estimates;
        obs.generation = m->generation;
        obs.global_cost = m->global_cost;
      });
  // Subscribing to ~markers makes the node build them (it does no marker work otherwise): the
  // latency from a frame's arrival to the markers built from it is measured that way.
  ros::Subscriber markers_sub = nh.subscribe<visualization_msgs::MarkerArray>(
      a.estimator + "/markers", 10, [&](const visualization_msgs::MarkerArray::ConstPtr&) {
        std::lock_guard<std::mutex> lock(obs.mutex);
        ++obs.marker_arrays;
      });
  ros::AsyncSpinner spinner(1);
  spinner.start();

  // Wait for the estimator to subscribe (up to 30 s).
  for (int k = 0; k < 300 && pub.getNumSubscribers() == 0 && ros::ok(); ++k)
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  if (pub.getNumSubscribers() == 0) {
    std::fprintf(stderr, "soak_publisher: nobody subscribes to %s\n", pub.getTopic().c_str());
    return 1;
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(500));

  std::ofstream csv(a.csv);
  csv << "elapsed_s,rss_kb,published_valid,published_invalid,accepted,rejected,estimates,"
         "generation,global_cost,cpu_percent,latency_p50_ms,latency_p99_ms,marker_arrays,"
         "max_update_gap_ms,max_update_gap_10s_ms\n";
  std::mt19937_64 rng(a.seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<std::string> names = clip.marker_names;
  const ros::Time base = ros::Time::now();
  uint64_t valid = 0, invalid = 0, frame = 0, loops = 0;
  std::vector<motion_model_estimation::MarkerFrame> held;  // a burst being held back
  bool holding = false;
  uint64_t burst_end = 0, bursts = 0;
  const auto start = std::chrono::steady_clock::now();
  const uint64_t total_frames = static_cast<uint64_t>(a.minutes * 60.0 * rate_hz);
  double next_sample_s = 0.0;
  struct Sample {
    double t;
    long rss;
    uint64_t estimates;
    double cpu_percent, p50_ms, p99_ms, gap10_ms;
  };
  std::vector<Sample> samples;
  motion_model_estimation::MarkerFrame last;
  bool alive = true;

  double last_cpu_s = readCpuSeconds(a.estimator_pid), last_cpu_t = 0.0;
  auto sample = [&](double t) {
    const long rss = readRssKb(a.estimator_pid);
    if (rss < 0) alive = false;
    const double cpu_s = readCpuSeconds(a.estimator_pid);
    const double cpu_percent =
        t > last_cpu_t ? 100.0 * (cpu_s - last_cpu_s) / (t - last_cpu_t) : 0.0;
    last_cpu_s = cpu_s;
    last_cpu_t = t;
    std::lock_guard<std::mutex> lock(obs.mutex);
    csv << std::fixed;
    csv.precision(1);
    csv << t << ',' << rss << ',' << valid << ',' << invalid << ','
        << statValue(obs.stats, "accepted") << ',' << statValue(obs.stats, "rejected") << ','
        << obs.estimates << ',' << obs.generation << ',';
    csv.precision(6);
    csv << std::scientific << obs.global_cost << std::defaultfloat;
    const double p50 = statDouble(obs.stats, "latency_p50_ms");
    const double p99 = statDouble(obs.stats, "latency_p99_ms");
    const double gap_ms = statDouble(obs.stats, "max_update_gap_ms");
    const double gap10_ms = statDouble(obs.stats, "max_update_gap_10s_ms");
    csv.precision(3);
    csv << std::fixed << ',' << cpu_percent << ',' << p50 << ',' << p99 << ','
        << obs.marker_arrays << ',' << gap_ms << ',' << gap10_ms << '\n';
    csv.flush();
    samples.push_back({t, rss, obs.estimates, cpu_percent, p50, p99, gap10_ms});
  };

  for (frame = 0; frame < total_frames && ros::ok() && alive; ++frame) {
    const std::chrono::duration<double> due(static_cast<double>(frame) / rate_hz);
    std::this_thread::sleep_until(start + due);
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (elapsed >= next_sample_s) {
      sample(next_sample_s);
      next_sample_s += 5.0;
    }
    const int t = static_cast<int>(frame % clip_frames);
    if (t == 0 && frame > 0) ++loops;  // the stamps jump back by the clip length
    motion_model_estimation::MarkerFrame msg;
    msg.header.stamp = base + ros::Duration(t / rate_hz);
    msg.header.frame_id = model.frame_id;
    msg.frame_number = static_cast<uint32_t>(t);
    std::vector<int> order(n);
    for (int i = 0; i < n; ++i) order[i] = i;
    if (u(rng) < 0.05) std::shuffle(order.begin(), order.end(), rng);  // another marker order
    if (u(rng) < 0.03) order.resize(n - 1 - static_cast<int>(u(rng) * 3));  // markers missing
    bool any_occluded = false;
    std::vector<uint8_t> occluded;
    for (int i : order) {
      geometry_msgs::Point p;
      const Eigen::Vector3d& x = clip.position(t, i);
      p.x = x.x();
      p.y = x.y();
      p.z = x.z();
      if (u(rng) < 0.01) p.y = std::numeric_limits<double>::quiet_NaN();  // a NaN sample
      const bool occ = u(rng) < 0.02;                                     // an occlusion
      any_occluded = any_occluded || occ;
      msg.names.push_back(names[i]);
      msg.positions.push_back(p);
      occluded.push_back(occ);
    }
    if (u(rng) < 0.02) {  // a marker the model does not know: ignored, the frame is valid
      msg.names.push_back("stray");
      msg.positions.emplace_back();
      occluded.push_back(0);
    }
    if (any_occluded) msg.occluded = occluded;

    // Bursts: about every 15 s, 0.5 s of frames are held back and then sent at once.
    if (!holding && t > 10 && t + 60 < clip_frames && u(rng) < 1.0 / (15.0 * rate_hz)) {
      holding = true;
      burst_end = frame + static_cast<uint64_t>(0.5 * rate_hz);
      ++bursts;
    }
    std::vector<motion_model_estimation::MarkerFrame> out;
    if (holding) {
      held.push_back(msg);
      if (frame >= burst_end) {
        out.swap(held);
        holding = false;
      }
    } else {
      out.push_back(msg);
    }
    for (const auto& m : out) {
      pub.publish(m);
      ++valid;
      last = m;
    }
    // Deliberately invalid frames (expected to be rejected), never inside a burst.
    if (!holding && !out.empty() && u(rng) < 0.005) {
      motion_model_estimation::MarkerFrame bad = last;
      const double kind = u(rng);
      if (kind < 0.25) {
        // duplicate: same stamp again
      } else if (kind < 0.5) {
        bad.header.stamp = last.header.stamp - ros::Duration(3.0 / rate_hz);  // stale
      } else if (kind < 0.75) {
        bad.positions.pop_back();  // names and positions differ in length
      } else {
        bad.occluded.assign(bad.positions.size() + 2, 0);  // occluded of the wrong length
      }
      pub.publish(bad);
      ++invalid;
    }
  }
  const double run_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  // Let the last frames and one ~stats period arrive.
  long long accepted = -1, rejected = -1;
  for (int k = 0; k < 100 && alive; ++k) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    std::lock_guard<std::mutex> lock(obs.mutex);
    accepted = statValue(obs.stats, "accepted");
    rejected = statValue(obs.stats, "rejected");
    if (k >= 15 && accepted == static_cast<long long>(valid) &&
        rejected == static_cast<long long>(invalid))
      break;
  }
  sample(run_s);
  alive = alive && readRssKb(a.estimator_pid) > 0;

  // RSS flat: from a quarter of the run (after the warm-up) to the end.
  long rss_quarter = -1, rss_first = samples.empty() ? -1 : samples.front().rss;
  for (const Sample& s : samples)
    if (s.t >= 0.25 * run_s) {
      rss_quarter = s.rss;
      break;
    }
  const long rss_end = samples.empty() ? -1 : samples.back().rss;
  const long growth_kb = rss_end - rss_quarter;
  const bool rss_flat = rss_quarter > 0 && growth_kb <= std::max(2048L, rss_quarter / 50);
  // Estimate rate: estimates per minute (after the first minute), min and max.
  std::vector<double> per_min;
  for (size_t k = 0; k < samples.size(); ++k)
    for (size_t j = k + 1; j < samples.size(); ++j)
      if (samples[j].t - samples[k].t >= 60.0 - 1e-6) {
        if (samples[k].t >= 60.0 && static_cast<int>(samples[k].t) % 60 == 0)
          per_min.push_back(double(samples[j].estimates - samples[k].estimates) * 60.0 /
                            (samples[j].t - samples[k].t));
        break;
      }
  double rate_min = 0, rate_max = 0, rate_mean = 0;
  if (!per_min.empty()) {
    rate_min = *std::min_element(per_min.begin(), per_min.end());
    rate_max = *std::max_element(per_min.begin(), per_min.end());
    for (double r : per_min) rate_mean += r / per_min.size();
  }
  const bool rate_steady = per_min.empty() || (rate_min > 0 && rate_min >= 0.5 * rate_mean);
  const bool frames_ok = accepted == static_cast<long long>(valid);
  const bool rejects_ok = rejected == static_cast<long long>(invalid);
  const bool ok = alive && frames_ok && rejects_ok && rss_flat && rate_steady;
  // CPU and latency after the warm-up (the first 5 s sample is the start-up).
  double cpu_mean = 0, cpu_max = 0, p50_worst = 0, p99_worst = 0, p99_mean = 0;
  int n_after = 0;
  for (const Sample& s : samples)
    if (s.t >= 10.0 && std::isfinite(s.p99_ms)) {
      cpu_mean += s.cpu_percent;
      cpu_max = std::max(cpu_max, s.cpu_percent);
      p50_worst = std::max(p50_worst, s.p50_ms);
      p99_worst = std::max(p99_worst, s.p99_ms);
      p99_mean += s.p99_ms;
      ++n_after;
    }
  if (n_after > 0) {
    cpu_mean /= n_after;
    p99_mean /= n_after;
  }
  // Gaps between estimate updates: the node's figure over the whole run (at the end), and the
  // longest gap of each 10 s (every gap is seen by a 5 s sample within 10 s of its end).
  double gap_run_ms = std::numeric_limits<double>::quiet_NaN();
  {
    std::lock_guard<std::mutex> lock(obs.mutex);
    gap_run_ms = statDouble(obs.stats, "max_update_gap_ms");
  }
  std::vector<double> gaps10;
  for (const Sample& s : samples)
    if (s.t >= 10.0 && std::isfinite(s.gap10_ms)) gaps10.push_back(s.gap10_ms);
  double gap10_median = std::numeric_limits<double>::quiet_NaN(), gap10_worst = gap10_median;
  if (!gaps10.empty()) {
    std::sort(gaps10.begin(), gaps10.end());
    gap10_median = gaps10[gaps10.size() / 2];
    gap10_worst = gaps10.back();
  }
  const double kGapTargetMs = 500.0;

  std::ostringstream s;
  s << "soak: " << run_s / 60.0 << " min at " << rate_hz << " Hz, " << n << " markers, "
    << model.bonds.size() << " bonds, clip " << a.clip_seconds << " s looped " << loops
    << " times (clock jumps back), " << bursts << " bursts\n"
    << "estimator alive at the end: " << (alive ? "yes" : "NO") << "\n"
    << "frames published valid: " << valid << ", accepted by the node: " << accepted
    << (frames_ok ? " (none lost)" : " (MISMATCH)") << "\n"
    << "frames published invalid: " << invalid << ", rejected by the node: " << rejected
    << (rejects_ok ? "" : " (MISMATCH)") << "\n"
    << "VmRSS: " << rss_first << " kB at start, " << rss_quarter << " kB at 1/4, " << rss_end
    << " kB at the end (growth after warm-up " << growth_kb << " kB"
    << (rss_flat ? ", flat)" : ", GROWING)") << "\n"
    << "estimates per minute (after the first): min " << rate_min << ", mean " << rate_mean
    << ", max " << rate_max << (rate_steady ? " (steady)" : " (NOT steady)") << " = "
    << rate_mean / 60.0 << " Hz\n"
    << "estimator_node CPU (utime + stime, % of one core, 5 s samples after 10 s): mean "
    << cpu_mean << ", max " << cpu_max << "\n"
    << "latency frame arrival -> ~markers built from it (last 1024 frames at each 5 s sample): "
    << "p50 worst " << p50_worst << " ms, p99 mean " << p99_mean << " ms, p99 worst "
    << p99_worst << " ms\n"
    << "longest gap between estimate updates (~stats max_update_gap_ms): " << gap_run_ms
    << " ms over the run; longest per 10 s (5 s samples after 10 s): median " << gap10_median
    << " ms, worst " << gap10_worst << " ms; target <= " << kGapTargetMs << " ms: "
    << (gap_run_ms <= kGapTargetMs ? "met" : "NOT met") << " (reported, not in the verdict)\n";
  {
    std::lock_guard<std::mutex> lock(obs.mutex);
    s << "last estimate: generation " << obs.generation << ", global cost " << obs.global_cost
      << " m^2; last ~stats: " << obs.stats << "\n";
  }
  s << (ok ? "SOAK PASSED" : "SOAK FAILED") << "\n";
  std::printf("%s", s.str().c_str());
  if (!a.summary.empty()) std::ofstream(a.summary) << s.str();
  spinner.stop();
  return ok ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  Args a;
  for (int k = 1; k < argc; ++k) {
    const std::string o = argv[k];
    auto next = [&]() -> std::string {
      if (k + 1 >= argc) {
        std::fprintf(stderr, "soak_publisher: %s needs a value\n", o.c_str());
        std::exit(2);
      }
      return argv[++k];
    };
    if (o == "--write-model") a.write_model = next();
    else if (o == "--model") a.model = next();
    else if (o == "--particles") a.particles = std::stoi(next());
    else if (o == "--bonds") a.bonds = std::stoi(next());
    else if (o == "--bond-types") a.bond_types = std::stoi(next());
    else if (o == "--damping-max") a.damping_max_nspm = std::stod(next());
    else if (o == "--seed") a.seed = std::stoull(next());
    else if (o == "--minutes") a.minutes = std::stod(next());
    else if (o == "--clip-seconds") a.clip_seconds = std::stod(next());
    else if (o == "--estimator") a.estimator = next();
    else if (o == "--estimator-pid") a.estimator_pid = std::stol(next());
    else if (o == "--csv") a.csv = next();
    else if (o == "--summary") a.summary = next();
    else if (o.rfind("__", 0) == 0 || o.rfind("_", 0) == 0) continue;  // ROS remappings
    else {
      std::fprintf(stderr, "soak_publisher: unknown option %s\n", o.c_str());
      return 2;
    }
  }
  try {
    if (!a.write_model.empty()) return writeModel(a);
    if (a.model.empty() || a.csv.empty() || a.estimator_pid <= 0) {
      std::fprintf(stderr, "soak_publisher: need --model, --csv and --estimator-pid\n");
      return 2;
    }
    ros::init(argc, argv, "soak_publisher", ros::init_options::NoSigintHandler);
    return run(a);
  } catch (const mme::InputError& e) {
    std::fprintf(stderr, "soak_publisher: %s\n", e.what());
    return 2;
  }
}
