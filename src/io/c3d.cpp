// C3D reader (https://www.c3d.org/): 3-D point data only, analog samples are skipped.
//
// File layout: 512-byte blocks; block 1 is the header, the parameter section starts at the
// block named in header byte 0 and the point/analog data at POINT:DATA_START. Numbers follow
// the processor type stored in the parameter section: Intel (little-endian IEEE), DEC
// (little-endian integers, VAX F-floats) or MIPS (big-endian IEEE).
//
// The whole file is read into memory and every access goes through bounds-checked helpers, so
// a truncated or corrupt file gives an InputError and never an out-of-range read: this reader
// is fed files from outside the project (and is fuzzed).

#include "motion_model_estimation/io/c3d.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <sstream>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/io/trajectory_io.h"  // kAbsurdCoordinate_m

namespace mme {
namespace {

constexpr size_t kBlock = 512;
constexpr uint8_t kKey = 0x50;

enum class Processor { kIntel, kDec, kMips };

std::string upper(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  return s;
}

/// Strips the blanks and NULs C3D pads fixed-width character arrays with.
std::string trimPadding(const std::string& s) {
  size_t b = 0, e = s.size();
  auto blank = [](char c) { return c == ' ' || c == '\0' || c == '\t' || c == '\r' || c == '\n'; };
  while (b < e && blank(s[b])) ++b;
  while (e > b && blank(s[e - 1])) --e;
  return s.substr(b, e - b);
}

/// One parameter as found in the file; its data stays in the file buffer (already checked to
/// lie within the parameter section).
struct Parameter {
  int type = 0;                ///< -1 char, 1 byte, 2 int16, 4 float
  std::vector<int> dims;       ///< empty = scalar
  size_t data_offset = 0;
  size_t count = 0;            ///< number of elements (product of dims, 1 for a scalar)
};

class C3dFile {
 public:
  C3dFile(std::string path, std::vector<uint8_t> bytes)
      : path_(std::move(path)), bytes_(std::move(bytes)) {}

  [[noreturn]] void fail(const std::string& reason) const {
    throw InputError(path_ + ": " + reason);
  }

  size_t size() const { return bytes_.size(); }
  /// True when [offset, offset + length) lies inside the file (overflow-safe).
  bool has(uint64_t offset, uint64_t length) const {
    return offset <= bytes_.size() && length <= bytes_.size() - offset;
  }
  void require(uint64_t offset, uint64_t length, const char* what) const {
    if (!has(offset, length)) fail(std::string("truncated file (") + what + " beyond end of file)");
  }

  uint8_t u8(size_t offset) const {
    require(offset, 1, "byte");
    return bytes_[offset];
  }
  uint16_t u16(size_t offset) const {
    require(offset, 2, "integer");
    const uint8_t a = bytes_[offset], b = bytes_[offset + 1];
    return processor_ == Processor::kMips ? static_cast<uint16_t>(a << 8 | b)
                                          : static_cast<uint16_t>(b << 8 | a);
  }
  int16_t i16(size_t offset) const { return static_cast<int16_t>(u16(offset)); }
  float f32(size_t offset) const {
    require(offset, 4, "float");
    const uint8_t* b = &bytes_[offset];
    uint32_t bits = 0;
    switch (processor_) {
      case Processor::kIntel:
        bits = uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24;
        return bitsToFloat(bits);
      case Processor::kMips:
        bits = uint32_t(b[3]) | uint32_t(b[2]) << 8 | uint32_t(b[1]) << 16 | uint32_t(b[0]) << 24;
        return bitsToFloat(bits);
      case Processor::kDec:
        // VAX F-float: two little-endian 16-bit words, the first holding sign, exponent and the
        // high mantissa bits; so the IEEE little-endian byte order is (b2, b3, b0, b1).
        bits = uint32_t(b[2]) | uint32_t(b[3]) << 8 | uint32_t(b[0]) << 16 | uint32_t(b[1]) << 24;
        return decToFloat(bits);
    }
    return 0.0f;
  }

  void setProcessor(Processor p) { processor_ = p; }
  Processor processor() const { return processor_; }
  const std::string& path() const { return path_; }

