#include "cli_args.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <sstream>

#include "motion_model_estimation/core/error.h"

namespace mme {

CliArgs::CliArgs(int argc, char** argv, const std::set<std::string>& valued,
                 const std::set<std::string>& flags) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("--", 0) != 0) throw InputError("unexpected argument '" + arg + "'");
    const std::string key = arg.substr(2);
    if (values_.count(key)) throw InputError("option --" + key + " given twice");
    if (flags.count(key)) {
      values_[key] = "1";
    } else if (valued.count(key)) {
      if (i + 1 >= argc) throw InputError("option --" + key + " needs a value");
      values_[key] = argv[++i];
    } else {
      throw InputError("unknown option --" + key);
    }
  }
}

std::string CliArgs::get(const std::string& key, const std::string& fallback) const {
  auto it = values_.find(key);
  return it == values_.end() ? fallback : it->second;
}

long CliArgs::getInt(const std::string& key, long fallback, long min, long max) const {
  auto it = values_.find(key);
  if (it == values_.end()) return fallback;
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(it->second.c_str(), &end, 10);
  if (errno != 0 || end == it->second.c_str() || *end != '\0' || v < min || v > max)
    throw InputError("option --" + key + " must be an integer in [" + std::to_string(min) + ", " +
                     std::to_string(max) + "], got '" + it->second + "'");
  return v;
}

double CliArgs::getDouble(const std::string& key, double fallback, double min, double max) const {
  auto it = values_.find(key);
  if (it == values_.end()) return fallback;
  char* end = nullptr;
  const double v = std::strtod(it->second.c_str(), &end);
  if (end == it->second.c_str() || *end != '\0' || !std::isfinite(v) || v < min || v > max)
    throw InputError("option --" + key + " must be a number in [" + std::to_string(min) + ", " +
                     std::to_string(max) + "], got '" + it->second + "'");
  return v;
}

int runTool(const char* tool, int (*run)(int, char**), int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const InputError& e) {
    std::fprintf(stderr, "%s: %s\n", tool, e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: error: %s\n", tool, e.what());
    return 1;
  }
}

std::vector<int> parseCountList(const std::string& text, const std::string& option, long max,
                                const std::string& example) {
  std::vector<int> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    char* end = nullptr;
    const long k = std::strtol(item.c_str(), &end, 10);
    if (item.empty() || *end != '\0' || k < 1 || k > max)
      throw InputError(option + ": '" + item + "' is not a frame count >= 1 (e.g. " + example + ")");
    out.push_back(static_cast<int>(k));
  }
  if (out.empty()) throw InputError(option + ": empty (e.g. " + example + ")");
  return out;
}

}  // namespace mme
