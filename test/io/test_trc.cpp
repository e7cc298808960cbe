// Tests of the TRC reader/writer and the extension dispatch: the real OpenSim files load with
// the counts, rates and values they hold, layout variations (CRLF, trailing tabs, short rows,
// empty/0,0,0/NaN gaps) parse, a file with fewer rows than its NumFrames (a cut-off copy) gives a
// warning and its rows, write/read round trips are exact to 1e-9 m, and every kind of bad input
// gives an InputError naming the file (and line).

#include <gtest/gtest.h>
#include <stdlib.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/io/trajectory_io.h"
#include "motion_model_estimation/io/trc.h"

namespace mme {
namespace {

const std::string kReal = MME_TEST_DATA_DIR "/real/";

/// Fresh directory per test so concurrent test runs never collide.
class TrcTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string templ = ::testing::TempDir() + "mme_trc_XXXXXX";
    ASSERT_NE(mkdtemp(templ.data()), nullptr);
    dir_ = templ;
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& content) const {
    const std::string path = dir_ + "/" + name;
    std::ofstream(path, std::ios::binary) << content;
    return path;
  }
  std::string dir_;
};

/// Expects an InputError whose message contains every one of `parts`.
template <typename F>
void expectInputError(F&& f, const std::vector<std::string>& parts) {
  try {
    f();
    FAIL() << "no InputError thrown";
  } catch (const InputError& e) {
    for (const std::string& part : parts)
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos)
          << "message '" << e.what() << "' lacks '" << part << "'";
  }
}

const char* kHeader =
    "PathFileType\t4\t(X/Y/Z)\tsmall.trc\n"
    "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame\t"
    "OrigNumFrames\n";

// ----------------------------------------------------------------------------- real files

TEST(TrcRealFiles, LoadWithReadmeCountsAndRates) {
  struct Expected {
    const char* file;
    int markers;
    double rate;
    int frames;
  };
  const Expected expected[] = {{"subject01_walk1.trc", 41, 60.0, 151},
                               {"motion_capture_walk.trc", 41, 100.0, 238},
                               {"arm26_elbow_flex.trc", 3, 120.0, 121}};
  for (const Expected& e : expected) {
    SCOPED_TRACE(e.file);
    const Trajectory t = readTrc(kReal + e.file);
    EXPECT_EQ(t.numMarkers(), e.markers);
    EXPECT_EQ(t.numFrames(), e.frames);
    EXPECT_DOUBLE_EQ(t.frame_rate_hz, e.rate);
    EXPECT_EQ(t.validate(), "");
    EXPECT_EQ(t.countOccluded(), 0u);  // these exports have no gaps
    ASSERT_EQ(t.frame_numbers.size(), static_cast<size_t>(e.frames));
    EXPECT_EQ(t.frame_numbers.front(), 1u);
    EXPECT_EQ(t.frame_numbers.back(), static_cast<uint32_t>(e.frames));
    EXPECT_DOUBLE_EQ(t.times_s.front(), 0.0);
  }
}

TEST(TrcRealFiles, Arm26KnownValuesInMetres) {
  const Trajectory t = readTrc(kReal + "arm26_elbow_flex.trc");
  EXPECT_EQ(t.marker_names,
            (std::vector<std::string>{"r_acromion", "r_humerus_epicondyle", "r_radius_styloid"}));
  // Row 1: "1  0  -13.05452443  839.50547557  169.5054756  ..." (mm).
  EXPECT_NEAR(t.position(0, 0).x(), -0.01305452443, 1e-12);
  EXPECT_NEAR(t.position(0, 0).y(), 0.83950547557, 1e-12);
  EXPECT_NEAR(t.position(0, 0).z(), 0.1695054756, 1e-12);
  // Last row: "121  1  -12.03835742  840.52164258  170.5216426  ..."; third marker x.
  EXPECT_NEAR(t.position(120, 0).x(), -0.01203835742, 1e-12);
  EXPECT_NEAR(t.times_s[120], 1.0, 1e-12);
  EXPECT_NEAR(t.times_s[1], 0.008333333, 1e-12);  // the Time column, not frame/rate
}

