// Shared helpers of the estimator_node rostests (test/ros/test_estimator_*.cpp): the truth of a
// built-in scene, a recorder of ~estimate, convergence checks and a scene streamer that
// publishes the scene's motion as MarkerFrame / PointCloud2 / vicon_bridge/Markers.
#pragma once

#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <std_msgs/String.h>
#include <topic_tools/shape_shifter.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cstdlib>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

#include "motion_model_estimation/MarkerFrame.h"
#include "motion_model_estimation/ModelEstimate.h"
#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/core/simulator.h"
#include "motion_model_estimation/ros/conversions.h"
#include "motion_model_estimation/ros/vicon_markers.h"
#include "motion_model_estimation/scenes/scenes.h"

namespace mmetest {

/// The fields of a ~stats line ("key=value" separated by spaces) by key.
inline std::map<std::string, double> parseStatsLine(const std::string& line) {
  std::map<std::string, double> fields;
  std::istringstream in(line);
  std::string item;
  while (in >> item) {
    const size_t eq = item.find('=');
    if (eq != std::string::npos) fields[item.substr(0, eq)] = std::atof(item.c_str() + eq + 1);
  }
  return fields;
}

/// The latest ~stats line (thread-safe).
class StatsWatcher {
 public:
  explicit StatsWatcher(ros::NodeHandle& nh, const std::string& topic = "estimator/stats") {
    sub_ = nh.subscribe<std_msgs::String>(topic, 10, [this](const std_msgs::String::ConstPtr& m) {
      std::lock_guard<std::mutex> lock(mutex_);
      line_ = m->data;
      ++count_;
    });
  }
  std::string line() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return line_;
  }
  /// ~stats messages received so far.
  int count() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return count_;
  }
  bool waitFor(const std::function<bool(const std::string&)>& done, double timeout_s) const {
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout_s);
    while (ros::ok() && ros::WallTime::now() < deadline) {
      if (done(line())) return true;
      ros::WallDuration(0.05).sleep();
    }
    return done(line());
  }

 private:
  ros::Subscriber sub_;
  mutable std::mutex mutex_;
  std::string line_;
  int count_ = 0;
};

using motion_model_estimation::MarkerFrame;
using motion_model_estimation::ModelEstimate;

/// The true values of a scene's free parameters (what identification should find).
struct Truth {
  std::vector<std::string> names;
  std::vector<double> values;
  double at(const std::string& name) const {
    for (size_t k = 0; k < names.size(); ++k)
      if (names[k] == name) return values[k];
    return std::numeric_limits<double>::quiet_NaN();
  }
};

inline Truth sceneTruth(const std::string& scene) {
  const mme::Scene s = mme::makeScene(scene);
  Truth t;
  for (const mme::ParamRef& ref : mme::freeParameters(s.model)) {
    t.names.push_back(ref.name);
    t.values.push_back(mme::getParam(s.model, ref));
  }
  return t;
}

/// Worst relative error |estimate - truth| / |truth| over the truth's parameters (a parameter
/// missing from the estimate counts as infinite). *worst names it with both values.
inline double worstRelativeError(const ModelEstimate& e, const Truth& truth,
                                 std::string* worst = nullptr) {
  double worst_error = 0.0;
  for (size_t k = 0; k < truth.names.size(); ++k) {
    double error = std::numeric_limits<double>::infinity();
    double value = std::numeric_limits<double>::quiet_NaN();
    for (size_t j = 0; j < e.parameter_names.size() && j < e.values.size(); ++j)
      if (e.parameter_names[j] == truth.names[k]) {
        value = e.values[j];
        error = std::fabs(value - truth.values[k]) / std::fabs(truth.values[k]);
        if (!std::isfinite(error)) error = std::numeric_limits<double>::infinity();
      }
    if (error >= worst_error) {
      worst_error = error;
      if (worst) {
        std::ostringstream s;
        s << truth.names[k] << " = " << value << " (truth " << truth.values[k] << ", error "
          << 100.0 * error << " %)";
        *worst = s.str();
      }
    }
  }
  return worst_error;
}

