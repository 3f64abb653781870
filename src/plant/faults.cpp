#include "selfsense/plant/faults.hpp"

#include <algorithm>
#include <limits>

#include "selfsense/plant/status.hpp"

namespace selfsense::plant {

bool FaultTable::add(const ActiveFault& fault) noexcept {
  if (size_ == faults_.size()) return false;
  faults_[size_] = fault;
  ++size_;
  return true;
}

FaultEffects FaultTable::at(std::int64_t sample) const noexcept {
  FaultEffects fx{};
  for (std::size_t i = 0; i < size_; ++i) {
    const ActiveFault& f = faults_[i];
    if (sample < f.start || sample >= f.end) continue;
    const bool e = f.channel != Channel::d;
    const bool d = f.channel != Channel::e;
    switch (f.kind) {
      case FaultKind::stuck_adc:
        fx.stuck_e = fx.stuck_e || e;
        fx.stuck_d = fx.stuck_d || d;
        break;
      case FaultKind::nan_sample:
        fx.nan_e = fx.nan_e || e;
        fx.nan_d = fx.nan_d || d;
        break;
      case FaultKind::out_of_range:
        fx.out_of_range_e = fx.out_of_range_e || e;
        fx.out_of_range_d = fx.out_of_range_d || d;
        break;
      case FaultKind::sensor_disconnect:
        fx.disconnect_e = fx.disconnect_e || e;
        fx.disconnect_d = fx.disconnect_d || d;
        break;
      case FaultKind::missed_data_ready:
        fx.missed_data_ready = true;
        break;
      case FaultKind::late_sample:
        fx.late_by_s = std::max(fx.late_by_s, f.late_by_s);
        break;
      case FaultKind::amplifier_fault:
        fx.amplifier_fault = true;
        break;
    }
  }
  return fx;
}

Measurement apply_faults(const FaultEffects& fx, Measurement fresh, const Measurement& last,
                         const Measurement& out_of_range, std::uint32_t* flags) noexcept {
  Measurement m = fresh;
  if (fx.disconnect_e || fx.disconnect_d) *flags |= kSensorDisconnect;
  if (fx.stuck_e) m.e_v_per_m = last.e_v_per_m;
  if (fx.stuck_d) m.d_c_per_m2 = last.d_c_per_m2;
  if (fx.stuck_e || fx.stuck_d) *flags |= kStuckAdc;
  if (fx.out_of_range_e) m.e_v_per_m = out_of_range.e_v_per_m;
  if (fx.out_of_range_d) m.d_c_per_m2 = out_of_range.d_c_per_m2;
  if (fx.out_of_range_e || fx.out_of_range_d) *flags |= kOutOfRange;
  constexpr double kNan{std::numeric_limits<double>::quiet_NaN()};
  if (fx.nan_e) m.e_v_per_m = kNan;
  if (fx.nan_d) m.d_c_per_m2 = kNan;
  if (fx.nan_e || fx.nan_d) *flags |= kNanSample;
  if (fx.missed_data_ready) {
    m = last;
    *flags |= kMissedDataReady;
  }
  if (fx.late_by_s > 0.0) *flags |= kLateSample;
  if (fx.amplifier_fault) *flags |= kAmplifierFault;
  return m;
}

}  // namespace selfsense::plant
