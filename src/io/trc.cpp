// OpenSim TRC marker files: tab-separated text, three header lines of metadata, a marker-name
// line, a coordinate-label line and one row per frame ("frame<TAB>time<TAB>x<TAB>y<TAB>z...").
//
// Reading is lenient about the layout variations real files show (CRLF line ends, trailing
// tabs, padded or doubled tabs in the metadata values line, an optional blank line before the
// data, short rows) but strict about content: a field that is present must be a number, so a
// corrupt file is reported with its line instead of silently becoming gaps.

#include "motion_model_estimation/io/trc.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/io/model_yaml.h"  // writeFileAtomically
#include "motion_model_estimation/io/trajectory_io.h"  // kAbsurdCoordinate_m

namespace mme {
namespace {

std::string trim(const std::string& s) {
  const char* ws = " \t\r\n\f\v";
  const size_t b = s.find_first_not_of(ws);
  if (b == std::string::npos) return "";
  const size_t e = s.find_last_not_of(ws);
  return s.substr(b, e - b + 1);
}

std::vector<std::string> splitTabs(const std::string& line) {
  std::vector<std::string> fields;
  size_t start = 0;
  while (true) {
    const size_t tab = line.find('\t', start);
    fields.push_back(trim(line.substr(start, tab == std::string::npos ? std::string::npos
                                                                       : tab - start)));
    if (tab == std::string::npos) break;
    start = tab + 1;
  }
  return fields;
}

[[noreturn]] void fail(const std::string& path, int line, const std::string& reason) {
  std::ostringstream msg;
  msg << path;
  if (line > 0) msg << ':' << line;
  msg << ": " << reason;
  throw InputError(msg.str());
}

/// Parses a whole field as a double. std::from_chars is locale-independent (a ROS node or a
/// GUI may have set a locale with a decimal comma) and rejects trailing garbage.
bool parseDouble(const std::string& field, double* value) {
  if (field.empty()) return false;
  const char* begin = field.data();
  const char* end = begin + field.size();
  if (*begin == '+') ++begin;  // from_chars does not accept a leading '+'
  const auto result = std::from_chars(begin, end, *value);
  return result.ec == std::errc() && result.ptr == end;
}

/// Units per metre (0 when unknown). Kept as exact integers so that converting divides by 1000
/// instead of multiplying by the inexact 1e-3: a millimetre file round-trips more exactly.
double unitsPerMetre(const std::string& units) {
  std::string u = units;
  std::transform(u.begin(), u.end(), u.begin(), [](unsigned char c) { return std::tolower(c); });
  if (u == "mm") return 1000.0;
  if (u == "cm") return 100.0;
  if (u == "m") return 1.0;
  return 0.0;
}

/// Reads lines, dropping a trailing '\r' so CRLF files parse like LF files.
class LineReader {
 public:
  explicit LineReader(std::istream& in) : in_(in) {}
  bool next(std::string* line) {
    if (!std::getline(in_, *line)) return false;
    ++number_;
    if (!line->empty() && line->back() == '\r') line->pop_back();
    return true;
  }
  int number() const { return number_; }

