#include "selfsense/runtime/rt_setup.hpp"

#include <fcntl.h>
#include <malloc.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "selfsense/base/errno_text.hpp"

namespace selfsense::runtime {
namespace {

std::string limit_text(int resource) {
  rlimit l{};
  if (getrlimit(resource, &l) != 0) return "unknown";
  if (l.rlim_cur == RLIM_INFINITY) return "unlimited";
  return std::to_string(l.rlim_cur);
}

// Touches the stack below this frame so its pages are mapped (and locked) before the loop runs.
void prefault_stack(std::size_t bytes) {
  volatile unsigned char* page = static_cast<unsigned char*>(alloca(bytes));
  for (std::size_t i = 0; i < bytes; i += 4096)
    page[i] = 0;
}

}  // namespace

CpuLatencyRequest::CpuLatencyRequest(int us, std::string* why) {
  const char* const path = "/dev/cpu_dma_latency";
  const int fd = ::open(path, O_WRONLY | O_CLOEXEC);
  const std::int32_t value = us;  // the kernel takes a binary 32-bit value
  if (fd >= 0 && ::write(fd, &value, sizeof(value)) == static_cast<ssize_t>(sizeof(value))) {
    fd_ = fd;
    return;
  }
  const int e = errno;
  if (fd >= 0) ::close(fd);
  if (why != nullptr) {
    *why = std::string("CPU wake-up latency ") + std::to_string(us) + " us (" + path +
           "): " + base::errno_text(e) +
           " (written by root only unless a udev rule grants it; deep idle states stay allowed)";
  }
}

CpuLatencyRequest::CpuLatencyRequest(CpuLatencyRequest&& other) noexcept : fd_(other.fd_) {
  other.fd_ = -1;
}

CpuLatencyRequest& CpuLatencyRequest::operator=(CpuLatencyRequest&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = other.fd_;
    other.fd_ = -1;
  }
  return *this;
}

CpuLatencyRequest::~CpuLatencyRequest() {
  if (fd_ >= 0) ::close(fd_);  // closing the file drops the request
}

RtSetupResult setup_realtime(const RtOptions& options) {
  RtSetupResult r;
  if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
    r.memory_locked = true;
    // Keep freed memory mapped: no trimming or mmap'd chunks that page-fault later.
    static_cast<void>(mallopt(M_TRIM_THRESHOLD, -1));
    static_cast<void>(mallopt(M_MMAP_MAX, 0));
  } else {
    const int e = errno;
    r.problems.push_back(std::string("mlockall: ") + base::errno_text(e) +
                         " (needs CAP_IPC_LOCK or RLIMIT_MEMLOCK, now " +
                         limit_text(RLIMIT_MEMLOCK) + " bytes)");
  }
  sched_param sp{};
  sp.sched_priority = options.priority;
  const int fifo = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp);
  if (fifo == 0) {
    r.fifo = true;
  } else {
    r.problems.push_back(
        "SCHED_FIFO priority " + std::to_string(options.priority) + ": " + base::errno_text(fifo) +
        " (needs CAP_SYS_NICE or RLIMIT_RTPRIO >= " + std::to_string(options.priority) + ", now " +
        limit_text(RLIMIT_RTPRIO) + ")");
  }
  if (options.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(static_cast<std::size_t>(options.cpu), &set);
    const int aff = pthread_setaffinity_np(pthread_self(), sizeof(set), &set);
    if (aff == 0) {
      r.affinity = true;
    } else {
      r.problems.push_back("CPU affinity to CPU " + std::to_string(options.cpu) + ": " +
                           base::errno_text(aff));
    }
  } else {
    r.affinity = true;
  }
  prefault_stack(options.prefault_stack);
  if (options.prefault_heap > 0) {
    auto* heap = static_cast<unsigned char*>(std::malloc(options.prefault_heap));
    if (heap != nullptr) {
      for (std::size_t i = 0; i < options.prefault_heap; i += 4096)
        heap[i] = 1;
      std::free(heap);
    }
  }
  return r;
}

}  // namespace selfsense::runtime
