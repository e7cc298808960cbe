#include "motion_model_estimation/ros/vicon_markers.h"

#include <cmath>
#include <cstring>

namespace mme {

namespace {

/// Bounds-checked little-endian reader over ROS serialization.
class Reader {
 public:
  Reader(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  bool u32(uint32_t* v) { return raw(v, 4); }
  bool f64(double* v) { return raw(v, 8); }
  bool u8(uint8_t* v) { return raw(v, 1); }
  bool str(std::string* s) {
    uint32_t n = 0;
    if (!u32(&n) || n > size_ - pos_) return false;
    s->assign(reinterpret_cast<const char*>(data_ + pos_), n);
    pos_ += n;
    return true;
  }
  size_t remaining() const { return size_ - pos_; }

 private:
  bool raw(void* v, size_t n) {
    if (n > size_ - pos_) return false;
    std::memcpy(v, data_ + pos_, n);  // x86/ARM little-endian hosts, as ROS 1 assumes
    pos_ += n;
    return true;
  }
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
};

void putU32(std::vector<uint8_t>* out, uint32_t v) {
  const uint8_t* p = reinterpret_cast<const uint8_t*>(&v);
  out->insert(out->end(), p, p + 4);
}
void putF64(std::vector<uint8_t>* out, double v) {
  const uint8_t* p = reinterpret_cast<const uint8_t*>(&v);
  out->insert(out->end(), p, p + 8);
}
void putStr(std::vector<uint8_t>* out, const std::string& s) {
  putU32(out, static_cast<uint32_t>(s.size()));
  out->insert(out->end(), s.begin(), s.end());
}

}  // namespace

bool decodeViconMarkers(const uint8_t* data, size_t size, bool qualify_with_subject,
                        ViconMarkers* out, std::string* error) {
  Reader r(data, size);
  uint32_t seq, sec, nsec, count;
  ViconMarkers m;
  if (!r.u32(&seq) || !r.u32(&sec) || !r.u32(&nsec) || !r.str(&m.frame_id) ||
      !r.u32(&m.frame_number) || !r.u32(&count)) {
    *error = "truncated vicon_bridge/Markers header";
    return false;
  }
  m.stamp_s = sec + 1e-9 * nsec;
  // Each marker needs at least 3 empty strings (12 bytes) + 24 + 1 bytes: reject absurd counts
  // before reserving memory.
  if (count > r.remaining() / 37) {
    *error = "vicon_bridge/Markers: marker count exceeds the message size";
    return false;
  }
  for (uint32_t k = 0; k < count; ++k) {
    std::string marker, subject, segment;
    double x, y, z;
    uint8_t occluded;
    if (!r.str(&marker) || !r.str(&subject) || !r.str(&segment) || !r.f64(&x) || !r.f64(&y) ||
        !r.f64(&z) || !r.u8(&occluded)) {
      *error = "truncated vicon_bridge/Marker " + std::to_string(k);
      return false;
    }
    m.names.push_back(qualify_with_subject && !subject.empty() ? subject + "/" + marker : marker);
    m.positions_m.emplace_back(1e-3 * x, 1e-3 * y, 1e-3 * z);  // driver publishes millimetres
    m.occluded.push_back(occluded != 0 || !std::isfinite(x) || !std::isfinite(y) ||
                         !std::isfinite(z));
  }
  *out = std::move(m);
  return true;
}

std::vector<uint8_t> encodeViconMarkers(const ViconMarkers& m, uint32_t seq) {
  std::vector<uint8_t> out;
  putU32(&out, seq);
  // Whole nanoseconds first: rounding the fraction alone could give 1e9 ns (a stamp 1 s early).
  const long long ns = std::llround(m.stamp_s * 1e9);
  putU32(&out, static_cast<uint32_t>(ns / 1000000000LL));
  putU32(&out, static_cast<uint32_t>(ns % 1000000000LL));
  putStr(&out, m.frame_id);
  putU32(&out, m.frame_number);
  putU32(&out, static_cast<uint32_t>(m.names.size()));
  for (size_t k = 0; k < m.names.size(); ++k) {
    putStr(&out, m.names[k]);
    putStr(&out, "");
    putStr(&out, "");
    for (int c = 0; c < 3; ++c) putF64(&out, 1e3 * m.positions_m[k][c]);
    out.push_back(k < m.occluded.size() && m.occluded[k] ? 1 : 0);
  }
  return out;
}

const char* viconMarkersMd5() { return "579f0637989aa8139ce6bf98cf7aabda"; }

const char* viconMarkersDefinition() {
  return "Header header\nuint32 frame_number\nvicon_bridge/Marker[] markers\n\n"
         "================================================================================\n"
         "MSG: std_msgs/Header\nuint32 seq\ntime stamp\nstring frame_id\n\n"
         "================================================================================\n"
         "MSG: vicon_bridge/Marker\nstring marker_name\nstring subject_name\n"
         "string segment_name\ngeometry_msgs/Point translation\nbool occluded\n\n"
         "================================================================================\n"
         "MSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z\n";
}

}  // namespace mme