/// Records every message of a ~estimate topic, with the value of a caller-supplied counter
/// (e.g. the latest input frame number seen) at reception.
class EstimateRecorder {
 public:
  struct Entry {
    ModelEstimate msg;
    ros::WallTime received;
    int64_t tag = -1;
  };

  EstimateRecorder(ros::NodeHandle& nh, const std::string& topic,
                   std::function<int64_t()> tagger = nullptr)
      : tagger_(std::move(tagger)) {
    sub_ = nh.subscribe<ModelEstimate>(topic, 100, [this](const ModelEstimate::ConstPtr& m) {
      Entry e;
      e.msg = *m;
      e.received = ros::WallTime::now();
      e.tag = tagger_ ? tagger_() : -1;
      std::lock_guard<std::mutex> lock(mutex_);
      entries_.push_back(std::move(e));
    });
  }
  size_t count() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return entries_.size();
  }
  std::vector<Entry> since(size_t first) const {
    std::lock_guard<std::mutex> lock(mutex_);
    if (first >= entries_.size()) return {};
    return std::vector<Entry>(entries_.begin() + first, entries_.end());
  }
  bool last(Entry* out) const {
    std::lock_guard<std::mutex> lock(mutex_);
    if (entries_.empty()) return false;
    *out = entries_.back();
    return true;
  }
  /// Waits (wall time) until `done(entries)` is true; the callbacks run on an AsyncSpinner.
  bool waitUntil(const std::function<bool(const std::vector<Entry>&)>& done,
                 double timeout_s) const {
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout_s);
    while (ros::ok() && ros::WallTime::now() < deadline) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (done(entries_)) return true;
      }
      ros::WallDuration(0.02).sleep();
    }
    std::lock_guard<std::mutex> lock(mutex_);
    return done(entries_);
  }

 private:
  std::function<int64_t()> tagger_;
  ros::Subscriber sub_;
  mutable std::mutex mutex_;
  std::vector<Entry> entries_;
};

/// Waits until `consecutive` successive estimates (from entry `first` on) have every truth
/// parameter within `tolerance` (relative) and were computed on at least `min_window_frames`
/// frames. Returns the index of the first of them, or -1. *report describes the last estimate.
inline long waitForConvergence(const EstimateRecorder& recorder, const Truth& truth,
                               double tolerance, double timeout_s, int consecutive,
                               std::string* report, size_t first = 0,
                               uint32_t min_window_frames = 0) {
  long found = -1;
  recorder.waitUntil(
      [&](const std::vector<EstimateRecorder::Entry>& entries) {
        int run = 0;
        for (size_t k = first; k < entries.size(); ++k) {
          std::string worst;
          const double error = worstRelativeError(entries[k].msg, truth, &worst);
          const bool full = entries[k].msg.window_frames >= min_window_frames;
          run = error <= tolerance && full ? run + 1 : 0;
          if (report) {
            std::ostringstream s;
            s << entries.size() - first << " estimates; last: generation "
              << entries[k].msg.generation << ", window " << entries[k].msg.window_frames
              << " frames, cost " << entries[k].msg.global_cost
              << ", worst " << worst;
            *report = s.str();
          }
          if (run >= consecutive) {
            found = static_cast<long>(k) - consecutive + 1;
            return true;
          }
        }
        return false;
      },
      timeout_s);
  return found;
}

