// Model files on disk: reading a model file's text for the YAML loader, and writing an export
// atomically (a temp file in the same directory, fsync, rename), so that a reader, or a node
// restarted after a crash, sees either the old file or the complete new one.

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "motion_model_estimation/core/error.h"
#include "motion_model_estimation/io/model_yaml.h"

namespace mme {

namespace {

/// Closes `fd` and removes `tmp` after a failure, then throws with the saved errno.
[[noreturn]] void failWrite(const std::string& path, const std::string& tmp, int fd, int err) {
  if (fd >= 0) ::close(fd);
  if (!tmp.empty()) ::unlink(tmp.c_str());
  throw InputError(path + ": cannot write: " + std::strerror(err));
}

/// What a file that is not YAML text is, recognised by its first bytes ("" when it may be a
/// model file): a capture or a bag given as --model says so instead of a YAML syntax error.
std::string wrongKind(const std::string& text) {
  if (text.rfind("PathFileType", 0) == 0) return "a TRC marker file (a capture)";
  if (text.rfind("#ROSBAG", 0) == 0) return "a rosbag";
  // C3D: the first 512-byte block starts with the parameter block's number and the key 0x50.
  if (text.size() >= 512 && static_cast<unsigned char>(text[0]) < 0x20 &&
      static_cast<unsigned char>(text[1]) == 0x50)
    return "a C3D file (a capture)";
  if (text.find('\0') != std::string::npos) return "a binary file";
  return "";
}

}  // namespace

Model loadModelFile(const std::string& path) {
  // POSIX read rather than ifstream: it reports a directory or a permission problem as an
  // error (with errno) instead of an empty read.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw InputError(path + ": cannot read file (" + std::strerror(errno) + ")");
  std::string text;
  char buf[65536];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n == 0) break;
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      ::close(fd);
      throw InputError(path + ": cannot read file (" + std::strerror(err) + ")");
    }
    text.append(buf, static_cast<std::size_t>(n));
  }
  ::close(fd);
  const std::string kind = wrongKind(text);
  if (!kind.empty())
    throw InputError(path + ": this is " + kind + ", not a model file (YAML text: particles, "
                     "bond_types, bonds; docs/model_file.md); a capture goes to --trajectory");
  return loadModelString(text, path);
}

void writeFileAtomically(const std::string& path, const std::string& content) {
  // The temp file is in the target's directory so that rename() is atomic (same filesystem):
  // a reader sees either the old file or the complete new one, never a partial write.
  std::string tmp = path + ".tmp.XXXXXX";
  std::vector<char> templ(tmp.begin(), tmp.end());
  templ.push_back('\0');
  const int fd = ::mkstemp(templ.data());
  if (fd < 0) failWrite(path, "", -1, errno);
  tmp = templ.data();
  // mkstemp creates 0600; a model file is meant to be shared like any other output.
  if (::fchmod(fd, 0644) != 0) failWrite(path, tmp, fd, errno);
  const char* data = content.data();
  std::size_t left = content.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, data, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      failWrite(path, tmp, fd, errno);
    }
    data += n;
    left -= static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0) failWrite(path, tmp, fd, errno);
  if (::close(fd) != 0) failWrite(path, tmp, -1, errno);
  if (::rename(tmp.c_str(), path.c_str()) != 0) failWrite(path, tmp, -1, errno);
}

void writeModelFile(const std::string& path, const Model& model, const IdentificationInfo* info) {
  writeFileAtomically(path, modelToYaml(model, info));
}

}  // namespace mme
