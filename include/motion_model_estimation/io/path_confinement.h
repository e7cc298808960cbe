// Keeps file access of services under one directory: a user-supplied path is resolved against
// the directory and refused when it would leave it ("..", absolute paths elsewhere, symlinks
// pointing out).
#pragma once

#include <string>

namespace mme {

/// The absolute path of an existing `path`, every link resolved; empty when it does not
/// resolve.
std::string realPath(const std::string& path);

/// Resolves `path` (relative = inside `directory`) to an absolute path inside `directory`.
/// `for_writing`: the file may not exist yet, but its parent directory must, and an existing
/// file must not be a symlink; otherwise the file must exist and its real path must be inside.
/// Returns an empty string and fills *error when the path is refused.
std::string confinePath(const std::string& directory, const std::string& path, bool for_writing,
                        std::string* error);

}  // namespace mme
