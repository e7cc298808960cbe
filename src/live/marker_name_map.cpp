#include "motion_model_estimation/live/marker_name_map.h"

#include "motion_model_estimation/identification/online/online_estimator.h"

#include <unordered_map>
#include <utility>

namespace mme {

MarkerNameMap::MarkerNameMap(std::vector<std::string> particle_names)
    : particles_(std::move(particle_names)) {}

void MarkerNameMap::setParticles(std::vector<std::string> particle_names) {
  particles_ = std::move(particle_names);
  have_index_ = false;
  cached_names_.clear();
  cached_index_.clear();
}

MappedFrame MarkerNameMap::map(const std::vector<std::string>& names,
                               std::vector<Eigen::Vector3d> positions_m,
                               std::vector<uint8_t> occluded) {
  MappedFrame out;
  if (names.empty()) {
    out.matched = positions_m.size();
    out.positions_m = std::move(positions_m);
    out.occluded = std::move(occluded);
    return out;
  }
  if (names.size() != positions_m.size() ||
      (!occluded.empty() && occluded.size() != positions_m.size())) {
    out.rejection = kLengthsDiffer;
    return out;
  }
  if (!have_index_ || names != cached_names_) {
    have_index_ = true;
    out.names_changed = true;
    cached_names_ = names;
    cached_index_.assign(names.size(), -1);
    cached_unknown_ = 0;
    cached_example_unknown_.clear();
    std::unordered_map<std::string, int> index;
    for (size_t i = 0; i < particles_.size(); ++i) index[particles_[i]] = static_cast<int>(i);
    for (size_t k = 0; k < names.size(); ++k) {
      auto it = index.find(names[k]);
      if (it != index.end()) {
        cached_index_[k] = it->second;
      } else if (cached_unknown_++ == 0) {
        cached_example_unknown_ = names[k];
      }
    }
    if (cached_unknown_ > 0)
      out.warning = std::to_string(cached_unknown_) +
                    " marker names in the input are not model particles (ignored), e.g. '" +
                    cached_example_unknown_ + "'";
  }
  out.unknown = cached_unknown_;
  out.example_unknown = cached_example_unknown_;
  out.positions_m.assign(particles_.size(), Eigen::Vector3d::Zero());
  // A particle absent from the frame has no marker in it: the estimator tells a point of the
  // model only (a fixed particle, e.g. an anchor) from a hidden marker.
  out.occluded.assign(particles_.size(), OnlineEstimator::kNoMarker);
  for (size_t k = 0; k < names.size(); ++k) {
    const int i = cached_index_[k];
    if (i < 0) continue;
    out.positions_m[i] = positions_m[k];
    out.occluded[i] = !occluded.empty() && occluded[k];
    ++out.matched;
  }
  if (out.matched == 0) out.rejection = kNoNameMatches;
  return out;
}

}  // namespace mme
