// The calling thread's own clock, to tell where a slow stretch of a thread went: computing on a
// core, runnable but waiting for a core (other threads or processes had them), or neither
// (sleeping, blocked on a lock, a page fault or I/O). Linux's per-thread scheduler statistics
// (/proc/thread-self/schedstat); elsewhere only the time on a core is known. And the priority of
// a background thread, lowered so that a thread that must keep its pace gets the cores first.
// No ROS here.
#pragma once

#include <string>

namespace mme {

struct ThreadTimes {
  double on_cpu_s = 0.0;     ///< [s] the calling thread's time on a core since it started
  double waiting_s = 0.0;    ///< [s] its time runnable but waiting for a core (0 when unknown)
  bool waiting_known = false;  ///< whether waiting_s was measured (Linux schedstat)
};

/// The calling thread's times (cheap: one small /proc read, or one clock call).
ThreadTimes callingThreadTimes();

/// Lowers the calling thread's scheduling priority to niceness `nice` (0..19; Linux: per
/// thread, no privilege needed to lower it). "" when done, else why not (the thread then keeps
/// its priority: a slower update rate, never a failure).
std::string lowerCallingThreadPriority(int nice);

/// Names the calling thread (Linux: at most 15 characters, shown by top -H and ps -L; longer
/// names are cut; elsewhere nothing happens).
void nameCallingThread(const std::string& name);

}  // namespace mme