/// The motion of a built-in scene, one frame at a time (what simulator_node publishes).
class SceneStream {
 public:
  explicit SceneStream(const std::string& scene)
      : model_(mme::makeScene(scene).model), simulator_(model_), state_(simulator_.initialState()) {
    for (const mme::Particle& p : model_.particles) names_.push_back(p.name);
  }
  const std::vector<std::string>& names() const { return names_; }
  const mme::Model& model() const { return model_; }
  double frameRateHz() const { return model_.frame_rate_hz; }
  /// Positions of the current frame [m, model frame].
  const std::vector<Eigen::Vector3d>& positions() const { return state_.x_m; }
  void next() { simulator_.stepFrame(&state_, 1.0 / model_.frame_rate_hz); }

 private:
  mme::Model model_;
  mme::Simulator simulator_;
  mme::State state_;
  std::vector<std::string> names_;
};

inline MarkerFrame makeMarkerFrame(const std::vector<std::string>& names,
                                   const std::vector<Eigen::Vector3d>& x, uint32_t frame_number,
                                   const ros::Time& stamp, const std::string& frame_id) {
  MarkerFrame m;
  m.header.stamp = stamp;
  m.header.frame_id = frame_id;
  m.frame_number = frame_number;
  m.names = names;
  for (const Eigen::Vector3d& p : x) {
    geometry_msgs::Point q;
    q.x = p.x();
    q.y = p.y();
    q.z = p.z();
    m.positions.push_back(q);
  }
  return m;
}

/// Points in particle order as float32 x/y/z (NaN = occluded).
inline sensor_msgs::PointCloud2 makePointCloud(const std::vector<Eigen::Vector3d>& x,
                                               const ros::Time& stamp,
                                               const std::string& frame_id) {
  sensor_msgs::PointCloud2 cloud;
  cloud.header.stamp = stamp;
  cloud.header.frame_id = frame_id;
  sensor_msgs::PointCloud2Modifier modifier(cloud);
  modifier.setPointCloud2FieldsByString(1, "xyz");
  modifier.resize(x.size());
  sensor_msgs::PointCloud2Iterator<float> it(cloud, "x");
  for (size_t i = 0; i < x.size(); ++i, ++it) {
    it[0] = static_cast<float>(x[i].x());
    it[1] = static_cast<float>(x[i].y());
    it[2] = static_cast<float>(x[i].z());
  }
  return cloud;
}

/// A vicon_bridge/Markers publisher without depending on vicon_bridge (ShapeShifter).
class ViconPublisher {
 public:
  ViconPublisher(ros::NodeHandle& nh, const std::string& topic) {
    shifter_.morph(mme::viconMarkersMd5(), "vicon_bridge/Markers", mme::viconMarkersDefinition(),
                   "");
    pub_ = shifter_.advertise(nh, topic, 200);
  }
  /// Positions in metres (sent in millimetres, as the driver does).
  void publish(const std::vector<std::string>& names, const std::vector<Eigen::Vector3d>& x,
               uint32_t frame_number, const ros::Time& stamp, const std::string& frame_id) {
    mme::ViconMarkers m;
    m.stamp_s = stamp.toSec();
    m.frame_id = frame_id;
    m.frame_number = frame_number;
    m.names = names;
    m.positions_m = x;
    m.occluded.assign(x.size(), 0);
    std::vector<uint8_t> bytes = mme::encodeViconMarkers(m, frame_number);
    ros::serialization::IStream stream(bytes.data(), static_cast<uint32_t>(bytes.size()));
    shifter_.read(stream);
    pub_.publish(shifter_);
  }
  uint32_t getNumSubscribers() const { return pub_.getNumSubscribers(); }

 private:
  topic_tools::ShapeShifter shifter_;
  ros::Publisher pub_;
};

/// Waits until `pub` has at least one subscriber (connection made: nothing published after it
/// is lost).
template <typename Pub>
bool waitForSubscriber(const Pub& pub, double timeout_s) {
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout_s);
  while (ros::ok() && ros::WallTime::now() < deadline) {
    if (pub.getNumSubscribers() > 0) return true;
    ros::WallDuration(0.02).sleep();
  }
  return pub.getNumSubscribers() > 0;
}

}  // namespace mmetest