 private:
  static float bitsToFloat(uint32_t bits) {
    float f;
    std::memcpy(&f, &bits, sizeof f);
    return f;
  }
  /// VAX F-float bits (already word-swapped) -> IEEE single. Same layout as IEEE but with
  /// exponent bias 129 instead of 127 (mantissa 0.1f instead of 1.f), i.e. 4 times smaller.
  static float decToFloat(uint32_t bits) {
    const uint32_t exponent = (bits >> 23) & 0xff;
    if (exponent == 0) {
      // Exponent 0: zero, or with the sign bit set the VAX "reserved operand" (a NaN).
      return (bits & 0x80000000u) ? std::numeric_limits<float>::quiet_NaN() : 0.0f;
    }
    if (exponent > 2) return bitsToFloat(bits - (2u << 23));  // exact division by 4
    return bitsToFloat(bits) / 4.0f;  // result is subnormal in IEEE; rounding is acceptable
  }

  std::string path_;
  std::vector<uint8_t> bytes_;
  Processor processor_ = Processor::kIntel;
};

/// Parameter section: groups by id, parameters by (group name, parameter name), upper case.
class Parameters {
 public:
  Parameters(const C3dFile& file, size_t begin, size_t end) : file_(file) { parse(begin, end); }

  const Parameter* find(const std::string& group, const std::string& name) const {
    auto it = params_.find(upper(group) + ":" + upper(name));
    return it == params_.end() ? nullptr : &it->second;
  }

  /// Element `index` of a numeric parameter as a double; int16 parameters are read unsigned
  /// when `unsigned16` (counts such as POINT:FRAMES exceed 32767 in long trials).
  bool number(const Parameter* p, size_t index, bool unsigned16, double* value) const {
    if (!p || index >= p->count) return false;
    switch (p->type) {
      case 1: *value = file_.u8(p->data_offset + index); return true;
      case 2:
        *value = unsigned16 ? double(file_.u16(p->data_offset + 2 * index))
                            : double(file_.i16(p->data_offset + 2 * index));
        return true;
      case 4: *value = file_.f32(p->data_offset + 4 * index); return true;
      default: return false;
    }
  }
  bool number(const std::string& group, const std::string& name, bool unsigned16,
              double* value) const {
    return number(find(group, name), 0, unsigned16, value);
  }

  /// Strings of a character parameter: dims[0] is the string length, the other dimensions
  /// count the strings.
  std::vector<std::string> strings(const std::string& group, const std::string& name) const {
    std::vector<std::string> out;
    const Parameter* p = find(group, name);
    if (!p || p->type != -1) return out;
    const size_t length = p->dims.empty() ? 1 : static_cast<size_t>(p->dims[0]);
    if (length == 0) return out;
    const size_t n = p->count / length;
    for (size_t k = 0; k < n; ++k) {
      std::string s;
      for (size_t c = 0; c < length; ++c)
        s.push_back(static_cast<char>(file_.u8(p->data_offset + k * length + c)));
      out.push_back(trimPadding(s));
    }
    return out;
  }

