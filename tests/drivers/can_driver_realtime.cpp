// The CAN driver's real-time calls under a real kernel (run in the VM by
// tests/vm/payload/can_loop.sh against `selfsense sim-device --can`): after activation, a 1 kHz
// loop of read() and write() for 2 s while every heap allocation and lock in the process is
// counted (the bus thread included). Prints one "name=value" line; exit 0 only if the loop read
// fresh inputs, sent its commands, and nothing allocated or locked.
//   can_driver_realtime IFACE CONFIG.yaml
#include <time.h>

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>

#include "selfsense/daemon/config.hpp"
#include "selfsense/drivers/can/can_driver.hpp"
#include "selfsense/drivers/registry/registry.hpp"
#include "support/allocation_counter.hpp"

namespace {

std::int64_t now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

void sleep_until(std::int64_t t) {
  const timespec ts{static_cast<time_t>(t / 1'000'000'000), static_cast<long>(t % 1'000'000'000)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) != 0) {
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    static_cast<void>(std::fprintf(stderr, "usage: can_driver_realtime IFACE CONFIG.yaml\n"));
    return 2;
  }
  selfsense::drivers::Registry registry;
  const auto loaded = selfsense::daemon::load_config(argv[2], &registry);
  if (!loaded.ok()) {
    static_cast<void>(std::fprintf(stderr, "%s\n", loaded.problems.front().c_str()));
    return 2;
  }
  selfsense::drivers::can::CanConfig config = registry.can_config();
  config.interface = argv[1];
  selfsense::drivers::can::CanDriver driver(config);
  std::string why;
  if (!driver.configure({1e-3}, &why) || !driver.activate(&why)) {
    static_cast<void>(std::fprintf(stderr, "can_driver_realtime: %s\n", why.c_str()));
    return 2;
  }
  selfsense::runtime::InputSample in;
  for (int i = 0; i < 3000 && driver.read(in) != selfsense::runtime::DriverStatus::kOk; ++i)
    sleep_until(now_ns() + 1'000'000);

  constexpr int kCycles = 2000;
  int ok = 0;
  int sent = 0;
  std::size_t allocations = 0;
  std::size_t locks = 0;
  {
    const selfsense::test::AllocationCounter counter;
    std::int64_t next = now_ns();
    for (int i = 0; i < kCycles; ++i) {
      next += 1'000'000;
      sleep_until(next);
      if (driver.read(in) == selfsense::runtime::DriverStatus::kOk) ++ok;
      if (driver.write({1.0e5}) == selfsense::runtime::DriverStatus::kOk) ++sent;
    }
    allocations = counter.count();
    locks = counter.locks();
  }
  driver.deactivate();
  std::printf("realtime_allocations=%zu locks=%zu reads_ok=%d writes_ok=%d cycles=%d\n",
              allocations, locks, ok, sent, kCycles);
  return allocations == 0 && locks == 0 && ok > kCycles / 2 && sent == kCycles ? 0 : 1;
}
