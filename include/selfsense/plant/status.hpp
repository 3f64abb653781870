// Status bits carried by every plant output sample. Fault bits report injected faults as a
// driver's status register would; the limit bits report where the amplifier or an ADC limited.
#pragma once

#include <cstdint>

namespace selfsense::plant {

enum StatusFlag : std::uint32_t {
  kStatusOk = 0U,
  kStuckAdc = 1U << 0U,
  kNanSample = 1U << 1U,
  kOutOfRange = 1U << 2U,
  kMissedDataReady = 1U << 3U,  // no new sample: the values repeat the last delivered ones
  kLateSample = 1U << 4U,       // delivered StepOutput::latency_s after its sampling instant
  kAmplifierFault = 1U << 5U,   // amplifier fault line asserted; output stage discharging
  kSensorDisconnect = 1U << 6U,
  kAdcClipped = 1U << 7U,
  kVoltageClipped = 1U << 8U,
  kSlewLimited = 1U << 9U,
  kCurrentLimited = 1U << 10U,
};

// Any bit that makes the sample unusable for estimation.
inline constexpr std::uint32_t kFaultMask{kStuckAdc | kNanSample | kOutOfRange | kMissedDataReady |
                                          kAmplifierFault | kSensorDisconnect};

}  // namespace selfsense::plant
