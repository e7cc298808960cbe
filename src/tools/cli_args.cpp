#include "cli_args.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <map>
#include <sstream>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/io/path_confinement.h"

namespace mme {

CliArgs::CliArgs(int argc, char** argv, const CliSpec& spec) {
  std::map<std::string, bool> valued;  // name -> takes a value
  valued["help"] = false;
  for (const CliGroup& group : spec.groups)
    for (const CliOption& option : group.options) valued[option.name] = !option.value_name.empty();
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("--", 0) != 0)
      throw InputError("unexpected argument '" + arg + "' (options start with --; see --help)");
    const std::string key = arg.substr(2);
    if (values_.count(key)) throw InputError("option --" + key + " given twice");
    auto it = valued.find(key);
    if (it == valued.end()) throw InputError("unknown option --" + key + " (see --help)");
    if (!it->second) {
      values_[key] = "1";
    } else {
      if (i + 1 >= argc) throw InputError("option --" + key + " needs a value");
      values_[key] = argv[++i];
    }
  }
}

namespace {

/// `text` wrapped to lines of at most `width` characters, each prefixed by `indent`.
std::string wrap(const std::string& text, size_t indent, size_t width) {
  std::istringstream words(text);
  std::string word, out, line;
  const std::string pad(indent, ' ');
  while (words >> word) {
    if (!line.empty() && line.size() + 1 + word.size() > width - indent) {
      out += pad + line + "\n";
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
  }
  if (!line.empty()) out += pad + line + "\n";
  return out;
}

}  // namespace

std::string formatHelp(const CliSpec& spec) {
  constexpr size_t kWidth = 100;
  std::string out = "usage: " + spec.tool + " " + spec.synopsis + "\n\n" + wrap(spec.purpose, 0, kWidth);
  for (const CliGroup& group : spec.groups) {
    out += "\n" + group.title + ":\n";
    for (const CliOption& o : group.options) {
      out += "  --" + o.name + (o.value_name.empty() ? "" : " " + o.value_name) + "\n";
      std::string meaning = o.meaning;
      if (!o.default_text.empty()) meaning += " Default: " + o.default_text + ".";
      out += wrap(meaning, 6, kWidth);
    }
  }
  out += "\n  --help\n" + wrap("This reference.", 6, kWidth);
  if (!spec.examples.empty()) {
    out += "\nExamples:\n";
    for (const std::string& example : spec.examples) out += "  " + example + "\n";
  }
  if (!spec.next_step.empty()) out += "\nNext step:\n" + wrap(spec.next_step, 2, kWidth);
  return out;
}

bool printHelpIfAsked(int argc, char** argv, const CliSpec& spec) {
  for (int i = 1; i < argc; ++i)
    if (std::string(argv[i]) == "--help") {
      std::fputs(formatHelp(spec).c_str(), stdout);
      return true;
    }
  return false;
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
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
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

std::string absolutePath(const std::string& path) {
  const std::string real = realPath(path);
  return real.empty() ? path : real;
}

std::string rvizCommand(const std::string& model_path, const std::string& trajectory_path) {
  return "roslaunch motion_model_estimation replay.launch model:=" + absolutePath(model_path) +
         " bag:=" + absolutePath(trajectory_path) + " estimate:=false rviz:=true";
}

}  // namespace mme
