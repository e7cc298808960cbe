// Command-line parsing for the tools from one option table per tool: the same table parses the
// command line and prints `--help`, so an option cannot be accepted without being documented.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace mme {

/// One option of a tool: "--name VALUE" (a valued option) or "--name" (a switch).
struct CliOption {
  std::string name;         ///< without the leading "--"
  std::string value_name;   ///< e.g. "FILE", "N"; empty: a switch
  std::string default_text; ///< what holds when the option is not given ("" for switches)
  std::string meaning;      ///< one or two sentences for --help
};

/// A titled group of options, in the order --help lists them.
struct CliGroup {
  std::string title;
  std::vector<CliOption> options;
};

/// A tool's whole command line: what it does, its options, examples and the next step.
struct CliSpec {
  std::string tool;
  std::string synopsis;  ///< the usage line after "usage: TOOL "
  std::string purpose;   ///< what the tool is for, a sentence or two
  std::vector<CliGroup> groups;
  std::vector<std::string> examples;  ///< whole command lines
  std::string next_step;              ///< what to run next with the tool's output
};

/// The reference --help prints: usage, purpose, every option grouped with its meaning and
/// default, examples, the next step.
std::string formatHelp(const CliSpec& spec);

/// Parses argv into key -> value by `spec`'s table ("--help" is always a switch). Throws
/// InputError on an unknown option, a missing value or a repeated option.
class CliArgs {
 public:
  CliArgs(int argc, char** argv, const CliSpec& spec);
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

/// A tool's main(): stdout line-buffered (so that a warning on stderr never lands inside a
/// table when both go to one pipe), `run` run and its exceptions turned into one line on
/// stderr prefixed by the tool's name, exit code 2 for bad input (InputError), 1 for anything
/// else.
int runTool(const char* tool, int (*run)(int, char**), int argc, char** argv);

/// Prints formatHelp(spec) to stdout when argv holds --help; true when it did (the tool then
/// returns 0). The help is printed before any other check so that it always works.
bool printHelpIfAsked(int argc, char** argv, const CliSpec& spec);

/// `path` made absolute (roslaunch starts nodes in the ROS home, so a printed command must not
/// depend on the shell's directory); `path` itself when it cannot be resolved.
std::string absolutePath(const std::string& path);

/// The command that shows `model_path` as it is in rviz, played against the capture
/// `trajectory_path` (replay.launch with estimate:=false): the last step of every tool's output.
std::string rvizCommand(const std::string& model_path, const std::string& trajectory_path);

}  // namespace mme