TEST(TrcRealFiles, Subject01KnownValuesAndTimeColumn) {
  const Trajectory t = readTrc(kReal + "subject01_walk1.trc");
  EXPECT_EQ(t.marker_names.front(), "R.ASIS");
  EXPECT_EQ(t.marker_names.back(), "Top.Head");
  // Row 2: "2  0.017000  617.998110  1053.217530  168.513170 ...": the file's Time column
  // (0.017, not 1/60) is what times_s holds.
  EXPECT_NEAR(t.times_s[1], 0.017, 1e-12);
  EXPECT_NEAR(t.position(1, 0).x(), 0.61799811, 1e-12);
  EXPECT_NEAR(t.position(1, 0).y(), 1.05321753, 1e-12);
  EXPECT_NEAR(t.position(1, 0).z(), 0.16851317, 1e-12);
}

TEST(TrcRealFiles, MotionCaptureWalkPaddedMetadataLine) {
  // Its values line is "  100.0\t\t  100.0\t\t    238\t\t     41\t\t mm\t...": doubled tabs.
  const Trajectory t = readTrc(kReal + "motion_capture_walk.trc");
  EXPECT_DOUBLE_EQ(t.frame_rate_hz, 100.0);
  EXPECT_EQ(t.marker_names.front(), "R.Shoulder");
  EXPECT_NEAR(t.position(0, 0).x(), -0.65263, 1e-12);
  EXPECT_NEAR(t.position(0, 0).y(), 1.529542, 1e-12);
  EXPECT_NEAR(t.position(0, 0).z(), -0.09452, 1e-12);
  // Last row: "238  2.37000  2305.031  1522.685  -100.799".
  EXPECT_NEAR(t.times_s.back(), 2.37, 1e-12);
  EXPECT_NEAR(t.position(237, 0).x(), 2.305031, 1e-12);
}

TEST(TrajectoryIo, DispatchesByExtension) {
  const Trajectory t = readTrajectoryFile(kReal + "arm26_elbow_flex.trc");
  EXPECT_EQ(t.numMarkers(), 3);
  const Trajectory c = readTrajectoryFile(kReal + "Sample02_pc_int.c3d");
  EXPECT_EQ(c.numMarkers(), 36);
}

TEST(TrajectoryIo, FileExtension) {
  EXPECT_EQ(fileExtension("a/b/walk.TRC"), ".trc");
  EXPECT_EQ(fileExtension("walk.c3d"), ".c3d");
  EXPECT_EQ(fileExtension("x.tar.GZ"), ".gz");
  EXPECT_EQ(fileExtension("noext"), "");
  EXPECT_EQ(fileExtension("runs.v2/data"), "");
  EXPECT_EQ(fileExtension("dir/.hidden"), "");
  EXPECT_EQ(fileExtension(""), "");
}

TEST_F(TrcTest, UnknownExtensionNamesFileAndExtension) {
  const std::string path = write("walk.csv", "1,2,3\n");
  expectInputError([&] { readTrajectoryFile(path); },
                   {"walk.csv", "unsupported trajectory file extension '.csv'", ".trc", ".c3d"});
  expectInputError([&] { readTrajectoryFile(dir_ + "/noext"); }, {"noext", "''"});
}

// ----------------------------------------------------------------------------- layout variants