 private:
  void parse(size_t begin, size_t end) {
    // Entries: name length (int8, negative = locked), group id (int8, negative = group),
    // name, int16 offset to the next entry counted from the offset field itself (0 = last),
    // then for a parameter: type, dimension count, dimensions, data, description.
    std::map<int, std::string> group_names;
    struct Raw {
      int group;
      std::string name;
      Parameter parameter;
    };
    std::vector<Raw> raw;
    size_t pos = begin;
    while (pos + 2 <= end) {
      const int name_length = std::abs(static_cast<int8_t>(file_.u8(pos)));
      const int id = static_cast<int8_t>(file_.u8(pos + 1));
      if (name_length == 0 || id == 0) break;  // terminator (or padding after the last entry)
      const size_t offset_field = pos + 2 + name_length;
      if (offset_field + 2 > end) break;
      std::string name;
      for (int c = 0; c < name_length; ++c) name.push_back(static_cast<char>(file_.u8(pos + 2 + c)));
      name = upper(trimPadding(name));
      const int next_offset = file_.i16(offset_field);
      const size_t entry_end =
          next_offset > 0 ? std::min(end, offset_field + static_cast<size_t>(next_offset)) : end;
      if (id < 0) {
        group_names.emplace(-id, name);
      } else {
        Parameter p;
        bool ok = offset_field + 4 <= entry_end;
        if (ok) {
          p.type = static_cast<int8_t>(file_.u8(offset_field + 2));
          const int num_dims = file_.u8(offset_field + 3);
          ok = (p.type == -1 || p.type == 1 || p.type == 2 || p.type == 4) &&
               offset_field + 4 + num_dims <= entry_end;
          uint64_t count = 1;
          for (int d = 0; ok && d < num_dims; ++d) {
            const int dim = file_.u8(offset_field + 4 + d);
            p.dims.push_back(dim);
            count *= static_cast<uint64_t>(dim);
            if (count > end) ok = false;  // cannot fit: also keeps the product from overflowing
          }
          if (ok) {
            p.count = static_cast<size_t>(count);
            p.data_offset = offset_field + 4 + num_dims;
            ok = p.data_offset + p.count * std::abs(p.type) <= entry_end;
          }
        }
        // A malformed parameter is skipped rather than fatal: files often carry vendor
        // parameters this reader never needs; the ones it needs are checked where used.
        if (ok) raw.push_back({id, name, p});
      }
      if (next_offset <= 0) break;  // last entry (a negative offset cannot be followed safely)
      pos = offset_field + static_cast<size_t>(next_offset);
    }
    for (const Raw& r : raw) {
      auto g = group_names.find(r.group);
      if (g == group_names.end()) continue;  // parameter of an undeclared group: unreachable
      params_.emplace(g->second + ":" + r.name, r.parameter);  // first definition wins
    }
  }

