// Tests of the C3D reader: the real c3d.org samples load with the counts, rates, gap shares and
// values an independent script found in them (the two Sample02 encodings agree), synthetic
// files cover the three processor formats x two storage formats, analog skipping, units and
// LABELS2, and corrupt files (truncated, garbage, randomly mutated) give InputError naming the
// file rather than a crash.

#include <gtest/gtest.h>
#include <stdlib.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/io/c3d.h"
#include "motion_model_estimation/io/trajectory_io.h"

namespace mme {
namespace {

const std::string kReal = MME_TEST_DATA_DIR "/real/";

std::vector<uint8_t> readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<uint8_t>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

class C3dTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string templ = ::testing::TempDir() + "mme_c3d_XXXXXX";
    ASSERT_NE(mkdtemp(templ.data()), nullptr);
    dir_ = templ;
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string write(const std::string& name, const std::vector<uint8_t>& bytes) const {
    const std::string path = dir_ + "/" + name;
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    return path;
  }
  std::string dir_;
};

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

double occludedShare(const Trajectory& t) {
  return static_cast<double>(t.countOccluded()) / static_cast<double>(t.occluded.size());
}

/// Occluded samples sit at (0,0,0); visible ones never do.
void expectGapConvention(const Trajectory& t) {
  for (size_t k = 0; k < t.occluded.size(); ++k) {
    if (t.occluded[k])
      ASSERT_TRUE(t.positions_m[k].isZero(0.0)) << k;
    else
      ASSERT_FALSE(t.positions_m[k].isZero(0.0)) << k;
  }
}

// ----------------------------------------------------------------------------- real files

TEST(C3dRealFiles, LoadWithReadmeCountsAndRates) {
  struct Expected {
    const char* file;
    int markers;
    double rate;
    int frames;
    uint32_t first_frame;
    const char* first_label;
    const char* last_label;
  };
  const Expected expected[] = {
      {"Sample01_Eb015pi.c3d", 26, 50.0, 450, 1, "RFT1", "pv4"},
      {"Sample26_Walking_Hybrid_1_1.c3d", 25, 240.0, 672, 290, "R_ASIS", "L_MT_5"},
      {"Sample02_dec_real.c3d", 36, 50.0, 89, 1, "RFT1", "LFA3"},
      {"Sample02_pc_int.c3d", 36, 50.0, 89, 1, "RFT1", "LFA3"},
  };
  for (const Expected& e : expected) {
    SCOPED_TRACE(e.file);
    const Trajectory t = readC3d(kReal + e.file);
    EXPECT_EQ(t.numMarkers(), e.markers);
    EXPECT_EQ(t.numFrames(), e.frames);
    EXPECT_DOUBLE_EQ(t.frame_rate_hz, e.rate);
    EXPECT_EQ(t.validate(), "");
    ASSERT_FALSE(t.marker_names.empty());
    EXPECT_EQ(t.marker_names.front(), e.first_label);
    EXPECT_EQ(t.marker_names.back(), e.last_label);  // trailing label padding trimmed
    EXPECT_EQ(t.frame_numbers.front(), e.first_frame);
    EXPECT_EQ(t.frame_numbers.back(), e.first_frame + static_cast<uint32_t>(e.frames) - 1);
    EXPECT_DOUBLE_EQ(t.times_s.front(), 0.0);
    EXPECT_NEAR(t.times_s.back(), (e.frames - 1) / e.rate, 1e-12);
    expectGapConvention(t);
  }
}

TEST(C3dRealFiles, Sample26GapsAreTheZeroSamples) {
  // Float storage, Qualisys. An independent script counted 3902 of the 16800 samples at exactly
  // 0,0,0, each with residual word 65535.0 (the unsigned form of -1); no other sample has an
  // invalid residual. 3902 / 16800 = 23.2 %.
  const Trajectory t = readC3d(kReal + "Sample26_Walking_Hybrid_1_1.c3d");
  EXPECT_GT(occludedShare(t), 0.15);
  EXPECT_LT(occludedShare(t), 0.30);
  EXPECT_EQ(t.countOccluded(), 3902u);
  // Frame 100 (index), markers 0 and 1, as stored (mm floats).
  EXPECT_FALSE(t.isOccluded(100, 0));
  EXPECT_NEAR(t.position(100, 0).x(), -1200.0076904296875e-3, 1e-12);
  EXPECT_NEAR(t.position(100, 0).y(), -57.246673583984375e-3, 1e-12);
  EXPECT_NEAR(t.position(100, 0).z(), 981.2091064453125e-3, 1e-12);
  EXPECT_NEAR(t.position(100, 1).y(), 167.55870056152344e-3, 1e-12);
}

TEST(C3dRealFiles, Sample01FewGapsAndKnownValue) {
  // Integer storage, scale 0.0833 mm. 226 of 11700 samples (1.9 %) have residual -1, and they
  // are exactly the 0,0,0 ones.
  const Trajectory t = readC3d(kReal + "Sample01_Eb015pi.c3d");
  EXPECT_GT(t.countOccluded(), 0u);
  EXPECT_LT(occludedShare(t), 0.10);
  EXPECT_EQ(t.countOccluded(), 226u);
  // Frame index 10, marker 5 (LFT3): raw int16 x scale = (-95.4167, 4.6667, 44.2500) mm.
  EXPECT_NEAR(t.position(10, 5).x(), -95.41666951030493e-3, 1e-9);
  EXPECT_NEAR(t.position(10, 5).y(), 4.666666805744171e-3, 1e-9);
  EXPECT_NEAR(t.position(10, 5).z(), 44.250001318752766e-3, 1e-9);
}

TEST(C3dRealFiles, Sample02DecAndIntelEncodingsAgree) {
  const Trajectory dec = readC3d(kReal + "Sample02_dec_real.c3d");
  const Trajectory pc = readC3d(kReal + "Sample02_pc_int.c3d");
  ASSERT_EQ(dec.marker_names, pc.marker_names);
  ASSERT_EQ(dec.numFrames(), pc.numFrames());
  EXPECT_DOUBLE_EQ(dec.frame_rate_hz, pc.frame_rate_hz);
  EXPECT_EQ(dec.frame_numbers, pc.frame_numbers);
  EXPECT_EQ(dec.occluded, pc.occluded);
  EXPECT_EQ(pc.countOccluded(), 228u);  // 7.1 % gaps in both

  // Integer scale of the Intel file (header words 7-8, equal to its POINT:SCALE), in mm.
  const std::vector<uint8_t> bytes = readBytes(kReal + "Sample02_pc_int.c3d");
  ASSERT_GE(bytes.size(), 16u);
  float scale_mm;
  std::memcpy(&scale_mm, &bytes[12], 4);  // little-endian file; the test hosts are too
  ASSERT_NEAR(scale_mm, 0.28118, 1e-5);
  double max_diff = 0.0;
  for (size_t k = 0; k < pc.positions_m.size(); ++k)
    if (!pc.occluded[k])
      max_diff = std::max(max_diff, (dec.positions_m[k] - pc.positions_m[k]).cwiseAbs().maxCoeff());
  // The integer file truncates to whole scale units: at most one unit apart.
  EXPECT_LE(max_diff, scale_mm * 1e-3 * 1.001);
  EXPECT_GT(max_diff, 0.0);  // genuinely two encodings

  // DEC VAX floats decoded exactly (value from an independent decoder), frame 40, marker 3.
  EXPECT_NEAR(dec.position(40, 3).x(), 407.1513366699219e-3, 1e-12);
  EXPECT_NEAR(dec.position(40, 3).y(), 855.6364135742188e-3, 1e-12);
  EXPECT_NEAR(dec.position(40, 3).z(), 381.0014343261719e-3, 1e-12);
}

// ----------------------------------------------------------------------------- synthetic files

/// Minimal C3D writer for the tests: one POINT group, optional analog values to skip.
struct Synth {
  int processor = 84;  // 84 Intel, 85 DEC, 86 MIPS
  bool float_storage = false;
  double scale = 0.1;  // magnitude; negative is written for float storage
  double rate = 100.0;
  std::string units = "mm";
  int analog_per_frame = 0;
  uint16_t first_frame = 1;
  std::vector<std::string> labels;
  int frames = 0;
  std::vector<std::array<double, 4>> samples;  // frames x points: x, y, z (file units), residual

