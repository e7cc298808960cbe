// check_model_file: a test helper that says whether a model file loads (mme::loadModelFile),
// without python or yaml tools. Used by test/cli/test_crash_restart.sh on the autosave while
// the node rewrites it.
//   check_model_file FILE                      exit 0 when it loads, 2 (one line why) when not
//   check_model_file FILE --print              also prints "name value" per free parameter
//   check_model_file FILE --compare TRUTH [--tolerance REL]
//       exit 1 when a free parameter of FILE differs from TRUTH's value by more than REL
//       (relative, default 0.01); prints the largest relative error either way.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/core/model.h"
#include "motion_model_estimation/io/model_yaml.h"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: check_model_file FILE [--print] [--compare TRUTH [--tolerance REL]]\n");
    return 2;
  }
  std::string truth_path;
  bool print = false;
  double tolerance = 0.01;
  for (int k = 2; k < argc; ++k) {
    const std::string a = argv[k];
    if (a == "--print") {
      print = true;
    } else if (a == "--compare" && k + 1 < argc) {
      truth_path = argv[++k];
    } else if (a == "--tolerance" && k + 1 < argc) {
      tolerance = std::atof(argv[++k]);
    } else {
      std::fprintf(stderr, "check_model_file: unknown option %s\n", a.c_str());
      return 2;
    }
  }
  try {
    const mme::Model model = mme::loadModelFile(argv[1]);
    const std::vector<mme::ParamRef> refs = mme::freeParameters(model);
    if (print)
      for (const mme::ParamRef& r : refs)
        std::printf("%s %.17g\n", r.name.c_str(), mme::getParam(model, r));
    if (truth_path.empty()) return 0;
    const mme::Model truth = mme::loadModelFile(truth_path);
    const std::vector<mme::ParamRef> truth_refs = mme::freeParameters(truth);
    if (truth_refs.size() != refs.size()) {
      std::fprintf(stderr, "check_model_file: %s and %s differ in free parameters\n", argv[1],
                   truth_path.c_str());
      return 2;
    }
    double worst = 0.0;
    std::string worst_name;
    for (size_t k = 0; k < refs.size(); ++k) {
      const double t = mme::getParam(truth, truth_refs[k]);
      const double v = mme::getParam(model, refs[k]);
      const double e = std::fabs(v - t) / std::max(std::fabs(t), 1e-12);
      if (!(e <= worst)) {
        worst = e;
        worst_name = refs[k].name;
      }
    }
    std::printf("max relative error %.3g (%s)\n", worst, worst_name.c_str());
    return worst <= tolerance ? 0 : 1;
  } catch (const mme::InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
}
