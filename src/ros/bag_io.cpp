#include "motion_model_estimation/ros/bag_io.h"

#include <fcntl.h>
#include <rosbag/bag.h>
#include <unistd.h>
#include <rosbag/view.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <set>
#include <string>

#include "motion_model_estimation/MarkerFrame.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/ros/conversions.h"

namespace mme {

namespace {
const std::string kMarkerFrameType = "motion_model_estimation/MarkerFrame";
}

void writeBag(const std::string& path, const std::string& topic, const std::string& frame_id,
              const Trajectory& trajectory) {
  // rosbag writes in place; write to a temporary name and rename so readers never see a
  // half-written bag. The name is this writer's own (process and call), so that two writers of
  // one path never share it: the last rename wins, whole.
  static std::atomic<unsigned> calls{0};
  const std::string tmp = path + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(calls++);
  try {
    rosbag::Bag bag;
    bag.open(tmp, rosbag::bagmode::Write);
    for (int t = 0; t < trajectory.numFrames(); ++t) {
      // ros::Time cannot be 0 in a bag index, and negative times are invalid: offset by 1 s
      // only when needed.
      ros::Time stamp;
      stamp.fromSec(std::max(trajectory.times_s[t], 0.0) + (trajectory.times_s[0] <= 0.0 ? 1.0 : 0.0));
      bag.write(topic, stamp, toMarkerFrameMsg(trajectory, t, frame_id, stamp));
    }
    bag.close();
  } catch (const rosbag::BagException& e) {
    std::remove(tmp.c_str());
    throw InputError(path + ": cannot write bag: " + e.what());
  }
  // On disk before the rename, like every other write of the package (writeFileAtomically): a
  // crash then leaves the old file or the whole new one.
  const int fd = ::open(tmp.c_str(), O_RDONLY);
  const bool synced = fd >= 0 && ::fsync(fd) == 0;
  if (fd >= 0) ::close(fd);
  if (!synced) {
    std::remove(tmp.c_str());
    throw InputError(path + ": cannot write bag (fsync failed)");
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw InputError(path + ": cannot write bag (rename failed)");
  }
}

Trajectory readBag(const std::string& path, const std::string& topic) {
  rosbag::Bag bag;
  try {
    bag.open(path, rosbag::bagmode::Read);
  } catch (const rosbag::BagException& e) {
    throw InputError(path + ": cannot open bag: " + e.what());
  }
  Trajectory trajectory;
  try {
    std::string chosen = topic;
    if (chosen.empty()) {
      rosbag::View all(bag);
      std::set<std::string> topics;
      for (const rosbag::ConnectionInfo* c : all.getConnections())
        if (c->datatype == kMarkerFrameType) topics.insert(c->topic);
      if (topics.empty()) throw InputError(path + ": no " + kMarkerFrameType + " messages in bag");
      if (topics.size() > 1)
        throw InputError(path + ": several MarkerFrame topics; choose one with --topic");
      chosen = *topics.begin();
    }
    rosbag::View view(bag, rosbag::TopicQuery(chosen));
    if (view.size() == 0) throw InputError(path + ": no messages on topic '" + chosen + "'");
    for (const rosbag::ConnectionInfo* c : view.getConnections())
      if (c->datatype != kMarkerFrameType)
        throw InputError(path + ": topic '" + chosen + "' holds " + c->datatype + ", expected " +
                         kMarkerFrameType);
    bool first = true;
    for (const rosbag::MessageInstance& m : view) {
      auto msg = m.instantiate<motion_model_estimation::MarkerFrame>();
      if (!msg) continue;
      if (first) {
        trajectory.marker_names = msg->names;
        first = false;
      }
      appendMarkerFrame(*msg, &trajectory);  // mismatched frames are skipped
    }
  } catch (const rosbag::BagException& e) {
    throw InputError(path + ": bad bag: " + e.what());
  }
  // Rate from the median stamp difference: robust to a dropped frame.
  std::vector<double> dts;
  for (size_t t = 1; t < trajectory.times_s.size(); ++t)
    dts.push_back(trajectory.times_s[t] - trajectory.times_s[t - 1]);
  if (!dts.empty()) {
    std::nth_element(dts.begin(), dts.begin() + dts.size() / 2, dts.end());
    const double dt = dts[dts.size() / 2];
    if (dt > 0.0) {
      // Stamps have nanosecond resolution: 1/120 s reads back as 120.0000048 Hz. Snap rates
      // that are that close to an integer.
      double rate_hz = 1.0 / dt;
      if (std::abs(rate_hz - std::round(rate_hz)) < 1e-3) rate_hz = std::round(rate_hz);
      trajectory.frame_rate_hz = rate_hz;
    }
  }
  return trajectory;
}

}  // namespace mme
