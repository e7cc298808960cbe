// callingThreadTimes: a thread's time on a core grows while it computes and not while it
// sleeps; lowerCallingThreadPriority lowers only the calling thread's priority.
#include <gtest/gtest.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <string>
#include <thread>

#if defined(__linux__)
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

#include "motion_model_estimation/live/thread_times.h"

namespace {

double spin(double seconds_on_cpu) {
  const mme::ThreadTimes start = mme::callingThreadTimes();
  volatile double x = 1.0;
  while (mme::callingThreadTimes().on_cpu_s - start.on_cpu_s < seconds_on_cpu)
    for (int k = 0; k < 10000; ++k) x = std::sqrt(x + k);
  return x;
}

TEST(ThreadTimes, OnCpuGrowsWhileComputingNotWhileSleeping) {
  const mme::ThreadTimes a = mme::callingThreadTimes();
  spin(0.02);
  const mme::ThreadTimes b = mme::callingThreadTimes();
  EXPECT_GE(b.on_cpu_s - a.on_cpu_s, 0.02);
  EXPECT_GE(b.waiting_s, a.waiting_s);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const mme::ThreadTimes c = mme::callingThreadTimes();
  EXPECT_LT(c.on_cpu_s - b.on_cpu_s, 0.1);  // asleep: off the cores (the wall time was 0.2 s)
#if defined(__linux__)
  EXPECT_TRUE(c.waiting_known);
#endif
}

#if defined(__linux__)
TEST(ThreadTimes, LowersOnlyTheCallingThreadsPriority) {
  errno = 0;
  const int before = getpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)));
  int inside = -100;
  std::string error;
  std::thread background([&] {
    error = mme::lowerCallingThreadPriority(std::min(19, before + 5));
    inside = getpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)));
  });
  background.join();
  EXPECT_EQ(error, "");
  EXPECT_EQ(inside, std::min(19, before + 5));
  EXPECT_EQ(getpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid))), before);
  EXPECT_NE(mme::lowerCallingThreadPriority(20), "");
}
#endif

}  // namespace