TEST_F(TrcTest, CrlfTrailingTabsShortRowsAndGaps) {
  std::string text = std::string(kHeader) +
                     "100\t100\t4\t2\tcm\t100\t1\t4\n"
                     "Frame#\tTime\tA\t\t\tB\t\t\t\n"
                     "\t\tX1\tY1\tZ1\tX2\tY2\tZ2\t\n"
                     "\n"
                     "1\t0\t1.5\t-2\t3\t10\t20\t30\t\n"  // trailing tab
                     "2\t0.01\t\t\t\t10\t20\t30\n"       // A empty
                     "3\t0.02\t0\t0\t0\t+1e1\t2E1\t.3e2\t\t\n"  // A at exactly 0,0,0
                     "4\t0.03\t1\t2\n";                  // short: A partial, B missing
  // CRLF everywhere.
  std::string crlf;
  for (char c : text) {
    if (c == '\n') crlf += '\r';
    crlf += c;
  }
  const Trajectory t = readTrc(write("small.trc", crlf));
  ASSERT_EQ(t.numMarkers(), 2);
  ASSERT_EQ(t.numFrames(), 4);
  EXPECT_EQ(t.marker_names, (std::vector<std::string>{"A", "B"}));
  EXPECT_DOUBLE_EQ(t.frame_rate_hz, 100.0);
  EXPECT_EQ(t.validate(), "");
  // cm -> m.
  EXPECT_FALSE(t.isOccluded(0, 0));
  EXPECT_NEAR(t.position(0, 0).x(), 0.015, 1e-15);
  EXPECT_NEAR(t.position(0, 0).y(), -0.02, 1e-15);
  EXPECT_NEAR(t.position(0, 1).z(), 0.30, 1e-15);
  EXPECT_TRUE(t.isOccluded(1, 0));
  EXPECT_FALSE(t.isOccluded(1, 1));
  EXPECT_TRUE(t.isOccluded(2, 0));
  EXPECT_FALSE(t.isOccluded(2, 1));
  EXPECT_NEAR(t.position(2, 1).x(), 0.10, 1e-15);
  EXPECT_NEAR(t.position(2, 1).z(), 0.30, 1e-15);
  EXPECT_TRUE(t.isOccluded(3, 0));
  EXPECT_TRUE(t.isOccluded(3, 1));
  for (int f = 1; f < 4; ++f) EXPECT_TRUE(t.position(f, 0).isZero(0.0)) << f;
  EXPECT_TRUE(t.position(3, 1).isZero(0.0));
  EXPECT_EQ(t.countOccluded(), 4u);
  EXPECT_EQ(t.frame_numbers, (std::vector<uint32_t>{1, 2, 3, 4}));
  EXPECT_NEAR(t.times_s[3], 0.03, 1e-15);
}

TEST_F(TrcTest, MetresNanGapsAndStaleNumMarkers) {
  // NumMarkers says 3 but one name is given: names take precedence. NaN = gap (OpenSim 4).
  const std::string path = write("m.trc", std::string(kHeader) +
                                              "50\t50\t2\t3\tm\t50\t1\t2\n"
                                              "Frame#\tTime\tP\n"
                                              "\t\tX1\tY1\tZ1\n"
                                              "7\t0\t1\t2\t3\n"
                                              "8\t0.02\tNaN\tnan\tNaN\n");
  const Trajectory t = readTrc(path);
  ASSERT_EQ(t.numMarkers(), 1);
  ASSERT_EQ(t.numFrames(), 2);
  EXPECT_EQ(t.position(0, 0), Eigen::Vector3d(1, 2, 3));
  EXPECT_TRUE(t.isOccluded(1, 0));
  EXPECT_TRUE(t.position(1, 0).isZero(0.0));
  EXPECT_EQ(t.frame_numbers, (std::vector<uint32_t>{7, 8}));
}

// ----------------------------------------------------------------------------- cut-off files

/// The first `lines` lines of a text file, each with its '\n'.
std::string firstLines(const std::string& path, int lines) {
  std::ifstream in(path, std::ios::binary);
  std::string out, line;
  for (int k = 0; k < lines && std::getline(in, line); ++k) out += line + "\n";
  return out;
}

TEST_F(TrcTest, CutOffCopyWarnsWithDeclaredAndFoundFramesAndKeepsTheRows) {
  // A cut-off copy of a real file: its 5 header lines, the blank line and the first 14 of the
  // 151 rows its NumFrames declares.
  const Trajectory full = readTrc(kReal + "subject01_walk1.trc");
  ASSERT_EQ(full.numFrames(), 151);
  const std::string path = write("cut.trc", firstLines(kReal + "subject01_walk1.trc", 6 + 14));
  std::vector<std::string> warnings;
  const Trajectory t = readTrc(path, &warnings);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0], path + ": header declares 151 frames, found 14 (file cut short?)");
  // The rows that are there, as in the whole file.
  ASSERT_EQ(t.numFrames(), 14);
  EXPECT_EQ(t.marker_names, full.marker_names);
  EXPECT_DOUBLE_EQ(t.frame_rate_hz, 60.0);
  EXPECT_EQ(t.validate(), "");
  EXPECT_EQ(t.frame_numbers,
            std::vector<uint32_t>(full.frame_numbers.begin(), full.frame_numbers.begin() + 14));
  EXPECT_EQ(t.times_s, std::vector<double>(full.times_s.begin(), full.times_s.begin() + 14));
  const size_t samples = 14 * static_cast<size_t>(full.numMarkers());
  ASSERT_EQ(t.positions_m.size(), samples);
  for (size_t k = 0; k < samples; ++k) EXPECT_EQ(t.positions_m[k], full.positions_m[k]) << k;
  EXPECT_EQ(t.occluded, std::vector<uint8_t>(full.occluded.begin(), full.occluded.begin() + samples));

  // Through the extension dispatch, the same warning; without a list the rows still load.
  std::vector<std::string> dispatched;
  EXPECT_EQ(readTrajectoryFile(path, &dispatched).numFrames(), 14);
  EXPECT_EQ(dispatched, warnings);
  EXPECT_EQ(readTrc(path).numFrames(), 14);
}

