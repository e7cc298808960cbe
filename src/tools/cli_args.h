// Minimal "--key value" command-line parsing for the tools, with one-line errors.
#pragma once

#include <map>
#include <set>
#include <string>
#include <vector>

namespace mme {

/// Parses argv into key -> value for "--key value" pairs and "--flag" switches. Throws
/// InputError on an unknown option, a missing value or a repeated option.
class CliArgs {
 public:
  CliArgs(int argc, char** argv, const std::set<std::string>& valued,
          const std::set<std::string>& flags);
  bool has(const std::string& key) const { return values_.count(key) != 0; }
  std::string get(const std::string& key, const std::string& fallback = "") const;
  /// Integer option in [min, max]; InputError naming the option otherwise.
  long getInt(const std::string& key, long fallback, long min, long max) const;
  /// Finite number option in [min, max]; InputError naming the option otherwise.
  double getDouble(const std::string& key, double fallback, double min, double max) const;

 private:
  std::map<std::string, std::string> values_;
};

/// A comma-separated list of frame counts in [1, max] given to `option` (e.g. "--horizons");
/// throws InputError naming the option, the bad item and `example` otherwise.
std::vector<int> parseCountList(const std::string& text, const std::string& option, long max,
                                const std::string& example);

/// A tool's main(): runs `run` and turns exceptions into one line on stderr prefixed by the
/// tool's name, exit code 2 for bad input (InputError), 1 for anything else.
int runTool(const char* tool, int (*run)(int, char**), int argc, char** argv);

}  // namespace mme
