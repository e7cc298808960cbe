#include "motion_model_estimation/live/thread_times.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>

#if defined(__linux__)
#include <pthread.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

namespace mme {

ThreadTimes callingThreadTimes() {
  ThreadTimes t;
#if defined(__linux__)
  // "<ns on a core> <ns waiting on a run queue> <time slices>"
  if (std::FILE* f = std::fopen("/proc/thread-self/schedstat", "r")) {
    unsigned long long on_cpu_ns = 0, waiting_ns = 0;
    const bool ok = std::fscanf(f, "%llu %llu", &on_cpu_ns, &waiting_ns) == 2;
    std::fclose(f);
    if (ok) {
      t.on_cpu_s = 1e-9 * static_cast<double>(on_cpu_ns);
      t.waiting_s = 1e-9 * static_cast<double>(waiting_ns);
      t.waiting_known = true;
      return t;
    }
  }
#endif
  timespec ts{};
  if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts) == 0)
    t.on_cpu_s = static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
  return t;
}

std::string lowerCallingThreadPriority(int nice) {
  if (nice < 0 || nice > 19) return "niceness must be in [0, 19]";
#if defined(__linux__)
  // On Linux a niceness set for a thread id applies to that thread alone.
  const pid_t tid = static_cast<pid_t>(::syscall(SYS_gettid));
  if (::setpriority(PRIO_PROCESS, static_cast<id_t>(tid), nice) != 0) return std::strerror(errno);
  return "";
#else
  return "per-thread priorities are Linux only";
#endif
}

void nameCallingThread(const std::string& name) {
#if defined(__linux__)
  ::pthread_setname_np(::pthread_self(), name.substr(0, 15).c_str());
#else
  (void)name;
#endif
}

}  // namespace mme