TEST_F(TrcTest, NoWarningForCompleteFilesOrMoreRowsThanDeclared) {
  for (const char* file : {"subject01_walk1.trc", "motion_capture_walk.trc", "arm26_elbow_flex.trc"}) {
    SCOPED_TRACE(file);
    std::vector<std::string> warnings;
    readTrc(kReal + file, &warnings);
    EXPECT_EQ(warnings, std::vector<std::string>{});
  }
  // A stale NumFrames below the row count, or one that is not a count: the rows are the data.
  const std::string rows = "Frame#\tTime\tP\n\t\tX1\tY1\tZ1\n1\t0\t1\t2\t3\n2\t0.1\t1\t2\t3\n";
  for (const char* num_frames : {"1", "2", "n/a", "-3", "2.5"}) {
    SCOPED_TRACE(num_frames);
    const std::string path = write("stale.trc", std::string(kHeader) + "10\t10\t" + num_frames +
                                                    "\t1\tmm\t10\t1\t2\n" + rows);
    std::vector<std::string> warnings;
    EXPECT_EQ(readTrc(path, &warnings).numFrames(), 2);
    EXPECT_EQ(warnings, std::vector<std::string>{});
  }
  // One row short of NumFrames 3: warned.
  const std::string path =
      write("short.trc", std::string(kHeader) + "10\t10\t3\t1\tmm\t10\t1\t3\n" + rows);
  std::vector<std::string> warnings;
  EXPECT_EQ(readTrc(path, &warnings).numFrames(), 2);
  EXPECT_EQ(warnings, std::vector<std::string>{path + ": header declares 3 frames, found 2 (file cut short?)"});
}

// A header that disagrees with the data: NumMarkers 3 over two names, and a second name whose
// columns no row has (the header names a marker the data lack): both said, both figures named.
TEST_F(TrcTest, HeaderMarkerCountsCheckedAgainstTheData) {
  const std::string path = write("counts.trc", std::string(kHeader) + "10\t10\t2\t3\tmm\t10\t1\t2\n"
                                                   "Frame#\tTime\tP\t\t\tQ\n"
                                                   "\t\tX1\tY1\tZ1\tX2\tY2\tZ2\n"
                                                   "1\t0\t1\t2\t3\n2\t0.1\t1\t2\t3\n");
  std::vector<std::string> warnings;
  const Trajectory t = readTrc(path, &warnings);
  EXPECT_EQ(t.numMarkers(), 2);
  ASSERT_EQ(warnings.size(), 2u) << ::testing::PrintToString(warnings);
  EXPECT_EQ(warnings[0], path + ": header declares 3 markers (NumMarkers), its names line names 2: the names are used");
  EXPECT_NE(warnings[1].find(path + ": the names line names 2 markers but the widest data row holds 3 "
                             "coordinate fields (1 markers): 'Q' and after are never in the data"),
            std::string::npos)
      << warnings[1];
  // A header that agrees with its data: no word.
  const std::string good = write("good.trc", std::string(kHeader) + "10\t10\t2\t2\tmm\t10\t1\t2\n"
                                                  "Frame#\tTime\tP\t\t\tQ\n"
                                                  "\t\tX1\tY1\tZ1\tX2\tY2\tZ2\n"
                                                  "1\t0\t1\t2\t3\t4\t5\t6\n2\t0.1\t1\t2\t3\n");
  warnings.clear();
  readTrc(good, &warnings);
  EXPECT_EQ(warnings, std::vector<std::string>{});
}