  void put16(std::vector<uint8_t>* b, size_t at, int v) const {
    const uint16_t u = static_cast<uint16_t>(v);
    if (processor == 86) {
      (*b)[at] = u >> 8;
      (*b)[at + 1] = u & 0xff;
    } else {
      (*b)[at] = u & 0xff;
      (*b)[at + 1] = u >> 8;
    }
  }
  void putFloat(std::vector<uint8_t>* b, size_t at, double value) const {
    float f = static_cast<float>(value);
    if (processor == 85) f *= 4.0f;  // VAX F-float = IEEE bits / 4
    uint32_t bits;
    std::memcpy(&bits, &f, 4);
    const uint8_t le[4] = {uint8_t(bits), uint8_t(bits >> 8), uint8_t(bits >> 16), uint8_t(bits >> 24)};
    for (int k = 0; k < 4; ++k) {
      uint8_t byte;
      if (value == 0.0) byte = 0;  // VAX zero is all-zero bits, not IEEE 0 x 4
      else if (processor == 84) byte = le[k];
      else if (processor == 86) byte = le[3 - k];
      else byte = le[(k + 2) % 4];  // DEC: the high word first
      (*b)[at + k] = byte;
    }
  }

  std::vector<uint8_t> build() const {
    const int points = static_cast<int>(labels.size());
    // Parameter entries, appended to `p` (offsets in the section are relative anyway).
    std::vector<uint8_t> p = {1, 0x50, 0, static_cast<uint8_t>(processor)};
    auto entry = [&](int8_t id, const std::string& name, int type, std::vector<int> dims,
                     const std::vector<uint8_t>& data) {
      p.push_back(static_cast<uint8_t>(name.size()));
      p.push_back(static_cast<uint8_t>(id));
      p.insert(p.end(), name.begin(), name.end());
      const size_t offset_at = p.size();
      p.resize(p.size() + 2);
      if (id > 0) {
        p.push_back(static_cast<uint8_t>(type));
        p.push_back(static_cast<uint8_t>(dims.size()));
        for (int d : dims) p.push_back(static_cast<uint8_t>(d));
        p.insert(p.end(), data.begin(), data.end());
      }
      p.push_back(0);  // empty description
      put16(&p, offset_at, static_cast<int>(p.size() - offset_at));
    };
    auto i16 = [&](int v) {
      std::vector<uint8_t> d(2);
      put16(&d, 0, v);
      return d;
    };
    auto f32 = [&](double v) {
      std::vector<uint8_t> d(4);
      putFloat(&d, 0, v);
      return d;
    };
    auto chars = [](const std::vector<std::string>& s, size_t width) {
      std::vector<uint8_t> d;
      for (const std::string& x : s) {
        std::string padded = x;
        padded.resize(width, ' ');
        d.insert(d.end(), padded.begin(), padded.end());
      }
      return d;
    };
    const double signed_scale = float_storage ? -scale : scale;
    // Parameter blocks needed (labels dominate): estimate generously, then fix DATA_START.
    const int label_bytes = points * 4 + 64;
    const int param_blocks = 1 + (label_bytes + 400) / 512;
    const int data_start = 2 + param_blocks;
    entry(-1, "POINT", 0, {}, {});
    entry(1, "USED", 2, {}, i16(points));
    entry(1, "SCALE", 4, {}, f32(signed_scale));
    entry(1, "RATE", 4, {}, f32(rate));
    entry(1, "FRAMES", 2, {}, i16(frames));
    entry(1, "DATA_START", 2, {}, i16(data_start));
    entry(1, "UNITS", -1, {static_cast<int>(units.size())}, chars({units}, units.size()));
    const size_t first_batch = std::min<size_t>(labels.size(), 255);
    entry(1, "LABELS", -1, {4, static_cast<int>(first_batch)},
          chars(std::vector<std::string>(labels.begin(), labels.begin() + first_batch), 4));
    if (labels.size() > 255)
      entry(1, "LABELS2", -1, {4, static_cast<int>(labels.size() - 255)},
            chars(std::vector<std::string>(labels.begin() + 255, labels.end()), 4));
    entry(-2, "ANALOG", 0, {}, {});
    entry(2, "USED", 2, {}, i16(analog_per_frame));
    p.push_back(0);  // terminator
    p.push_back(0);
    EXPECT_LE(p.size(), static_cast<size_t>(param_blocks) * 512);
    p[2] = static_cast<uint8_t>(param_blocks);

    const size_t value_size = float_storage ? 4 : 2;
    const size_t frame_bytes = (4 * points + analog_per_frame) * value_size;
    std::vector<uint8_t> b((data_start - 1) * 512 + frames * frame_bytes);
    b.resize((b.size() + 511) / 512 * 512);
    b[0] = 2;
    b[1] = 0x50;
    put16(&b, 2, points);
    put16(&b, 4, analog_per_frame);
    put16(&b, 6, first_frame);
    put16(&b, 8, first_frame + frames - 1);
    putFloat(&b, 12, signed_scale);
    put16(&b, 16, data_start);
    put16(&b, 18, analog_per_frame);
    putFloat(&b, 20, rate);
    std::copy(p.begin(), p.end(), b.begin() + 512);
    for (int t = 0; t < frames; ++t) {
      size_t at = (data_start - 1) * 512 + t * frame_bytes;
      for (int i = 0; i < points; ++i) {
        const std::array<double, 4>& s = samples[t * points + i];
        for (int c = 0; c < 4; ++c, at += value_size) {
          if (float_storage) putFloat(&b, at, s[c]);
          else put16(&b, at, static_cast<int>(std::lround(c < 3 ? s[c] / scale : s[c])));
        }
      }
      // Analog values that would be read as huge coordinates if not skipped.
      for (int a = 0; a < analog_per_frame; ++a, at += value_size) {
        if (float_storage) putFloat(&b, at, 31000.0);
        else put16(&b, at, 31000);
      }
    }
    return b;
  }
};

Synth threeFrameScene() {
  Synth s;
  s.labels = {"A", "B"};
  s.frames = 3;
  s.analog_per_frame = 5;
  s.first_frame = 40000;  // above 32767: header words are unsigned
  s.scale = 0.5;
  s.samples = {
      {{100.5, -200.0, 300.0, 2}}, {{1.0, 2.0, 3.0, 0}},     // frame 0
      {{0.0, 0.0, 0.0, 5}},        {{4.5, -5.0, 6.0, -1}},   // frame 1: zero gap, residual gap
      {{-7.0, 8.0, 0.0, 1}},       {{0.0, 0.5, 0.0, 0}},     // frame 2: zeros in one axis only
  };
  return s;
}

TEST_F(C3dTest, AllProcessorsAndStorageFormats) {
  for (int processor : {84, 85, 86})
    for (bool float_storage : {false, true}) {
      SCOPED_TRACE("processor " + std::to_string(processor) + (float_storage ? " float" : " int"));
      Synth s = threeFrameScene();
      s.processor = processor;
      s.float_storage = float_storage;
      const Trajectory t = readC3d(write("synth.c3d", s.build()));
      ASSERT_EQ(t.marker_names, (std::vector<std::string>{"A", "B"}));
      ASSERT_EQ(t.numFrames(), 3);
      EXPECT_DOUBLE_EQ(t.frame_rate_hz, 100.0);
      EXPECT_EQ(t.frame_numbers, (std::vector<uint32_t>{40000, 40001, 40002}));
      EXPECT_NEAR(t.times_s[2], 0.02, 1e-15);
      EXPECT_EQ(t.occluded, (std::vector<uint8_t>{0, 0, 1, 1, 0, 0}));
      EXPECT_NEAR(t.position(0, 0).x(), 0.1005, 1e-12);
      EXPECT_NEAR(t.position(0, 0).y(), -0.2, 1e-12);
      EXPECT_NEAR(t.position(0, 0).z(), 0.3, 1e-12);
      EXPECT_NEAR(t.position(0, 1).z(), 0.003, 1e-12);
      EXPECT_NEAR(t.position(2, 0).x(), -0.007, 1e-12);
      EXPECT_NEAR(t.position(2, 1).y(), 0.0005, 1e-12);
      EXPECT_TRUE(t.position(1, 1).isZero(0.0));  // residual gap stored as zero
      EXPECT_EQ(t.validate(), "");
    }
}

TEST_F(C3dTest, UnitsAndUnsignedFloatResidual) {
  Synth s = threeFrameScene();
  s.float_storage = true;
  s.units = "cm";
  s.samples[1][3] = 65535.0;  // unsigned 16-bit form of -1 (Qualisys)
  const Trajectory t = readC3d(write("cm.c3d", s.build()));
  EXPECT_NEAR(t.position(0, 0).x(), 1.005, 1e-12);
  EXPECT_TRUE(t.isOccluded(0, 1));
  s.units = "m";
  const Trajectory m = readC3d(write("m.c3d", s.build()));
  EXPECT_NEAR(m.position(0, 0).y(), -200.0, 1e-9);
  s.units = "ft";
  expectInputError([&] { readC3d(write("ft.c3d", s.build())); }, {"ft.c3d", "POINT:UNITS 'ft'"});
}

// An absurd sample (1e30 m, float storage) is refused naming the file, the frame and the marker.
TEST_F(C3dTest, AbsurdSampleNamesFileFrameAndMarker) {
  Synth s = threeFrameScene();
  s.float_storage = true;
  s.units = "m";
  s.samples[3] = {{1e30, 5.0, 6.0, 1}};  // frame 1 (number 40001), marker B
  expectInputError([&] { readC3d(write("absurd.c3d", s.build())); },
                   {"absurd.c3d: frame 40001, marker 'B': a coordinate 1e+30 m from the origin"});
}

TEST_F(C3dTest, MoreThan255LabelsContinueInLabels2) {
  Synth s;
  s.frames = 2;
  for (int i = 0; i < 300; ++i) s.labels.push_back("M" + std::to_string(i));
  for (int k = 0; k < 600; ++k) s.samples.push_back({{1.0 + k, 2.0, 3.0, 0}});
  const Trajectory t = readC3d(write("many.c3d", s.build()));
  ASSERT_EQ(t.numMarkers(), 300);
  EXPECT_EQ(t.marker_names[254], "M254");
  EXPECT_EQ(t.marker_names[255], "M255");
  EXPECT_EQ(t.marker_names[299], "M299");
  // Integer 6000 x scale 0.1 stored as a float (0.1f): float precision, not 1e-12.
  EXPECT_NEAR(t.position(1, 299).x(), (1.0 + 599) * 1e-3, 1e-7);
  EXPECT_EQ(t.countOccluded(), 0u);
}

// ----------------------------------------------------------------------------- errors

TEST_F(C3dTest, TruncatedFilesThrowNamingTheFile) {
  const std::vector<uint8_t> full = readBytes(kReal + "Sample01_Eb015pi.c3d");
  // Data of 450 frames x 336 bytes from byte 5120 ends at 156320 (the file is padded to 156672).
  for (size_t length : {size_t(0), size_t(1), size_t(100), size_t(511), size_t(512), size_t(515),
                        size_t(1000), size_t(5120), size_t(100000), size_t(156319)}) {
    SCOPED_TRACE(length);
    const std::string path =
        write("cut_Sample01.c3d", std::vector<uint8_t>(full.begin(), full.begin() + length));
    expectInputError([&] { readC3d(path); }, {"cut_Sample01.c3d: "});
  }
  const std::string path =
      write("just_enough.c3d", std::vector<uint8_t>(full.begin(), full.begin() + 156320));
  EXPECT_EQ(readC3d(path).numFrames(), 450);
}

TEST_F(C3dTest, GarbageBadKeyAndUnknownProcessor) {
  std::mt19937 rng(7);
  std::vector<uint8_t> garbage(4096);
  for (uint8_t& b : garbage) b = static_cast<uint8_t>(rng());
  garbage[1] = 0x13;
  expectInputError([&] { readC3d(write("garbage.c3d", garbage)); }, {"garbage.c3d", "not a C3D"});
  expectInputError([&] { readC3d(write("text.c3d", std::vector<uint8_t>(600, 'x'))); },
                   {"text.c3d"});

  std::vector<uint8_t> bytes = readBytes(kReal + "Sample02_pc_int.c3d");
  bytes[512 + 3] = 99;
  expectInputError([&] { readC3d(write("proc.c3d", bytes)); },
                   {"proc.c3d", "unknown processor type 99"});

  Synth s = threeFrameScene();
  std::vector<uint8_t> b = s.build();
  b[0] = 200;  // parameter section far beyond the end
  expectInputError([&] { readC3d(write("pblock.c3d", b)); }, {"pblock.c3d", "truncated"});
  s.rate = 0.0;
  expectInputError([&] { readC3d(write("rate.c3d", s.build())); }, {"rate.c3d", "RATE"});
  s = threeFrameScene();
  s.labels.clear();
  s.samples.clear();
  expectInputError([&] { readC3d(write("nopoints.c3d", s.build())); }, {"nopoints.c3d", "no 3-D"});
}

TEST_F(C3dTest, DataStartBeyondEndOfFile) {
  Synth s = threeFrameScene();
  std::vector<uint8_t> b = s.build();
  // Drop the last data block: the declared frames no longer fit in the file.
  b.resize(b.size() - 512);
  expectInputError([&] { readC3d(write("short_data.c3d", b)); }, {"short_data.c3d", "truncated"});
}

TEST_F(C3dTest, MissingFileAndDispatch) {
  expectInputError([&] { readC3d(dir_ + "/missing_trial.c3d"); },
                   {"missing_trial.c3d", "cannot open"});
  const std::string upper = write("TRIAL.C3D", readBytes(kReal + "Sample02_pc_int.c3d"));
  EXPECT_EQ(readTrajectoryFile(upper).numMarkers(), 36);
  expectInputError([&] { readTrajectoryFile(dir_ + "/missing_trial.c3d"); },
                   {"missing_trial.c3d"});
}

TEST_F(C3dTest, RandomMutationsNeverCrash) {
  // A small fuzz pass: random byte changes (mostly in the header and parameter section, where
  // the structure is) must give either a valid trajectory or an InputError.
  const std::vector<uint8_t> original = readBytes(kReal + "Sample02_pc_int.c3d");
  std::mt19937 rng(12345);
  const std::string path = dir_ + "/mutant.c3d";
  int errors = 0, loaded = 0;
  for (int iteration = 0; iteration < 1500; ++iteration) {
    std::vector<uint8_t> bytes = original;
    const int changes = 1 + static_cast<int>(rng() % 8);
    for (int c = 0; c < changes; ++c) {
      const size_t region = (rng() % 4 == 0) ? bytes.size() : 12 * 512;
      bytes[rng() % region] = static_cast<uint8_t>(rng());
    }
    if (rng() % 5 == 0) bytes.resize(rng() % bytes.size());
    {
      std::ofstream out(path, std::ios::binary | std::ios::trunc);
      out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    }
    try {
      const Trajectory t = readC3d(path);
      ASSERT_EQ(t.validate(), "") << "iteration " << iteration;
      ++loaded;
    } catch (const InputError& e) {
      ASSERT_NE(std::string(e.what()).find("mutant.c3d"), std::string::npos) << e.what();
      ++errors;
    }
  }
  EXPECT_GT(loaded, 0);
  EXPECT_GT(errors, 0);
}

}  // namespace
}  // namespace mme
