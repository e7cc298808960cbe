// Maps a frame's markers, named in the input's order, onto the model's particles (the online
// node's input path). The name -> particle index is rebuilt only when the input's name list
// changes, so a steady stream costs one comparison of the name lists per frame. No ROS here.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace mme {

/// One frame in the model's particle order, and what the mapping found on the way.
struct MappedFrame {
  std::vector<Eigen::Vector3d> positions_m;  ///< [m] particle order (empty names: input order)
  /// 0 = seen, 1 = occluded, OnlineEstimator::kNoMarker = absent from the frame
  std::vector<uint8_t> occluded;
  bool names_changed = false;   ///< the name list differs from the previous frame's (index rebuilt)
  size_t unknown = 0;           ///< input names that are no model particle (ignored)
  std::string example_unknown;  ///< the first of them ("" when none)
  size_t matched = 0;           ///< input markers placed on a particle
  /// Log once: set only when the name list changed and holds unknown names, e.g.
  /// "2 marker names in the input are not model particles (ignored), e.g. 'stray'".
  std::string warning;
  /// Why the frame must be skipped ("" when it is usable): no known name, or unequal lengths.
  std::string rejection;
};

/// The input -> particle mapping with its cache. Not thread-safe: the caller serialises map()
/// and setParticles().
class MarkerNameMap {
 public:
  static constexpr const char* kNoNameMatches = "no marker name matches a model particle";
  static constexpr const char* kLengthsDiffer = "names, positions and occluded differ in length";

  explicit MarkerNameMap(std::vector<std::string> particle_names = {});

  /// Other particles (a model was loaded): the next frame rebuilds the index, and its unknown
  /// names are reported again even when the input's name list is the same.
  void setParticles(std::vector<std::string> particle_names);
  const std::vector<std::string>& particles() const { return particles_; }

  /// Places marker `names[k]` (position `positions_m[k]`, flag `occluded[k]`) at its particle's
  /// index; particles absent from the frame are at (0,0,0), flagged kNoMarker. Unknown names are ignored;
  /// when two markers share a name the later one wins. Empty `names`: the input is already in
  /// particle order and passes through unchanged (the estimator checks its size). `occluded`
  /// may be empty (nothing occluded); otherwise all three have the same length.
  MappedFrame map(const std::vector<std::string>& names, std::vector<Eigen::Vector3d> positions_m,
                  std::vector<uint8_t> occluded);

 private:
  std::vector<std::string> particles_;
  bool have_index_ = false;
  std::vector<std::string> cached_names_;
  std::vector<int> cached_index_;  // input position -> particle index (-1 = unknown marker)
  size_t cached_unknown_ = 0;
  std::string cached_example_unknown_;
};

}  // namespace mme
