// libFuzzer harness: bytes -> motion_model_estimation/MarkerFrame (ros::serialization, as the
// node's subscriber deserialises them) -> mme::appendMarkerFrame (bags, identify) and the node's
// path into mme::OnlineEstimator::addFrame + update() on a small 3-particle model.
//
// roscpp's vector deserialisation resizes to the wire length before checking it against the
// buffer, so a length field of 2^32 makes it allocate ~100 GB before throwing. That is roscpp's
// code, not ours, and a live message is bounded by the transport; the harness therefore first
// walks the wire format and skips inputs whose array lengths cannot fit in the bytes given.
#include <ros/serialization.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <string>

#include "motion_model_estimation/MarkerFrame.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/identification/online/online_estimator.h"
#include "motion_model_estimation/io/model_yaml.h"
#include "motion_model_estimation/live/marker_name_map.h"
#include "motion_model_estimation/ros/conversions.h"

namespace {

const char* kModel = R"(
frame_rate_hz: 100
gravity: [0, 0, -9.81]
particles:
  - {name: a, mass: 1.0, position: [0, 0, 0], fixed: true}
  - {name: b, mass: 0.5, position: [0, 0, -0.1]}
  - {name: c, mass: 0.5, position: [0, 0.1, -0.1]}
bond_types:
  - name: s
    kind: spring
    stiffness: {value: 40.0, free: true, min: 1, max: 1000}
    rest_length: {value: 0.08, free: true}
    damping: 0.1
bonds:
  - {type: s, particles: [a, b]}
  - {type: s, particles: [b, c]}
)";

/// True when every length field of the MarkerFrame wire format fits in the remaining bytes.
bool plausible(const uint8_t* data, size_t size) {
  size_t pos = 0;
  auto u32 = [&](uint32_t* v) {
    if (size - pos < 4) return false;
    std::memcpy(v, data + pos, 4);
    pos += 4;
    return true;
  };
  auto skip = [&](uint64_t n) {
    if (n > size - pos) return false;
    pos += static_cast<size_t>(n);
    return true;
  };
  uint32_t v = 0;
  // header: seq, stamp.sec, stamp.nsec, frame_id
  if (!u32(&v) || !u32(&v) || !u32(&v) || !u32(&v) || !skip(v)) return false;
  if (!u32(&v)) return false;  // frame_number
  uint32_t names = 0;
  if (!u32(&names) || names > (size - pos) / 4) return false;
  for (uint32_t k = 0; k < names; ++k)
    if (!u32(&v) || !skip(v)) return false;
  if (!u32(&v) || !skip(uint64_t(v) * 24)) return false;  // positions
  if (!u32(&v) || !skip(v)) return false;                 // occluded
  return true;
}

const mme::Model& model() {
  static const mme::Model m = mme::loadModelString(kModel, "fuzz_model");
  return m;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (!plausible(data, size)) return 0;
  motion_model_estimation::MarkerFrame msg;
  try {
    ros::serialization::IStream stream(const_cast<uint8_t*>(data), static_cast<uint32_t>(size));
    ros::serialization::deserialize(stream, msg);
  } catch (const ros::Exception&) {
    return 0;
  }
  const mme::Model& m = model();
  std::vector<std::string> particle_names;
  for (const mme::Particle& p : m.particles) particle_names.push_back(p.name);

  // 1. appendMarkerFrame against a trajectory of the model's markers and one named by the
  //    frame itself (the bag reader's case: the first frame sets the names).
  for (int variant = 0; variant < 2; ++variant) {
    mme::Trajectory t;
    t.marker_names = variant == 0 ? particle_names : msg.names;
    t.frame_rate_hz = 100.0;
    for (int k = 0; k < 3; ++k) {
      const std::string why = mme::appendMarkerFrame(msg, &t);
      if (!why.empty()) break;
      if (!t.validate().empty()) {
        std::fprintf(stderr, "appendMarkerFrame made an invalid trajectory: %s\n",
                     t.validate().c_str());
        std::abort();
      }
    }
  }

  // 2. The node's path: names -> model order (absent = occluded, MarkerNameMap), then the
  //    estimator.
  mme::OnlineEstimatorOptions options;
  options.window_frames = 6;
  options.min_frames = 3;
  options.generations_per_update = 1;
  options.es.population = 4;
  options.es.offspring = 4;
  options.es.refine_period = 0;
  mme::OnlineEstimator estimator(m, options);
  std::vector<Eigen::Vector3d> positions;
  for (const auto& p : msg.positions) positions.emplace_back(p.x, p.y, p.z);
  mme::MarkerNameMap names(particle_names);
  mme::MappedFrame mapped = names.map(msg.names, positions, msg.occluded);
  if (!mapped.rejection.empty() || msg.names.empty()) {
    // Refused (the node skips it) or in model order of the wrong size: go on with a frame
    // of the model's size, every particle occluded, to exercise the estimator anyway.
    mapped.positions_m.assign(particle_names.size(), Eigen::Vector3d::Zero());
    mapped.occluded.assign(particle_names.size(), 1);
  } else if (mapped.positions_m.size() != particle_names.size() ||
             mapped.occluded.size() != particle_names.size() ||
             mapped.matched + mapped.unknown != msg.names.size()) {
    std::fprintf(stderr, "MarkerNameMap made an inconsistent frame\n");
    std::abort();
  }
  const std::vector<Eigen::Vector3d>& x = mapped.positions_m;
  const std::vector<uint8_t>& mask = mapped.occluded;
  const double t0 = msg.header.stamp.toSec();
  for (int k = 0; k < 5; ++k) {
    std::vector<Eigen::Vector3d> xk = x;
    for (Eigen::Vector3d& p : xk) p += Eigen::Vector3d(0.001 * k, -0.0005 * k * k, 0.0);
    (void)estimator.addFrame(t0 + 0.01 * k, xk, mask);
    (void)estimator.addFrame(t0 + 0.01 * k, xk, mask);  // duplicate: rejected
  }
  // Raw positions in message order (wrong size unless it happens to match).
  std::vector<uint8_t> raw_occ(msg.occluded.begin(), msg.occluded.end());
  (void)estimator.addFrame(t0 + 1.0, positions, raw_occ);
  try {
    estimator.update();
  } catch (const mme::InputError&) {
  }
  const mme::Estimate e = estimator.estimate();
  if (e.valid && e.values.size() != e.parameter_names.size()) std::abort();
  (void)estimator.currentModel();
  (void)mme::OnlineEstimator::rollout(m, estimator.window(), 3);
  const mme::InputCounters c = estimator.counters();
  if (c.accepted > 6) std::abort();
  return 0;
}
