// Decoding of vicon_bridge/Markers messages received as raw bytes (topic_tools::ShapeShifter),
// so labs can feed their existing Vicon driver without this package depending on it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace mme {

/// vicon_bridge/Markers: Header header, uint32 frame_number, Marker[] markers with
/// Marker: string marker_name, string subject_name, string segment_name,
/// geometry_msgs/Point translation (millimetres), bool occluded.
struct ViconMarkers {
  double stamp_s = 0.0;
  std::string frame_id;
  uint32_t frame_number = 0;
  std::vector<std::string> names;          ///< marker_name (subject_name/marker_name when
                                           ///< `qualify_with_subject`)
  std::vector<Eigen::Vector3d> positions_m;  ///< converted from millimetres
  std::vector<uint8_t> occluded;
};

/// Decodes the serialized message. Returns false (and sets *error) on truncated or malformed
/// bytes; never reads out of bounds.
bool decodeViconMarkers(const uint8_t* data, size_t size, bool qualify_with_subject,
                        ViconMarkers* out, std::string* error);

/// Serializes (for tests and the vicon-shaped test publisher).
std::vector<uint8_t> encodeViconMarkers(const ViconMarkers& markers, uint32_t seq);

/// The md5sum and definition of vicon_bridge/Markers, to advertise a compatible topic.
const char* viconMarkersMd5();
const char* viconMarkersDefinition();

}  // namespace mme
