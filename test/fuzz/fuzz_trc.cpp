// libFuzzer harness: mme::readTrc on arbitrary bytes. Only InputError may come out; whatever it
// returns must be a consistent trajectory (validate() empty: sizes and finite positions;
// finite rate and times).
#include <cmath>
#include <cstdlib>

#include "fuzz_common.h"
#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/io/trc.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string& path = mme_fuzz::writeTemp(data, size, ".trc");
  try {
    const mme::Trajectory t = mme::readTrc(path);
    if (!t.validate().empty()) std::abort();
    if (t.numMarkers() <= 0 || t.numFrames() <= 0) std::abort();
    if (!(t.frame_rate_hz > 0.0) || !std::isfinite(t.frame_rate_hz)) std::abort();
    if (t.frame_numbers.size() != t.times_s.size()) std::abort();
    for (double time : t.times_s)
      if (!std::isfinite(time)) std::abort();
  } catch (const mme::InputError&) {
  }
  return 0;
}