  const C3dFile& file_;
  std::map<std::string, Parameter> params_;
};

std::vector<uint8_t> readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open: " + std::strerror(errno));
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw InputError(path + ": read error");
  return bytes;
}

/// Units per metre for POINT:UNITS (0 when unknown).
double unitsPerMetre(const std::string& units) {
  const std::string u = upper(units);
  if (u.empty() || u == "MM") return 1000.0;  // the C3D default is millimetres
  if (u == "CM") return 100.0;
  if (u == "M") return 1.0;
  return 0.0;
}

/// Float storage keeps the integer residual word (camera mask << 8 | residual) as a float.
/// Writers disagree on its sign: most store the signed word (-1 = invalid), some (e.g.
/// Qualisys, Sample26) the same 16 bits unsigned (65535). Both mean "sign bit set = invalid",
/// as in integer storage. NaN is invalid too.
bool floatResidualInvalid(float residual) {
  if (std::isnan(residual)) return true;
  const double word = std::trunc(static_cast<double>(residual));
  if (word < 0.0) return true;
  if (word > 65535.0) return false;  // not a 16-bit word: an actual (positive) residual
  return static_cast<int16_t>(static_cast<uint16_t>(word)) < 0;
}

// ------------------------------------------------------------------------------------------
// Reading, one step per part of the file
// ------------------------------------------------------------------------------------------

/// Header words (1-based as in the specification).
struct Header {
  int points = 0;              ///< word 2
  int analog_per_frame = 0;    ///< word 3: all analog channels x samples
  uint32_t first_frame = 0;    ///< word 4
  uint32_t last_frame = 0;     ///< word 5
  float scale = 0.0f;          ///< words 7-8
  int data_start_block = 0;    ///< word 9
  float rate_hz = 0.0f;        ///< words 11-12
};

/// The 3-D point layout the reader follows: parameters where present, else the header.
struct PointLayout {
  int points = 0;
  bool float_storage = false;
  double scale = 0.0;          ///< of integer storage (|POINT:SCALE|)
  double rate_hz = 0.0;
  size_t data_start = 0;       ///< byte offset of the first frame
  uint32_t first_frame = 0;
  int64_t frames = 0;
  size_t value_size = 0;       ///< bytes per stored value
  uint64_t frame_bytes = 0;    ///< bytes per frame, points and analog samples
};

/// Checks the header key and finds the parameter section; sets the processor type, which
/// every later number depends on. Returns the section's first byte.
size_t findParameterSection(C3dFile& file) {
  if (file.size() < kBlock) file.fail("truncated file (shorter than the 512-byte header)");
  if (file.u8(1) != kKey) file.fail("not a C3D file (header key is not 0x50)");
  const size_t parameter_block = file.u8(0);
  if (parameter_block < 2) file.fail("invalid parameter section block number");
  const size_t param_start = (parameter_block - 1) * kBlock;
  if (!file.has(param_start, 4)) file.fail("truncated file (parameter section beyond end of file)");

  switch (file.u8(param_start + 3)) {
    case 84: file.setProcessor(Processor::kIntel); break;
    case 85: file.setProcessor(Processor::kDec); break;
    case 86: file.setProcessor(Processor::kMips); break;
    default:
      file.fail("unknown processor type " + std::to_string(file.u8(param_start + 3)) +
                " (expected 84 Intel, 85 DEC or 86 MIPS)");
  }
  return param_start;
}

Header readHeader(const C3dFile& file) {
  Header h;
  h.points = file.u16(2);
  h.analog_per_frame = file.u16(4);
  h.first_frame = file.u16(6);
  h.last_frame = file.u16(8);
  h.scale = file.f32(12);
  h.data_start_block = file.u16(16);
  h.rate_hz = file.f32(20);
  return h;
}

/// Byte after the parameter section: where its block count says; it cannot extend into the
/// data.
size_t parameterSectionEnd(const C3dFile& file, size_t param_start, const Header& header) {
  const size_t declared_blocks = file.u8(param_start + 2);
  size_t param_end = param_start + std::max<size_t>(declared_blocks, 1) * kBlock;
  if (header.data_start_block > 0 && (header.data_start_block - 1) * kBlock > param_end)
    param_end = (header.data_start_block - 1) * kBlock;  // a stale block count must not hide params
  return std::min(param_end, file.size());
}

/// Element `index` of a count parameter into `out`; false when the parameter is absent.
/// Counts may come from float parameters in a corrupt file: converting a NaN or huge float to
/// an integer is undefined behaviour, so every count goes through this range check.
bool readCount(const C3dFile& file, const Parameters& params, const Parameter* p, size_t index,
               int64_t* out) {
  double v = 0.0;
  if (!params.number(p, index, true, &v)) return false;
  if (!(v >= 0.0 && v <= 2147483647.0)) file.fail("invalid count in a parameter");
  *out = static_cast<int64_t>(v);
  return true;
}

/// Points, storage, scale, rate and data start. Parameters supersede the header where both
/// exist (as the specification says); this also sizes the data, since writers that disagree
/// update POINT:USED, not the header.
void readPointParameters(const C3dFile& file, const Parameters& params, const Header& header,
                         PointLayout* layout) {
  int64_t n = 0;
  layout->points = readCount(file, params, params.find("POINT", "USED"), 0, &n)
                       ? static_cast<int>(n)
                       : header.points;
  if (layout->points <= 0) file.fail("no 3-D points (POINT:USED is 0)");

  double value = 0.0;
  double scale = header.scale;
  if (params.number("POINT", "SCALE", false, &value)) scale = value;
  if (!std::isfinite(scale) || scale == 0.0) file.fail("invalid POINT:SCALE");
  layout->float_storage = scale < 0.0;
  layout->scale = std::fabs(scale);

  double rate = header.rate_hz;
  if (params.number("POINT", "RATE", false, &value)) rate = value;
  if (!std::isfinite(rate) || rate <= 0.0) file.fail("invalid POINT:RATE (frame rate must be > 0)");
  layout->rate_hz = rate;

  size_t data_start_block = static_cast<size_t>(header.data_start_block);
  if (readCount(file, params, params.find("POINT", "DATA_START"), 0, &n) && n > 0)
    data_start_block = static_cast<size_t>(n);
  if (data_start_block < 2) file.fail("invalid POINT:DATA_START");
  layout->data_start = (data_start_block - 1) * kBlock;
}

/// Frame count: the header's first/last frame, cross-checked with POINT:FRAMES (unsigned, so
/// up to 65535). Long trials cap the 16-bit header at 65535 and store the true 32-bit range in
/// TRIAL:ACTUAL_START_FIELD / ACTUAL_END_FIELD (low word, high word).
void readFrameRange(const C3dFile& file, const Parameters& params, const Header& header,
                    PointLayout* layout) {
  uint32_t first_frame = header.first_frame;
  int64_t frames = header.last_frame >= header.first_frame
                       ? int64_t(header.last_frame) - header.first_frame + 1
                       : 0;
  int64_t n = 0;
  int64_t start_lo, start_hi, end_lo, end_hi;
  const Parameter* trial_start = params.find("TRIAL", "ACTUAL_START_FIELD");
  const Parameter* trial_end = params.find("TRIAL", "ACTUAL_END_FIELD");
  if (header.last_frame == 65535 && readCount(file, params, trial_start, 0, &start_lo) &&
      readCount(file, params, trial_start, 1, &start_hi) &&
      readCount(file, params, trial_end, 0, &end_lo) &&
      readCount(file, params, trial_end, 1, &end_hi)) {
    const int64_t s = start_lo + start_hi * 65536;
    const int64_t e = end_lo + end_hi * 65536;
    if (e >= s && s <= std::numeric_limits<uint32_t>::max()) {
      first_frame = static_cast<uint32_t>(s);
      frames = e - s + 1;
    }
  } else if (frames == 0 && readCount(file, params, params.find("POINT", "FRAMES"), 0, &n)) {
    frames = n;  // header range unusable: trust the parameter
  }
  // When POINT:FRAMES disagrees with a usable header range, the header wins: it is what the
  // writers that get POINT:FRAMES wrong (signed overflow) still fill in correctly.
  layout->first_frame = first_frame;
  layout->frames = frames;
}

/// Frame size, and that every frame lies inside the file.
void checkDataSize(const C3dFile& file, const Header& header, PointLayout* layout) {
  const int64_t frames = layout->frames;
  if (frames <= 0) file.fail("no frames (header first/last frame and POINT:FRAMES give none)");
  if (frames > std::numeric_limits<int>::max()) file.fail("too many frames");
  layout->value_size = layout->float_storage ? 4 : 2;
  const uint64_t values_per_frame =
      4ull * layout->points + static_cast<uint64_t>(header.analog_per_frame);
  const uint64_t frame_bytes = values_per_frame * layout->value_size;
  layout->frame_bytes = frame_bytes;
  const size_t data_start = layout->data_start;
  // frame_bytes <= file size first: frames * frame_bytes could otherwise wrap around 2^64
  // (points from a float POINT:USED, frames from TRIAL) and pass the size check.
  if (frame_bytes > file.size() ||
      !file.has(data_start, static_cast<uint64_t>(frames) * frame_bytes)) {
    std::ostringstream msg;
    msg << "truncated file (" << frames << " frames of " << frame_bytes << " bytes from byte "
        << data_start << " need " << data_start + frames * frame_bytes << " bytes, file has "
        << file.size() << ")";
    file.fail(msg.str());
  }
}

/// Units per metre of POINT:UNITS.
double readUnits(const C3dFile& file, const Parameters& params) {
  const std::vector<std::string> u = params.strings("POINT", "UNITS");
  const std::string units_text = u.empty() ? std::string() : u[0];
  const double per_metre = unitsPerMetre(units_text);
  if (per_metre == 0.0)
    file.fail("unsupported POINT:UNITS '" + units_text + "' (expected mm, cm or m)");
  return per_metre;
}

/// POINT:LABELS, continued in LABELS2, LABELS3, ... (a parameter holds at most 255); points
/// without a label are named POINT1, POINT2, ...
std::vector<std::string> readMarkerNames(const Parameters& params, int points) {
  std::vector<std::string> labels = params.strings("POINT", "LABELS");
  for (int k = 2; static_cast<int>(labels.size()) < points; ++k) {
    const std::vector<std::string> more = params.strings("POINT", "LABELS" + std::to_string(k));
    if (more.empty()) break;
    labels.insert(labels.end(), more.begin(), more.end());
  }
  std::vector<std::string> names;
  for (int i = 0; i < points; ++i) {
    const bool named = i < static_cast<int>(labels.size()) && !labels[i].empty();
    names.push_back(named ? labels[i] : "POINT" + std::to_string(i + 1));
  }
  return names;
}

/// One stored point at byte `at`, in file units, and whether it is occluded.
bool readPoint(const C3dFile& file, const PointLayout& layout, size_t at, Eigen::Vector3d* p) {
  bool occluded;
  if (layout.float_storage) {
    for (int c = 0; c < 3; ++c) (*p)[c] = file.f32(at + 4 * c);
    occluded = floatResidualInvalid(file.f32(at + 12)) || !p->allFinite();
  } else {
    for (int c = 0; c < 3; ++c) (*p)[c] = file.i16(at + 2 * c) * layout.scale;
    occluded = file.i16(at + 6) < 0;
  }
  // Several systems (e.g. Qualisys) write gaps as 0,0,0 with a valid residual.
  if (p->isZero(0.0)) occluded = true;
  return occluded;
}

/// Every frame's times, frame numbers and points (metres) into the trajectory.
void readFrames(const C3dFile& file, const PointLayout& layout, double per_metre,
                Trajectory* trajectory) {
  const int points = layout.points;
  const int num_frames = static_cast<int>(layout.frames);
  trajectory->times_s.resize(num_frames);
  trajectory->frame_numbers.resize(num_frames);
  trajectory->positions_m.assign(static_cast<size_t>(num_frames) * points, Eigen::Vector3d::Zero());
  trajectory->occluded.assign(static_cast<size_t>(num_frames) * points, 1);
  for (int t = 0; t < num_frames; ++t) {
    trajectory->times_s[t] = t / layout.rate_hz;  // times from the first recorded frame
    trajectory->frame_numbers[t] = layout.first_frame + static_cast<uint32_t>(t);
    const size_t frame_offset = layout.data_start + static_cast<size_t>(t) * layout.frame_bytes;
    for (int i = 0; i < points; ++i) {
      const size_t at = frame_offset + static_cast<size_t>(i) * 4 * layout.value_size;
      Eigen::Vector3d p;
      const bool occluded = readPoint(file, layout, at, &p);
      const size_t k = static_cast<size_t>(t) * points + i;
      trajectory->occluded[k] = occluded ? 1 : 0;
      trajectory->positions_m[k] =
          occluded ? Eigen::Vector3d::Zero() : Eigen::Vector3d(p / per_metre);
      if (trajectory->positions_m[k].cwiseAbs().maxCoeff() > kAbsurdCoordinate_m) {
        char far[32];
        std::snprintf(far, sizeof(far), "%g", trajectory->positions_m[k].cwiseAbs().maxCoeff());
        file.fail("frame " + std::to_string(trajectory->frame_numbers[t]) + ", marker '" +
                  trajectory->marker_names[static_cast<size_t>(i)] + "': a coordinate " + far +
                  " m from the origin, no capture's (a corrupt sample?)");
      }
    }
  }
}

}  // namespace

Trajectory readC3d(const std::string& path) {
  C3dFile file(path, readAll(path));
  const size_t param_start = findParameterSection(file);
  const Header header = readHeader(file);
  const Parameters params(file, param_start + 4, parameterSectionEnd(file, param_start, header));
  PointLayout layout;
  readPointParameters(file, params, header, &layout);
  readFrameRange(file, params, header, &layout);
  checkDataSize(file, header, &layout);
  const double per_metre = readUnits(file, params);

  Trajectory trajectory;
  trajectory.frame_rate_hz = layout.rate_hz;
  trajectory.marker_names = readMarkerNames(params, layout.points);
  readFrames(file, layout, per_metre, &trajectory);
  return trajectory;
}

}  // namespace mme
