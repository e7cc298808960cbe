#include "motion_model_estimation/io/path_confinement.h"

#include <sys/stat.h>

#include <climits>
#include <cstdlib>

namespace mme {

std::string realPath(const std::string& path) {
  char buffer[PATH_MAX];
  if (!::realpath(path.c_str(), buffer)) return "";
  return buffer;
}

namespace {

bool isInside(const std::string& root, const std::string& candidate) {
  return candidate.size() > root.size() && candidate.compare(0, root.size(), root) == 0 &&
         (root.back() == '/' || candidate[root.size()] == '/');
}

}  // namespace

std::string confinePath(const std::string& directory, const std::string& path, bool for_writing,
                        std::string* error) {
  const std::string root = realPath(directory);
  if (root.empty()) {
    *error = "model directory '" + directory + "' does not exist";
    return "";
  }
  if (path.empty()) {
    *error = "empty path";
    return "";
  }
  const std::string joined = path[0] == '/' ? path : root + "/" + path;
  if (!for_writing) {
    const std::string real = realPath(joined);
    if (real.empty()) {
      *error = "'" + path + "' does not exist";
      return "";
    }
    if (!isInside(root, real)) {
      *error = "'" + path + "' is outside the model directory " + root + " (refused)";
      return "";
    }
    return real;
  }
  const size_t slash = joined.find_last_of('/');
  const std::string parent = joined.substr(0, slash == 0 ? 1 : slash);
  const std::string name = joined.substr(slash + 1);
  if (name.empty() || name == "." || name == "..") {
    *error = "'" + path + "' does not name a file";
    return "";
  }
  const std::string real_parent = realPath(parent);
  if (real_parent.empty()) {
    *error = "the directory of '" + path + "' does not exist";
    return "";
  }
  const std::string target = real_parent + "/" + name;
  if (!(real_parent == root || isInside(root, real_parent))) {
    *error = "'" + path + "' is outside the model directory " + root + " (refused)";
    return "";
  }
  struct stat st;
  if (::lstat(target.c_str(), &st) == 0 && S_ISLNK(st.st_mode)) {
    *error = "'" + path + "' is a symlink (refused: it could lead out of " + root + ")";
    return "";
  }
  return target;
}

}  // namespace mme
