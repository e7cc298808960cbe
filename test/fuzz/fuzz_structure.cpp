// libFuzzer harness: structure selection on arbitrary TRC bytes (seeds: the structure sweep's
// windows of real captures, test/fuzz/corpus/structure). The trajectory is read, its first 6
// markers and 60 frames become the particles and the window, and the structure is selected
// under a 0.2 s limit without refits (the numerics, not the refits' search, are the target).
// Only InputError may come out; a chosen model's values must be finite.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <numeric>

#include "fuzz_common.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/identification/structure/marker_model.h"
#include "motion_model_estimation/identification/structure/structure_selection.h"
#include "motion_model_estimation/io/trc.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string& path = mme_fuzz::writeTemp(data, size, ".trc");
  try {
    mme::Trajectory t = mme::readTrc(path);
    const int markers = std::min(t.numMarkers(), 6);
    std::vector<std::string> names(t.marker_names.begin(), t.marker_names.begin() + markers);
    t = mme::sliceFrames(mme::remapMarkers(t, names, nullptr), 0, std::min(t.numFrames(), 60));
    mme::StructureOptions options;
    options.refit = false;
    options.max_wall_time_s = 0.2;
    options.identify.es.threads = 1;
    const mme::StructureResult r = mme::selectStructure(mme::markerModel(t), t, options);
    for (const mme::BondType& type : r.model.bond_types)
      for (mme::ParamId id : mme::paramsOfKind(type.kind))
        if (type.param(id).present && !std::isfinite(type.value(id))) std::abort();
  } catch (const mme::InputError&) {
  }
  return 0;
}
