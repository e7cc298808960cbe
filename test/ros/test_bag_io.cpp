// Bag round trips of MarkerFrame and the errors of readBag (no master needed).
#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <std_msgs/String.h>

#include <dirent.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <memory>
#include <string>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/trajectory.h"
#include "motion_model_estimation/ros/bag_format.h"
#include "motion_model_estimation/ros/bag_io.h"
#include "motion_model_estimation/ros/conversions.h"
#include "motion_model_estimation/io/trajectory_io.h"

namespace {

std::string tempPath(const std::string& name) {
  return (testing::TempDir().empty() ? std::string("/tmp/") : testing::TempDir()) + "mme_" + name;
}

mme::Trajectory makeTrajectory() {
  mme::Trajectory t;
  t.marker_names = {"a", "b", "c"};
  t.frame_rate_hz = 120.0;
  t.resize(25);
  for (int f = 0; f < t.numFrames(); ++f)
    for (int i = 0; i < 3; ++i) {
      t.position(f, i) = Eigen::Vector3d(0.1 * i + 0.001 * f, -0.37 * f / 7.0, 1.0 / (1 + i + f));
      t.occluded[f * 3 + i] = (f == 5 && i == 1) || (f == 11 && i == 2);
      if (t.occluded[f * 3 + i]) t.position(f, i).setZero();
    }
  return t;
}

TEST(BagIo, RoundTripKeepsPositionsOcclusionNamesAndRate) {
  const mme::Trajectory in = makeTrajectory();
  const std::string path = tempPath("roundtrip.bag");
  mme::writeBag(path, "markers", "world", in);
  const mme::Trajectory out = mme::readBag(path, "");  // the only MarkerFrame topic
  ASSERT_EQ(out.marker_names, in.marker_names);
  ASSERT_EQ(out.numFrames(), in.numFrames());
  EXPECT_DOUBLE_EQ(out.frame_rate_hz, 120.0);
  for (int f = 0; f < in.numFrames(); ++f) {
    EXPECT_EQ(out.frame_numbers[f], in.frame_numbers[f]);
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(out.isOccluded(f, i), in.isOccluded(f, i)) << f << " " << i;
      EXPECT_EQ(out.position(f, i), in.position(f, i)) << f << " " << i;  // bit exact doubles
    }
  }
  // Times keep their spacing (an offset may be added to avoid a zero stamp).
  EXPECT_NEAR(out.times_s[10] - out.times_s[0], 10.0 / 120.0, 1e-9);
  std::remove(path.c_str());
}

TEST(BagIo, ExplicitTopicAndMissingTopic) {
  const std::string path = tempPath("topic.bag");
  mme::writeBag(path, "/mocap/markers", "world", makeTrajectory());
  EXPECT_EQ(mme::readBag(path, "/mocap/markers").numFrames(), 25);
  try {
    mme::readBag(path, "/nothing_here");
    FAIL() << "a missing topic must throw";
  } catch (const mme::InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("/nothing_here"), std::string::npos);
  }
  std::remove(path.c_str());
}

TEST(BagIo, WrongMessageTypeIsRefusedByName) {
  const std::string path = tempPath("wrongtype.bag");
  {
    rosbag::Bag bag(path, rosbag::bagmode::Write);
    std_msgs::String s;
    s.data = "not markers";
    bag.write("markers", ros::Time(1.0), s);
  }
  try {
    mme::readBag(path, "markers");
    FAIL() << "a topic of the wrong type must throw";
  } catch (const mme::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("std_msgs/String"), std::string::npos) << e.what();
  }
  EXPECT_THROW(mme::readBag(path, ""), mme::InputError);  // no MarkerFrame topic at all
  std::remove(path.c_str());
}

TEST(BagIo, NotABagAndMissingFileThrowNamingTheFile) {
  const std::string path = tempPath("garbage.bag");
  std::ofstream(path) << "this is not a rosbag\n";
  try {
    mme::readBag(path, "");
    FAIL();
  } catch (const mme::InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
  }
  std::remove(path.c_str());
  EXPECT_THROW(mme::readBag(tempPath("does_not_exist.bag"), ""), mme::InputError);
}

// Two writers of one path at once (two tools: two processes, each writing several times): each
// writes a temporary file of its own and renames it, so the bag left is one of the two, whole,
// and no temporary stays.
TEST(BagIo, TwoWritersOfOnePathLeaveOneWholeBag) {
  const std::string path = tempPath("two_writers.bag");
  const mme::Trajectory a = makeTrajectory();
  mme::Trajectory b = makeTrajectory();
  b.resize(40);  // 40 frames, every sample occluded at the origin
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    int failures = 0;
    for (int k = 0; k < 20; ++k) {
      try {
        mme::writeBag(path, "markers", "world", b);
      } catch (const mme::InputError&) {
        ++failures;
      }
    }
    ::_exit(failures == 0 ? 0 : 1);
  }
  for (int k = 0; k < 20; ++k) mme::writeBag(path, "markers", "world", a);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "the other writer failed";
  const mme::Trajectory out = mme::readBag(path, "");
  EXPECT_TRUE(out.numFrames() == 25 || out.numFrames() == 40) << out.numFrames();
  const std::string dir = path.substr(0, path.rfind('/') + 1);
  const std::string base = path.substr(dir.size());
  std::unique_ptr<DIR, int (*)(DIR*)> d(::opendir(dir.c_str()), ::closedir);
  ASSERT_TRUE(d);
  for (dirent* e = ::readdir(d.get()); e; e = ::readdir(d.get()))
    EXPECT_NE(std::string(e->d_name).rfind(base + ".tmp", 0), 0u) << e->d_name;
  std::remove(path.c_str());
}

