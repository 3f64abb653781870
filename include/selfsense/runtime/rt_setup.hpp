// Real-time set-up of the loop thread, once at its start: lock memory (mlockall), SCHED_FIFO at
// the configured priority, CPU affinity, and pre-faulted stack and heap so the first cycles do
// not page-fault. Each step that fails is reported with its cause and what grants it
// (CAP_SYS_NICE or RLIMIT_RTPRIO for SCHED_FIFO, CAP_IPC_LOCK or RLIMIT_MEMLOCK for mlockall).
// The daemon refuses to arm with a failed step unless degraded timing is allowed (CI, desktops),
// and says so in its status. Not called on the real-time path itself.
#pragma once

#include <string>
#include <vector>

namespace selfsense::runtime {

struct RtOptions {
  int priority{80};                         // SCHED_FIFO 1..99
  int cpu{-1};                              // -1: no affinity
  std::size_t prefault_stack{256U << 10U};  // bytes of stack touched
  std::size_t prefault_heap{8U << 20U};     // bytes malloc'ed, touched and freed (kept by glibc)
};

struct RtSetupResult {
  bool memory_locked{false};
  bool fifo{false};
  bool affinity{false};
  std::vector<std::string> problems{};  // one sentence each, with the cause
  [[nodiscard]] bool complete() const noexcept { return problems.empty(); }
};

// Applies to the calling thread (and mlockall to the process).
[[nodiscard]] RtSetupResult setup_realtime(const RtOptions& options);

}  // namespace selfsense::runtime