// An absurd sample (1e308 mm) is refused where it is read, naming the file, line, frame and
// marker, not later as a search's infinite bounds.
TEST_F(TrcTest, AbsurdSampleNamesFileLineFrameAndMarker) {
  const std::string path = write("absurd.trc", std::string(kHeader) + "10\t10\t2\t2\tmm\t10\t1\t2\n"
                                                    "Frame#\tTime\tP\t\t\tQ\n"
                                                    "\t\tX1\tY1\tZ1\tX2\tY2\tZ2\n"
                                                    "1\t0\t1\t2\t3\t4\t5\t6\n"
                                                    "2\t0.1\t1\t2\t3\t4\t1e308\t6\n");
  expectInputError([&] { readTrc(path); },
                   {path + ":7: frame 2, marker 'Q': coordinate '1e308' is 1e+305 m from the origin"});
}

TEST_F(TrcTest, CutBeforeTheFirstRowIsAnErrorNamingTheDeclaredFrames) {
  const std::string path = write("header_only.trc", firstLines(kReal + "subject01_walk1.trc", 6));
  expectInputError([&] { readTrc(path); },
                   {"header_only.trc", "no data rows (header declares 151 frames)"});
}

// ----------------------------------------------------------------------------- round trips

TEST_F(TrcTest, WriteReadRoundTripKeepsEverything) {
  Trajectory original = readTrc(kReal + "subject01_walk1.trc");
  // Add gaps and awkward values so the round trip covers them.
  original.occluded[5] = 1;
  original.positions_m[5].setZero();
  for (int i = 0; i < original.numMarkers(); ++i) {
    original.occluded[10 * original.numMarkers() + i] = 1;  // a fully occluded frame
    original.position(10, i).setZero();
  }
  original.position(3, 2) = Eigen::Vector3d(1.0 / 3.0, -2.0 / 7.0, 1e-7);
  original.times_s[4] = 0.1 + 0.2;  // not exactly representable in decimal
  for (const std::string units : {"mm", "cm", "m"}) {
    SCOPED_TRACE(units);
    const std::string path = dir_ + "/out_" + units + ".trc";
    writeTrc(path, original, units);
    const Trajectory back = readTrc(path);
    ASSERT_EQ(back.marker_names, original.marker_names);
    ASSERT_EQ(back.numFrames(), original.numFrames());
    EXPECT_DOUBLE_EQ(back.frame_rate_hz, original.frame_rate_hz);
    EXPECT_EQ(back.frame_numbers, original.frame_numbers);
    EXPECT_EQ(back.times_s, original.times_s);  // shortest round-trip formatting: exact
    EXPECT_EQ(back.occluded, original.occluded);
    double max_error = 0.0;
    for (size_t k = 0; k < original.positions_m.size(); ++k)
      max_error = std::max(max_error, (back.positions_m[k] - original.positions_m[k])
                                          .cwiseAbs()
                                          .maxCoeff());
    EXPECT_LT(max_error, 1e-9);
  }
  // Atomic write: no temporary file left next to the outputs.
  for (const auto& entry : std::filesystem::directory_iterator(dir_))
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos)
        << entry.path();
}

TEST_F(TrcTest, WriteOverwritesExistingFile) {
  const std::string path = write("over.trc", "old content that is not a TRC file\n");
  const Trajectory t = readTrc(kReal + "arm26_elbow_flex.trc");
  writeTrc(path, t);
  EXPECT_EQ(readTrc(path).numFrames(), 121);
}

TEST_F(TrcTest, WriteRejectsBadUnitsAndUnwritableNames) {
  Trajectory t = readTrc(kReal + "arm26_elbow_flex.trc");
  expectInputError([&] { writeTrc(dir_ + "/x.trc", t, "inch"); }, {"x.trc", "inch"});
  t.marker_names[1] = "bad\tname";
  expectInputError([&] { writeTrc(dir_ + "/y.trc", t); }, {"y.trc", "bad"});
  EXPECT_FALSE(std::filesystem::exists(dir_ + "/x.trc"));
  EXPECT_FALSE(std::filesystem::exists(dir_ + "/y.trc"));
  expectInputError([&] { writeTrc(dir_ + "/no/such/dir/z.trc", readTrc(kReal + "arm26_elbow_flex.trc")); },
                   {"z.trc"});
}

