// Fault injection: a fixed-capacity table of faults, each active on the sample interval
// [start, end). Filled from the configuration's schedule at construction or by explicit calls
// (Plant::inject). No heap memory; every method is real-time safe.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "selfsense/plant/config.hpp"

namespace selfsense::plant {

struct ActiveFault {
  FaultKind kind{FaultKind::nan_sample};
  Channel channel{Channel::d};
  std::int64_t start{0};
  std::int64_t end{0};
  double late_by_s{0.0};
};

// What the faults active at one sample do.
struct FaultEffects {
  bool stuck_e{false};
  bool stuck_d{false};
  bool nan_e{false};
  bool nan_d{false};
  bool out_of_range_e{false};
  bool out_of_range_d{false};
  bool disconnect_e{false};
  bool disconnect_d{false};
  bool missed_data_ready{false};
  bool amplifier_fault{false};
  double late_by_s{0.0};
};

// One delivered sample of both channels.
struct Measurement {
  double e_v_per_m{0.0};
  double d_c_per_m2{0.0};
};

// Applies the sample's faults to the freshly converted values: a stuck ADC or a missed
// data-ready repeats the last delivered value, out_of_range and nan_sample replace it (in that
// order of precedence, NaN last). ORs every fault's status bit into *flags. A disconnect acts on
// the converter input (the caller measures 0) and only sets its bit here.
[[nodiscard]] Measurement apply_faults(const FaultEffects& fx, Measurement fresh,
                                       const Measurement& last, const Measurement& out_of_range,
                                       std::uint32_t* flags) noexcept;

class FaultTable final {
 public:
  // False when the table is full (kMaxScheduledFaults).
  bool add(const ActiveFault& fault) noexcept;
  void clear() noexcept { size_ = 0; }
  [[nodiscard]] std::size_t size() const noexcept { return size_; }
  [[nodiscard]] FaultEffects at(std::int64_t sample) const noexcept;

 private:
  std::array<ActiveFault, kMaxScheduledFaults> faults_{};
  std::size_t size_{0};
};

}  // namespace selfsense::plant
