// Shared helper of the libFuzzer harnesses: the readers take a path, so each input is written
// to one per-process temporary file (no API added for fuzzing).
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace mme_fuzz {

/// Writes data to this process's temp file (created once, removed at exit) and returns its
/// path. `suffix` keeps the extension the reader may look at.
inline const std::string& writeTemp(const uint8_t* data, size_t size, const char* suffix) {
  static std::string path;
  if (path.empty()) {
    const char* dir = std::getenv("TMPDIR");
    path = std::string(dir && *dir ? dir : "/tmp") + "/mme_fuzz_" + std::to_string(::getpid()) +
           suffix;
    std::atexit([] { std::remove(path.c_str()); });
  }
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();
  if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
  return path;
}

}  // namespace mme_fuzz