// ----------------------------------------------------------------------------- errors

TEST_F(TrcTest, NonNumericFieldNamesFileLineAndMarker) {
  const std::string path = write("bad_field.trc", std::string(kHeader) +
                                                      "60\t60\t2\t1\tmm\t60\t1\t2\n"
                                                      "Frame#\tTime\tP\t\t\n"
                                                      "\t\tX1\tY1\tZ1\n"
                                                      "\n"
                                                      "1\t0\t1\t2\t3\n"
                                                      "2\t0.1\t1\t2x\t3\n");
  expectInputError([&] { readTrc(path); }, {"bad_field.trc:8:", "'P'", "'2x'"});
}

TEST_F(TrcTest, MalformedHeadersAndRows) {
  struct Case {
    const char* name;
    std::string content;
    std::vector<std::string> parts;
  };
  const std::string names = "Frame#\tTime\tP\t\t\n\t\tX1\tY1\tZ1\n";
  const Case cases[] = {
      {"units.trc", std::string(kHeader) + "60\t60\t1\t1\tinch\t60\t1\t1\n" + names + "1\t0\t1\t2\t3\n",
       {"units.trc:3:", "Units 'inch'"}},
      {"rate.trc", std::string(kHeader) + "abc\t60\t1\t1\tmm\t60\t1\t1\n" + names + "1\t0\t1\t2\t3\n",
       {"rate.trc:3:", "DataRate"}},
      {"zero_rate.trc", std::string(kHeader) + "0\t60\t1\t1\tmm\t60\t1\t1\n" + names + "1\t0\t1\t2\t3\n",
       {"zero_rate.trc:3:", "DataRate"}},
      {"nonames.trc", std::string(kHeader) + "60\t60\t1\t1\tmm\t60\t1\t1\nFrame#\tTime\t\t\n",
       {"nonames.trc:4:", "no marker names"}},
      {"notrc.trc", "hello\tworld\n", {"notrc.trc:1:", "PathFileType"}},
      {"empty.trc", "", {"empty.trc", "empty"}},
      {"short_meta.trc", std::string(kHeader) + "60\t60\n" + names + "1\t0\t1\t2\t3\n",
       {"short_meta.trc:3:", "values"}},
      {"nodata.trc", std::string(kHeader) + "60\t60\t1\t1\tmm\t60\t1\t1\n" + names + "\n",
       {"nodata.trc", "no data rows"}},
      {"extra.trc", std::string(kHeader) + "60\t60\t1\t1\tmm\t60\t1\t1\n" + names + "1\t0\t1\t2\t3\t4\n",
       {"extra.trc:6:", "only 1 markers"}},
      {"frame.trc", std::string(kHeader) + "60\t60\t1\t1\tmm\t60\t1\t1\n" + names + "1.5\t0\t1\t2\t3\n",
       {"frame.trc:6:", "Frame#"}},
      {"time.trc", std::string(kHeader) + "60\t60\t1\t1\tmm\t60\t1\t1\n" + names + "1\tt0\t1\t2\t3\n",
       {"time.trc:6:", "Time"}},
      {"inf.trc", std::string(kHeader) + "60\t60\t1\t1\tmm\t60\t1\t1\n" + names + "1\t0\tinf\t2\t3\n",
       {"inf.trc:6:", "infinite"}},
      {"truncated.trc", std::string(kHeader), {"truncated.trc", "missing metadata values"}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string path = write(c.name, c.content);
    expectInputError([&] { readTrc(path); }, c.parts);
  }
}

TEST_F(TrcTest, MissingFileNamesFile) {
  expectInputError([&] { readTrc(dir_ + "/missing_walk.trc"); },
                   {"missing_walk.trc", "cannot open"});
  expectInputError([&] { readTrajectoryFile(dir_ + "/missing_walk.trc"); }, {"missing_walk.trc"});
}

TEST_F(TrcTest, DirectoryIsNotReadable) {
  std::filesystem::create_directory(dir_ + "/folder.trc");
  expectInputError([&] { readTrc(dir_ + "/folder.trc"); }, {"folder.trc"});
}

}  // namespace
}  // namespace mme