 private:
  std::istream& in_;
  int number_ = 0;
};

std::string formatDouble(double v) {
  // Shortest representation that parses back to the same double: exact round trips without
  // the noise digits of %.17g.
  char buf[64];
  const auto result = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, result.ptr);
}

// ------------------------------------------------------------------------------------------
// Reading, one step per part of the file
// ------------------------------------------------------------------------------------------

/// What the metadata lines (2 and 3) say, by key, and the line of the values.
struct Metadata {
  std::map<std::string, std::string> values;
  int values_line = 0;
};

/// Line 1: "PathFileType 4 (X/Y/Z) name" (some writers use spaces instead of tabs).
void readFileTypeLine(const std::string& path, LineReader& reader) {
  std::string line;
  if (!reader.next(&line)) fail(path, 0, "empty file (expected a TRC header)");
  if (trim(line).rfind("PathFileType", 0) != 0)
    fail(path, reader.number(), "not a TRC file (expected a line starting with 'PathFileType')");
}

/// Lines 2 and 3: metadata keys and values.
Metadata readMetadata(const std::string& path, LineReader& reader) {
  std::string line;
  if (!reader.next(&line)) fail(path, reader.number(), "missing metadata keys line");
  std::vector<std::string> keys = splitTabs(line);
  keys.erase(std::remove(keys.begin(), keys.end(), std::string()), keys.end());
  if (!reader.next(&line)) fail(path, reader.number(), "missing metadata values line");
  Metadata meta;
  meta.values_line = reader.number();
  std::vector<std::string> values = splitTabs(line);
  // Some writers pad the values line with doubled tabs ("100.0\t\t100.0\t\t..."); when the
  // positional pairing cannot be right, pair keys with the non-empty values instead.
  while (!values.empty() && values.back().empty()) values.pop_back();
  if (values.size() != keys.size()) {
    values.erase(std::remove(values.begin(), values.end(), std::string()), values.end());
  }
  if (values.size() < keys.size())
    fail(path, meta.values_line,
         "metadata has " + std::to_string(keys.size()) + " keys but " +
             std::to_string(values.size()) + " values");
  for (size_t k = 0; k < keys.size(); ++k) meta.values[keys[k]] = values[k];
  return meta;
}

/// DataRate into the trajectory; returns the Units' units per metre.
double readRateAndUnits(const std::string& path, const Metadata& meta, Trajectory* trajectory) {
  auto rate_it = meta.values.find("DataRate");
  if (rate_it == meta.values.end()) fail(path, meta.values_line, "missing DataRate");
  if (!parseDouble(rate_it->second, &trajectory->frame_rate_hz) ||
      !std::isfinite(trajectory->frame_rate_hz) || trajectory->frame_rate_hz <= 0.0)
    fail(path, meta.values_line, "DataRate '" + rate_it->second + "' is not a positive number");
  // OpenSim always writes Units; a file without it follows the TRC convention of millimetres.
  const auto units_it = meta.values.find("Units");
  const std::string units = units_it != meta.values.end() ? units_it->second : std::string("mm");
  const double per_metre = unitsPerMetre(units);
  if (per_metre == 0.0)
    fail(path, meta.values_line, "unsupported Units '" + units + "' (expected mm, cm or m)");
  return per_metre;
}

/// Line 4: "Frame#<TAB>Time<TAB>name1<TAB><TAB><TAB>name2...": names are the non-empty fields
/// after Time, which also accepts writers that omit the padding tabs. Line 5: "X1 Y1 Z1 ..."
/// coordinate labels; only its presence matters.
void readMarkerNames(const std::string& path, LineReader& reader, Trajectory* trajectory) {
  std::string line;
  if (!reader.next(&line)) fail(path, reader.number(), "missing marker names line");
  const int names_line = reader.number();
  const std::vector<std::string> fields = splitTabs(line);
  for (size_t k = 2; k < fields.size(); ++k)
    if (!fields[k].empty()) trajectory->marker_names.push_back(fields[k]);
  if (trajectory->marker_names.empty()) fail(path, names_line, "no marker names");
  // A NumMarkers value that disagrees with the names is a warning (checkMarkerCounts): the names
  // line is what the data columns follow, so it takes precedence.
  if (!reader.next(&line)) fail(path, reader.number(), "missing coordinate labels line");
}

/// A data row's Frame# and Time into the trajectory. A row without a time continues the
/// sequence at the file's rate.
void readFrameAndTime(const std::string& path, int ln, const std::vector<std::string>& fields,
                      Trajectory* trajectory) {
  double frame = 0.0;
  if (!parseDouble(fields[0], &frame) || frame < 0.0 || frame != std::floor(frame) ||
      frame > std::numeric_limits<uint32_t>::max())
    fail(path, ln, "Frame# '" + fields[0] + "' is not a non-negative integer");
  double time = 0.0;
  if (fields.size() > 1 && !fields[1].empty()) {
    if (!parseDouble(fields[1], &time) || !std::isfinite(time))
      fail(path, ln, "Time '" + fields[1] + "' is not a number");
  } else {
    // No time column in this row: continue the sequence at the file's rate.
    time = trajectory->times_s.empty()
               ? 0.0
               : trajectory->times_s.back() + 1.0 / trajectory->frame_rate_hz;
    if (!std::isfinite(time))  // e.g. DataRate 1e-307: the sequence overflows
      fail(path, ln, "no Time and the time continued at DataRate is not finite");
  }
  trajectory->frame_numbers.push_back(static_cast<uint32_t>(frame));
  trajectory->times_s.push_back(time);
}

/// Marker `i`'s sample of a data row, in metres, into the trajectory: a missing, empty or NaN
/// field, or exactly 0,0,0, is a gap.
void readMarkerSample(const std::string& path, int ln, const std::vector<std::string>& fields,
                      size_t i, double per_metre, Trajectory* trajectory) {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  bool occluded = false;
  for (int c = 0; c < 3; ++c) {
    const size_t k = 2 + 3 * i + c;
    if (k >= fields.size() || fields[k].empty()) {
      occluded = true;  // missing or empty field: a gap
      continue;
    }
    double v = 0.0;
    if (!parseDouble(fields[k], &v))
      fail(path, ln,
           "marker '" + trajectory->marker_names[i] + "': '" + fields[k] + "' is not a number");
    if (std::isnan(v)) {
      occluded = true;  // OpenSim 4 writes NaN for missing markers
      continue;
    }
    if (!std::isfinite(v))
      fail(path, ln, "marker '" + trajectory->marker_names[i] + "': infinite coordinate");
    p[c] = v / per_metre;
    if (std::abs(p[c]) > kAbsurdCoordinate_m)
      fail(path, ln,
           "frame " + fields[0] + ", marker '" + trajectory->marker_names[i] + "': coordinate '" +
               fields[k] + "' is " + formatDouble(std::abs(p[c])) +
               " m from the origin, no capture's (a corrupt or hand-edited sample?)");
  }
  // Many capture systems export gaps as exactly 0,0,0.
  if (!occluded && p.isZero(0.0)) occluded = true;
  if (occluded) p.setZero();
  trajectory->positions_m.push_back(p);
  trajectory->occluded.push_back(occluded ? 1 : 0);
}

/// The data rows, to the end of the file; blank lines are skipped. Returns the most coordinate
/// fields a row held.
size_t readDataRows(const std::string& path, LineReader& reader, double per_metre,
                    Trajectory* trajectory) {
  const size_t n = trajectory->marker_names.size();
  size_t widest = 0;
  std::string line;
  while (reader.next(&line)) {
    if (trim(line).empty()) continue;  // the optional blank line, or blank lines at the end
    const int ln = reader.number();
    std::vector<std::string> fields = splitTabs(line);
    while (!fields.empty() && fields.back().empty()) fields.pop_back();  // trailing tabs
    if (fields.size() > 2 + 3 * n)
      fail(path, ln,
           "row has " + std::to_string(fields.size() - 2) + " coordinate fields but only " +
               std::to_string(n) + " markers are named");
    readFrameAndTime(path, ln, fields, trajectory);
    for (size_t i = 0; i < n; ++i) readMarkerSample(path, ln, fields, i, per_metre, trajectory);
    widest = std::max(widest, fields.size() - std::min<size_t>(fields.size(), 2));
  }
  return widest;
}

/// The header's marker counts against the data: a NumMarkers other than the names line's count,
/// and named markers no row has a column for (always hidden: the header and the data disagree,
/// e.g. a marker's columns deleted by hand), are warnings naming both figures.
void checkMarkerCounts(const std::string& path, const Metadata& meta, size_t widest_fields,
                       const Trajectory& trajectory, std::vector<std::string>* warnings) {
  if (!warnings) return;
  const size_t named = trajectory.marker_names.size();
  if (const auto it = meta.values.find("NumMarkers"); it != meta.values.end()) {
    double declared = 0.0;
    if (parseDouble(it->second, &declared) && declared != static_cast<double>(named))
      warnings->push_back(path + ": header declares " + it->second + " markers (NumMarkers), its names line names " +
                          std::to_string(named) + ": the names are used");
  }
  const size_t with_columns = (widest_fields + 2) / 3;
  if (with_columns < named)
    warnings->push_back(path + ": the names line names " + std::to_string(named) +
                        " markers but the widest data row holds " + std::to_string(widest_fields) +
                        " coordinate fields (" + std::to_string(with_columns) + " markers): '" +
                        trajectory.marker_names[with_columns] +
                        "' and after are never in the data (hidden throughout); check the header "
                        "against the columns");
}

/// The rows are the data; NumFrames only serves to notice a file that ends early (a cut-off
/// copy, an interrupted export): fewer rows than declared is a warning, the rows read are
/// returned. More rows than declared, or a NumFrames that is not a count, is left alone:
/// hand-edited files commonly keep a stale NumFrames. No rows at all is an error.
void checkFrameCount(const std::string& path, int last_line, const Metadata& meta,
                     const Trajectory& trajectory, std::vector<std::string>* warnings) {
  long declared_frames = -1;
  if (const auto it = meta.values.find("NumFrames"); it != meta.values.end()) {
    double value = 0.0;
    if (parseDouble(it->second, &value) && value >= 0.0 && value == std::floor(value) &&
        value <= std::numeric_limits<int>::max())
      declared_frames = static_cast<long>(value);
  }
  const long found_frames = static_cast<long>(trajectory.times_s.size());
  if (found_frames == 0)
    fail(path, last_line,
         declared_frames > 0
             ? "no data rows (header declares " + std::to_string(declared_frames) + " frames)"
             : std::string("no data rows"));
  if (found_frames < declared_frames && warnings)
    warnings->push_back(path + ": header declares " + std::to_string(declared_frames) +
                        " frames, found " + std::to_string(found_frames) + " (file cut short?)");
}

}  // namespace

