// Real-time set-up of the loop thread, once at its start: lock memory (mlockall), SCHED_FIFO at
// the configured priority, CPU affinity, and pre-faulted stack and heap so the first cycles do
// not page-fault. Each step that fails is reported with its cause and what grants it
// (CAP_SYS_NICE or RLIMIT_RTPRIO for SCHED_FIFO, CAP_IPC_LOCK or RLIMIT_MEMLOCK for mlockall).
// The daemon refuses to arm with a failed step unless degraded timing is allowed (CI, desktops),
// and says so in its status. Not called on the real-time path itself.
//
// While the loop runs it also holds a CPU wake-up latency request (PM QoS, the value written to
// /dev/cpu_dma_latency, kept while the file stays open), as cyclictest does: without it an
// idle CPU may sleep in a deep state, and the sleep's exit adds to every wake-up (measured here
// in a VM: cyclictest's p50 13 us with the request, 31 us without). The file belongs to root;
// when it cannot be held the loop runs anyway and the status says why (a note, not a problem
// that refuses arming): docs/daemon.md shows the udev rule that grants it to the daemon's group.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace selfsense::runtime {

struct RtOptions {
  int priority{80};                         // SCHED_FIFO 1..99
  int cpu{-1};                              // -1: no affinity
  std::size_t prefault_stack{256U << 10U};  // bytes of stack touched
  std::size_t prefault_heap{8U << 20U};     // bytes malloc'ed, touched and freed (kept by glibc)
  int cpu_latency_us{0};  // the wake-up latency requested while running [us]; -1: no request
};

struct RtSetupResult {
  bool memory_locked{false};
  bool fifo{false};
  bool affinity{false};
  bool cpu_latency_held{false};
  std::vector<std::string> problems{};  // one sentence each, with the cause
  std::vector<std::string> notes{};     // what failed without refusing arming, with the cause
  [[nodiscard]] bool complete() const noexcept { return problems.empty(); }
};

// A CPU wake-up latency request held while the object lives (RAII over the open file).
class CpuLatencyRequest final {
 public:
  CpuLatencyRequest() = default;
  // Requests `us` microseconds; on failure held() is false and *why says what and why.
  CpuLatencyRequest(int us, std::string* why);
  CpuLatencyRequest(const CpuLatencyRequest&) = delete;
  CpuLatencyRequest& operator=(const CpuLatencyRequest&) = delete;
  CpuLatencyRequest(CpuLatencyRequest&& other) noexcept;
  CpuLatencyRequest& operator=(CpuLatencyRequest&& other) noexcept;
  ~CpuLatencyRequest();
  [[nodiscard]] bool held() const noexcept { return fd_ >= 0; }

 private:
  int fd_{-1};
};

// Applies to the calling thread (and mlockall to the process).
[[nodiscard]] RtSetupResult setup_realtime(const RtOptions& options);

}  // namespace selfsense::runtime
