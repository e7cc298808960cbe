// Trajectory files by extension (io/trajectory_io.h): TRC written and read back through the one
// entry point, a format added from outside the core (as the ROS layer adds rosbags) read and
// written through it, and an extension nobody reads refused with the list of those that are,
// saying what a build without ROS lacks.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/io/trajectory_io.h"

namespace {

std::string tempPath(const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("mme_trajectory_io_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

mme::Trajectory twoFrames() {
  mme::Trajectory t;
  t.marker_names = {"a", "b"};
  t.frame_rate_hz = 100.0;
  t.resize(2);
  for (int f = 0; f < 2; ++f) {
    t.position(f, 0) = Eigen::Vector3d(0.1 * f, 0.2, 0.3);
    t.position(f, 1) = Eigen::Vector3d(1.0, 0.5 * f, 0.0);
    t.occluded[f * 2] = t.occluded[f * 2 + 1] = 0;
  }
  return t;
}

std::string messageOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const mme::InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}

TEST(TrajectoryIo, TrcThroughTheOneEntryPoint) {
  const std::string path = tempPath("round.trc");
  mme::writeTrajectory(path, twoFrames());
  const mme::Trajectory back = mme::readTrajectory(path, "");
  ASSERT_EQ(back.numFrames(), 2);
  ASSERT_EQ(back.marker_names, twoFrames().marker_names);
  EXPECT_NEAR((back.position(1, 1) - twoFrames().position(1, 1)).norm(), 0.0, 1e-9);
}

TEST(TrajectoryIo, ARegisteredFormatIsReadAndWrittenByItsExtension) {
  std::string read_topic, written_path;
  mme::TrajectoryFormat format;
  format.read = [&](const std::string&, const std::string& topic) {
    read_topic = topic;
    return twoFrames();
  };
  format.write = [&](const std::string& path, const mme::Trajectory& t, const mme::TrajectoryWriteOptions&) {
    written_path = path;
    EXPECT_EQ(t.numFrames(), 2);
  };
  mme::registerTrajectoryFormat(".toy", format);
  EXPECT_EQ(mme::readTrajectory("x.toy", "markers").numFrames(), 2);
  EXPECT_EQ(read_topic, "markers");
  mme::writeTrajectory("y.toy", twoFrames());
  EXPECT_EQ(written_path, "y.toy");
  // The list of what this build reads names it.
  EXPECT_NE(messageOf([] { mme::readTrajectory("z.csv", ""); }).find(".toy"), std::string::npos);
}

TEST(TrajectoryIo, UnknownExtensionsAreRefusedNamingWhatIsRead) {
  const std::string read = messageOf([] { mme::readTrajectory("walk.json", ""); });
  EXPECT_NE(read.find("walk.json"), std::string::npos) << read;
  EXPECT_NE(read.find(".trc"), std::string::npos) << read;
  EXPECT_NE(read.find(".c3d"), std::string::npos) << read;
  const std::string write = messageOf([] { mme::writeTrajectory("walk.json", twoFrames()); });
  EXPECT_NE(write.find("cannot write '.json' files (write .trc"), std::string::npos) << write;
}

// A capture in millimetres whose header says m spans hundreds of metres: reading it warns with
// the file, the figure and the fix; the same markers in the right units give no warning, and a
// capture in metres read as millimetres (a sub-millimetre body) warns too.
TEST(TrajectoryIo, ImplausibleMarkerSpreadWarnsOfTheUnits) {
  mme::Trajectory body = twoFrames();  // markers about 1 m apart
  const std::string right = tempPath("right.trc");
  mme::writeTrajectory(right, body);
  std::vector<std::string> warnings;
  mme::readTrajectory(right, "", &warnings);
  EXPECT_EQ(warnings, std::vector<std::string>{});

  for (Eigen::Vector3d& p : body.positions_m) p *= 1000.0;  // millimetre numbers under "m"
  const std::string large = tempPath("large.trc");
  mme::TrajectoryWriteOptions in_metres;
  in_metres.units = "m";
  mme::writeTrajectory(large, body, in_metres);
  mme::readTrajectory(large, "", &warnings);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find(large + ": the markers span "), std::string::npos) << warnings[0];
  EXPECT_NE(warnings[0].find(" m (median over frames): a human capture spans 0.1-3 m; is the file in "
                             "millimetres with a header saying m"),
            std::string::npos)
      << warnings[0];

  for (Eigen::Vector3d& p : body.positions_m) p *= 1e-6;  // metre numbers under "mm"
  EXPECT_NE(mme::implausibleSpreadWarning("small.trc", body).find("is the file in metres with a header saying mm"),
            std::string::npos);
}

// Without the ROS layer nobody registers ".bag": the message says so rather than "unknown".
TEST(TrajectoryIo, ABagWithoutTheRosLayerSaysWhatIsMissing) {
  const std::string read = messageOf([] { mme::readTrajectory("walk.bag", ""); });
  EXPECT_NE(read.find("rosbags need the ROS build"), std::string::npos) << read;
  const std::string write = messageOf([] { mme::writeTrajectory("walk.bag", twoFrames()); });
  EXPECT_NE(write.find("rosbags need the ROS build"), std::string::npos) << write;
}

}  // namespace
