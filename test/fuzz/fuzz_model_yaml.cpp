// libFuzzer harness: mme::loadModelString on arbitrary text. Only InputError may come out; a
// loaded model must validate, and its export must load again (round trip).
#include <cstdlib>
#include <string>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/io/model_yaml.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  mme::Model model;
  try {
    model = mme::loadModelString(text, "fuzz.yaml");
  } catch (const mme::InputError&) {
    return 0;
  }
  if (!mme::validateModel(model).empty()) std::abort();
  try {
    (void)mme::loadModelString(mme::modelToYaml(model), "roundtrip.yaml");
  } catch (const mme::InputError& e) {
    std::fprintf(stderr, "export of a loaded model does not load: %s\n", e.what());
    std::abort();
  }
  return 0;
}