Trajectory readTrc(const std::string& path, std::vector<std::string>* warnings) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, 0, std::string("cannot open: ") + std::strerror(errno));
  LineReader reader(in);
  readFileTypeLine(path, reader);
  const Metadata meta = readMetadata(path, reader);
  Trajectory trajectory;
  const double per_metre = readRateAndUnits(path, meta, &trajectory);
  readMarkerNames(path, reader, &trajectory);
  const size_t widest_fields = readDataRows(path, reader, per_metre, &trajectory);
  if (in.bad()) fail(path, reader.number(), "read error");
  checkFrameCount(path, reader.number(), meta, trajectory, warnings);
  checkMarkerCounts(path, meta, widest_fields, trajectory, warnings);
  return trajectory;
}

void writeTrc(const std::string& path, const Trajectory& trajectory, const std::string& units) {
  const double per_metre = unitsPerMetre(units);
  if (per_metre == 0.0)
    throw InputError(path + ": unsupported TRC units '" + units + "' (expected mm, cm or m)");
  const std::string problem = trajectory.validate();
  if (!problem.empty()) throw InputError(path + ": cannot write trajectory: " + problem);
  if (trajectory.marker_names.empty()) throw InputError(path + ": cannot write TRC: no markers");
  for (const std::string& name : trajectory.marker_names)
    if (name.empty() || name != trim(name) || name.find_first_of("\t\r\n") != std::string::npos)
      throw InputError(path + ": marker name '" + name +
                       "' cannot be written to TRC (empty, or contains tabs, line breaks or "
                       "surrounding spaces)");

  const int frames = trajectory.numFrames();
  const int n = trajectory.numMarkers();
  const std::string rate = formatDouble(trajectory.frame_rate_hz);
  const std::string first_frame =
      frames > 0 ? std::to_string(trajectory.frame_numbers[0]) : std::string("1");
  std::string base = path;
  const size_t slash = base.find_last_of('/');
  if (slash != std::string::npos) base = base.substr(slash + 1);

  std::string out;
  out.reserve(static_cast<size_t>(frames) * (32 + n * 48) + 512);
  out += "PathFileType\t4\t(X/Y/Z)\t" + base + "\n";
  out += "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame"
         "\tOrigNumFrames\n";
  out += rate + "\t" + rate + "\t" + std::to_string(frames) + "\t" + std::to_string(n) + "\t" +
         units + "\t" + rate + "\t" + first_frame + "\t" + std::to_string(frames) + "\n";
  out += "Frame#\tTime";
  for (const std::string& name : trajectory.marker_names) out += "\t" + name + "\t\t";
  out += "\n\t";
  for (int i = 1; i <= n; ++i) {
    const std::string k = std::to_string(i);
    out += "\tX" + k + "\tY" + k + "\tZ" + k;
  }
  out += "\n\n";
  for (int t = 0; t < frames; ++t) {
    out += std::to_string(trajectory.frame_numbers[t]);
    out += '\t';
    out += formatDouble(trajectory.times_s[t]);
    for (int i = 0; i < n; ++i) {
      if (trajectory.isOccluded(t, i)) {
        out += "\t\t\t";
        continue;
      }
      // A visible sample at exactly (0,0,0) reads back as a gap: that is the TRC convention.
      const Eigen::Vector3d& p = trajectory.position(t, i);
      for (int c = 0; c < 3; ++c) {
        out += '\t';
        out += formatDouble(p[c] * per_metre);
      }
    }
    out += '\n';
  }
  writeFileAtomically(path, out);
}

}  // namespace mme