TEST(BagIo, UnwritablePathThrowsAndLeavesNothing) {
  EXPECT_THROW(mme::writeBag("/nonexistent_dir_mme/x.bag", "markers", "world", makeTrajectory()),
               mme::InputError);
}

TEST(Conversions, NaNIsOccludedAndMismatchedFramesAreRejected) {
  mme::Trajectory t;
  t.marker_names = {"a", "b"};
  motion_model_estimation::MarkerFrame msg;
  msg.names = {"a", "b"};
  msg.positions.resize(2);
  msg.positions[1].x = std::nan("");
  EXPECT_EQ(mme::appendMarkerFrame(msg, &t), "");
  ASSERT_EQ(t.occluded.size(), 2u);
  EXPECT_EQ(t.occluded[0], 0);
  EXPECT_EQ(t.occluded[1], 1);
  EXPECT_TRUE(t.positions_m[1].allFinite());
  msg.positions.resize(3);
  EXPECT_NE(mme::appendMarkerFrame(msg, &t), "");
  msg.positions.resize(2);
  msg.names = {"a", "x"};
  EXPECT_NE(mme::appendMarkerFrame(msg, &t), "");
  msg.names = {"a", "b"};
  msg.occluded = {true};
  EXPECT_NE(mme::appendMarkerFrame(msg, &t), "");
  EXPECT_EQ(t.numFrames(), 1);  // rejected frames leave the trajectory as it was
  EXPECT_EQ(t.positions_m.size(), 2u);
}

}  // namespace

namespace {

// A real capture through writeTrajectory / readTrajectory: bag and TRC keep what was read.
void expectSameCapture(const mme::Trajectory& in, const mme::Trajectory& out, double tolerance_m,
                       double time_offset_s) {
  ASSERT_EQ(out.marker_names, in.marker_names);
  ASSERT_EQ(out.numFrames(), in.numFrames());
  EXPECT_DOUBLE_EQ(out.frame_rate_hz, in.frame_rate_hz);
  EXPECT_EQ(out.countOccluded(), in.countOccluded());
  for (int f = 0; f < in.numFrames(); ++f) {
    ASSERT_EQ(out.frame_numbers[f], in.frame_numbers[f]);
    ASSERT_NEAR(out.times_s[f], in.times_s[f] + time_offset_s, 1e-6) << f;
    for (int i = 0; i < in.numMarkers(); ++i) {
      ASSERT_EQ(out.isOccluded(f, i), in.isOccluded(f, i)) << f << " " << in.marker_names[i];
      ASSERT_LE((out.position(f, i) - in.position(f, i)).norm(), tolerance_m)
          << f << " " << in.marker_names[i];
    }
  }
}

TEST(TrajectoryFiles, RealCapturesWithGapsRoundTripThroughBagAndTrc) {
  mme::registerBagFormat();
  for (const char* file : {"Sample26_Walking_Hybrid_1_1.c3d", "motion_capture_walk.trc",
                           "Sample01_Eb015pi.c3d"}) {
    SCOPED_TRACE(file);
    const mme::Trajectory in =
        mme::readTrajectory(std::string(MME_TEST_DATA_DIR) + "/real/" + file, "");
    ASSERT_GT(in.numFrames(), 100);
    const std::string bag = tempPath("capture.bag"), trc = tempPath("capture.trc");
    mme::writeTrajectory(bag, in);
    const mme::Trajectory from_bag = mme::readTrajectory(bag, "markers");
    // A bag cannot hold time 0: a capture starting there is stamped from 1 s on.
    const double offset_s = in.times_s[0] <= 0.0 ? 1.0 : 0.0;
    expectSameCapture(in, from_bag, 0.0, offset_s);  // bit exact positions
    mme::TrajectoryWriteOptions o;
    o.units = "mm";
    mme::writeTrajectory(trc, from_bag, o);
    expectSameCapture(in, mme::readTrajectory(trc, ""), 1e-9, offset_s);
    std::remove(bag.c_str());
    std::remove(trc.c_str());
  }
  // Sample26's gaps are many: the round trip above checked 3902 of them one by one.
  EXPECT_EQ(mme::readTrajectory(std::string(MME_TEST_DATA_DIR) + "/real/Sample26_Walking_Hybrid_1_1.c3d", "")
                .countOccluded(), 3902u);
}

TEST(TrajectoryFiles, UnknownExtensionsAndEmptyTopicAreRefusedByName) {
  mme::registerBagFormat();
  const mme::Trajectory t = makeTrajectory();
  try {
    mme::writeTrajectory(tempPath("x.csv"), t);
    FAIL() << "no throw";
  } catch (const mme::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("x.csv: cannot write '.csv' files"), std::string::npos) << e.what();
  }
  mme::TrajectoryWriteOptions o;
  o.topic = "";
  EXPECT_THROW(mme::writeTrajectory(tempPath("x.bag"), t, o), mme::InputError);
  EXPECT_THROW(mme::readTrajectory(tempPath("x.json"), ""), mme::InputError);
}

}  // namespace
