#include "support/spi/ads131m04_emulator.hpp"

#include <cmath>
#include <utility>

namespace selfsense::test {

namespace adc = drivers::spi::ads131m04;

Ads131m04Emulator::Ads131m04Emulator(runtime::SimulatedClock& clock, double clkin_hz, Inputs inputs)
    : clock_(&clock), clkin_hz_(clkin_hz), inputs_(std::move(inputs)) {
  reset_registers();
  next_conversion_ns_ = clock_->now_ns() + period_ns();
}

void Ads131m04Emulator::reset_registers() noexcept {
  regs_.fill(0);
  regs_[adc::kRegId] = adc::kIdValue | 0x0001U;  // the low byte varies by revision
  regs_[adc::kRegMode] = adc::kModeResetValue;
  regs_[adc::kRegClock] = adc::kClockResetValue;
  regs_[adc::kRegCfg] = 0x0600;
  reset_flag_ = true;
  crc_err_flag_ = false;
  standby_ = false;
}

void Ads131m04Emulator::restart_conversions() noexcept {
  next_conversion_ns_ = clock_->now_ns() + period_ns();
  last_edge_taken_ns_ = -1;
}

void Ads131m04Emulator::spontaneous_reset() noexcept {
  reset_registers();
  pending_is_status_ = true;
}

double Ads131m04Emulator::data_rate_hz() const noexcept {
  const auto osr_code = static_cast<std::uint8_t>((regs_[adc::kRegClock] >> 2U) & 7U);
  return clkin_hz_ / 2.0 / static_cast<double>(adc::osr_of(osr_code));
}

std::int64_t Ads131m04Emulator::period_ns() const noexcept {
  return std::llround(1e9 / data_rate_hz());
}

void Ads131m04Emulator::convert_until(std::int64_t now) noexcept {
  while (next_conversion_ns_ <= now) {
    if (!standby_) {
      const std::array<double, 4> v = inputs_(next_conversion_ns_);
      const std::uint16_t g = regs_[adc::kRegGain];
      if (!stuck_) {
        for (std::size_t c = 0; c < 4; ++c) {
          const int gain = 1 << ((g >> (4U * c)) & 7U);
          codes_.at(c) = adc::code_of(v.at(c), gain);
        }
      }
      new_data_ = true;
      ++conversions_;
    }
    next_conversion_ns_ += period_ns();
  }
}

std::uint16_t Ads131m04Emulator::status() const noexcept {
  std::uint16_t s = regs_[adc::kRegMode] & 0x0300U;  // WLENGTH
  if (reset_flag_) s |= adc::kStatusReset;
  if (crc_err_flag_) s |= adc::kStatusCrcErr;
  if (new_data_) s |= adc::kStatusDrdyMask;
  return s;
}

bool Ads131m04Emulator::transfer(std::span<const std::uint8_t> tx,
                                 std::span<std::uint8_t> rx) noexcept {
  if (dead_ || tx.size() != rx.size()) return false;
  convert_until(clock_->now_ns());
  ++frames_;
  // Out: the previous command's answer, the newest codes, the CRC.
  adc::Frame out{};
  adc::put_word16(out, 0, pending_is_status_ ? status() : pending_);
  crc_err_flag_ = false;  // reading STATUS clears it
  for (std::size_t c = 0; c < 4; ++c)
    adc::put_code(out, 1 + c, codes_.at(c));
  std::uint16_t crc = adc::crc16(
      std::span<const std::uint8_t>(out.data(), (adc::kFrameWords - 1) * adc::kWordBytes));
  if (crc_errors_ > 0) {
    --crc_errors_;
    crc ^= 0x0400U;  // a bit flipped on DOUT
  }
  adc::put_word16(out, adc::kFrameWords - 1, crc);
  new_data_ = false;  // the frame read the conversion: DRDY rises
  for (std::size_t i = 0; i < rx.size(); ++i)
    rx[i] = i < out.size() ? out.at(i) : 0;
  // In: the command, answered in the next frame.
  execute(tx);
  return true;
}

void Ads131m04Emulator::execute(std::span<const std::uint8_t> tx) noexcept {
  if (tx.size() < adc::kFrameBytes) {
    ++rejected_;
    pending_is_status_ = true;
    return;
  }
  adc::Frame in{};
  for (std::size_t i = 0; i < in.size(); ++i)
    in.at(i) = tx[i];
  const std::uint16_t cmd = adc::word16(in, 0);
  const bool is_wreg = (cmd & 0xE000U) == 0x6000U;
  const std::size_t data_words = is_wreg ? (cmd & 0x7FU) + 1U : 0U;
  if ((regs_[adc::kRegMode] & adc::kModeRxCrcEn) != 0U) {
    const std::size_t at = 1 + data_words;
    const std::uint16_t expect =
        adc::crc16(std::span<const std::uint8_t>(in.data(), at * adc::kWordBytes));
    if (at >= adc::kFrameWords || adc::word16(in, at) != expect) {
      crc_err_flag_ = true;
      ++rejected_;
      pending_is_status_ = true;  // executed as NULL
      return;
    }
  }
  pending_is_status_ = false;
  const auto address = static_cast<std::uint8_t>((cmd >> 7U) & 0x3FU);
  if (cmd == adc::kNull) {
    pending_is_status_ = true;
  } else if (cmd == adc::kReset) {
    reset_registers();
    restart_conversions();
    pending_ = adc::kResetAnswer;
  } else if (cmd == adc::kStandby) {
    standby_ = true;
    pending_ = cmd;
  } else if (cmd == adc::kWakeup) {
    standby_ = false;
    pending_ = cmd;
  } else if ((cmd & 0xE000U) == 0xA000U) {
    if ((cmd & 0x7FU) != 0U) {
      ++rejected_;  // multi-register reads are not emulated
      pending_is_status_ = true;
      return;
    }
    std::uint16_t v = address == adc::kRegStatus ? status() : regs_.at(address);
    if (address == corrupt_address_) v ^= corrupt_xor_;
    pending_ = v;
  } else if (is_wreg) {
    if (data_words != 1 || address <= adc::kRegStatus) {
      ++rejected_;
      pending_is_status_ = true;
      return;
    }
    const std::uint16_t v = adc::word16(in, 1);
    regs_.at(address) = v;
    if (address == adc::kRegMode && (v & adc::kModeReset) == 0U) reset_flag_ = false;
    if (address == adc::kRegClock) restart_conversions();  // the filter starts over
    pending_ = adc::wreg_answer(address);
  } else {
    ++rejected_;
    pending_is_status_ = true;
  }
}

int Ads131m04Emulator::DrdyLine::read() noexcept {
  adc_->convert_until(adc_->clock_->now_ns());
  return adc_->new_data_ ? 0 : 1;
}

drivers::spi::EdgeWait Ads131m04Emulator::DrdyLine::wait_edge(std::int64_t timeout_ns,
                                                              drivers::spi::Edge* edge) noexcept {
  Ads131m04Emulator& a = *adc_;
  if (a.dead_) return drivers::spi::EdgeWait::kError;
  const std::int64_t now = a.clock_->now_ns();
  a.convert_until(now);
  // Edges since the first wait are queued (as the kernel queues line events) and come out
  // oldest first: the one after the last taken, on the conversion grid.
  const std::int64_t p = a.period_ns();
  if (a.last_edge_taken_ns_ < 0) a.last_edge_taken_ns_ = a.next_conversion_ns_ - p;
  std::int64_t t = a.last_edge_taken_ns_ + p;
  if (t > a.next_conversion_ns_) t = a.next_conversion_ns_;  // the grid moved (CLOCK written)
  if (t > now) {
    if (t > now + timeout_ns) {
      a.clock_->advance_ns(timeout_ns);
      return drivers::spi::EdgeWait::kTimeout;
    }
    a.clock_->sleep_until_ns(t);
    a.convert_until(a.clock_->now_ns());
  }
  a.last_edge_taken_ns_ = t;
  if (edge != nullptr) *edge = {false, t};
  return drivers::spi::EdgeWait::kEdge;
}

}  // namespace selfsense::test
