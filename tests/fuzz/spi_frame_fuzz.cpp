// Fuzz target: the ADS131M04's output frames (include/selfsense/drivers/spi/ads131m04.hpp), the
// bytes the ADC clocks out on DOUT, through the frame codec and through the SPI driver's read path
// (include/selfsense/drivers/spi/spi_driver.hpp).
// Input: one set-up byte, then frames of kFrameBytes (18) bytes, each the ADC's reply to one
// transfer; a last partial frame is ignored. The set-up byte: bits 0-1 the front end (the
// emulated bench's; other channels, PGA gain 2; offsets; narrow ranges), bits 2-3 stuck_frames
// {50, 1, 3, 0}, bits 4-5 faults.stale_frames {2, 0, 1, 5}, bit 6 input CRC off, bit 7: a
// re-initialisation the driver asks for reads its answers from the input too (else from the
// emulator).
// Properties of the codec, for every frame:
//  - crc16() is the data sheet's CRC (0x1021, init 0xFFFF, MSB first), computed here bit by bit
//    (and checked on "123456789": 0x29B1); it continues across a split;
//  - decode_reply(): crc_ok exactly when the 24-bit CRC word is that CRC over the 15 bytes before
//    it, padded with 0; the response and CRC are the words' top 16 bits; every code lies inside
//    [kCodeMin, kCodeMax] and is its word's 24-bit two's complement;
//  - put_code(code()) writes the same 3 bytes; put_word16(word16()) the same 2 and a 0 pad;
//    code_of(volts(code, gain), gain) == code for every gain;
//  - encode_command() of the frame's first words closes the host frame with its CRC.
// Properties of SpiDriver::read() on the frames (driver activated against the ADS131M04 and
// DAC8563 emulators, then the ADC bus switched to hand out the input; no threads, simulated
// clock), for every read:
//  - reads grows by one; a read while the ADC is being re-initialised is kDisconnected and
//    touches no bus; otherwise it takes exactly one frame;
//  - kOk only for a frame whose CRC is right, without STATUS.RESET, with codes not at full
//    scale, giving E and D finite, inside range_v_per_m / range_c_per_m2, equal to the front
//    end's scaling of the frame's codes, and device_status the frame's STATUS; no fault counter
//    moves;
//  - a frame with a wrong CRC is kBadData with E and D NaN, crc_errors and bad_data + 1;
//  - kBadData: bad_data + 1 and exactly one of crc_errors, clipped, out_of_range + 1;
//    kStale: stale + 1 (stuck + 1 or a missing conversion); kDeviceFault: adc_resets and
//    device_faults + 1 (the frame's STATUS.RESET); the counters of other causes stay;
//  - E and D codes the same as the previous frame's (since the last (re-)initialisation; the
//    first frame has none) for stuck_frames frames in a row count stuck (kStale), never kOk,
//    and nothing else counts stuck;
//  - crc_errors_to_reinit bad CRCs in a row or a reset ask for a re-initialisation, nothing
//    else; each attempt counts one of reinits and reinit_failures; through the emulator it
//    succeeds.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "fuzz_check.hpp"
#include "selfsense/drivers/spi/ads131m04.hpp"
#include "selfsense/drivers/spi/spi_bus.hpp"
#include "selfsense/drivers/spi/spi_config.hpp"
#include "selfsense/drivers/spi/spi_driver.hpp"
#include "selfsense/runtime/driver.hpp"
#include "selfsense/runtime/pacer.hpp"
#include "support/spi/ads131m04_emulator.hpp"
#include "support/spi/dac8563_emulator.hpp"
#include "support/spi/emulated_line.hpp"
#include "support/spi/spi_bench.hpp"

namespace {

namespace spi = selfsense::drivers::spi;
namespace adc = selfsense::drivers::spi::ads131m04;
namespace rt = selfsense::runtime;
using selfsense::fuzz::require;

constexpr double kRate = 10000.0;
constexpr std::int64_t kPeriodNs = 100'000;
constexpr std::size_t kMaxFrames = 256;
constexpr std::size_t kCrcBytes = (adc::kFrameWords - 1) * adc::kWordBytes;
constexpr std::array<int, 4> kStuckFrames{50, 1, 3, 0};
constexpr std::array<int, 4> kStaleFrames{2, 0, 1, 5};

// The data sheet's CRC, bit by bit, independent of adc::crc16.
std::uint16_t reference_crc(std::span<const std::uint8_t> bytes) {
  unsigned crc = 0xFFFF;
  for (const std::uint8_t b : bytes) {
    for (unsigned bit = 8; bit-- > 0;) {
      // The next message bit against the register's top bit: the polynomial is subtracted
      // (XORed) when they differ.
      const bool in = ((static_cast<unsigned>(b) >> bit) & 1U) != 0U;
      const bool top = (crc & 0x8000U) != 0U;
      crc = (crc << 1U) & 0xFFFFU;
      if (in != top) crc ^= 0x1021U;
    }
  }
  return static_cast<std::uint16_t>(crc);
}

std::string hex(std::span<const std::uint8_t> bytes) {
  constexpr std::string_view kDigits = "0123456789abcdef";
  std::string s;
  for (const std::uint8_t b : bytes) {
    s += kDigits[b >> 4U];
    s += kDigits[b & 15U];
  }
  return s;
}

// The frame's CRC is right (the 24-bit CRC word is the CRC of the bytes before it, 0-padded).
bool crc_right(const adc::Frame& f) {
  const std::uint16_t crc = reference_crc(std::span<const std::uint8_t>(f.data(), kCrcBytes));
  return f[kCrcBytes] == (crc >> 8U) && f[kCrcBytes + 1] == (crc & 0xFFU) && f[kCrcBytes + 2] == 0;
}

void check_codec(const adc::Frame& f) {
  const std::string what = hex(f);
  const std::span<const std::uint8_t> body(f.data(), kCrcBytes);
  const std::uint16_t crc = reference_crc(body);
  require(adc::crc16(body) == crc, "crc16 is the data sheet's CRC", what);
  require(adc::crc16(body.subspan(7), adc::crc16(body.first(7))) == crc,
          "crc16 continues across a split", what);

  const adc::Reply r = adc::decode_reply(f);
  require(r.crc_ok == crc_right(f), "crc_ok exactly when the CRC word is the CRC, 0-padded", what);
  const auto top16 = [&f](std::size_t at) {
    return (static_cast<unsigned>(f.at(at)) << 8U) | f.at(at + 1);
  };
  require(r.response == top16(0), "the response is word 0's top 16 bits", what);
  require(r.crc == top16(kCrcBytes), "the CRC is word 5's top 16 bits", what);
  for (std::size_t c = 0; c < adc::kChannels; ++c) {
    const std::size_t w = 1 + c;
    const std::size_t at = w * adc::kWordBytes;
    const auto u =
        static_cast<std::int32_t>((static_cast<std::uint32_t>(f.at(at)) << 16U) |
                                  (static_cast<std::uint32_t>(f.at(at + 1)) << 8U) | f.at(at + 2));
    const std::int32_t expected = u >= (1 << 23) ? u - (1 << 24) : u;
    const std::int32_t code = adc::code(f, w);
    require(code == expected && r.code.at(c) == code,
            "a code is its word's 24-bit two's complement", what);
    require(code >= adc::kCodeMin && code <= adc::kCodeMax, "a code is inside the ADC's scale",
            what);
    adc::Frame g{};
    adc::put_code(g, w, code);
    require(std::equal(g.begin() + static_cast<std::ptrdiff_t>(at),
                       g.begin() + static_cast<std::ptrdiff_t>(at + 3),
                       f.begin() + static_cast<std::ptrdiff_t>(at)),
            "put_code(code()) writes the same bytes", what);
    for (int gain = 1; gain <= 128; gain *= 2) {
      require(adc::code_of(adc::volts(code, gain), gain) == code,
              "code_of(volts(code)) is the code", what + " gain " + std::to_string(gain));
    }
  }
  for (std::size_t w = 0; w < adc::kFrameWords; ++w) {
    const std::size_t at = w * adc::kWordBytes;
    adc::Frame g{};
    g.fill(0xA5);
    adc::put_word16(g, w, adc::word16(f, w));
    require(g.at(at) == f.at(at) && g.at(at + 1) == f.at(at + 1) && g.at(at + 2) == 0,
            "put_word16(word16()) writes the same bytes and a 0 pad", what);
  }
  // A host frame of the first two words (a command and one data word).
  adc::Frame tx{};
  const std::array<std::uint16_t, 1> data{adc::word16(f, 1)};
  const std::uint16_t written = adc::encode_command(tx, adc::word16(f, 0), data);
  require(written == reference_crc(std::span<const std::uint8_t>(tx.data(), 6)) &&
              adc::word16(tx, 2) == written && adc::word16(tx, 0) == adc::word16(f, 0) &&
              adc::word16(tx, 1) == data[0] &&
              std::all_of(tx.begin() + 9, tx.end(), [](std::uint8_t b) { return b == 0; }),
          "encode_command closes the host frame with its CRC", what);
}

// The front ends (each accepted by SpiConfig::problems()).
spi::SpiConfig front_end(unsigned which) {
  spi::SpiConfig c = selfsense::test::emulated_spi_config(kRate);
  c.faults.reinit_backoff_s = {1e-4, 4e-4};  // a few periods: re-initialisations stay cheap
  if (which == 1) {                          // other channels, PGA gain 2 on both
    c.e.channel = 2;
    c.d.channel = 3;
    c.e.pga_gain = 2;
    c.d.pga_gain = 2;
    c.e.divider = 250.0;
    c.d.feedback_capacitance_f = 660e-6;
  } else if (which == 2) {  // offsets, a non-inverting charge amplifier
    c.e.channel = 3;
    c.d.channel = 0;
    c.e.offset_v = 0.02;
    c.d.offset_v = -0.05;
    c.d.inverting = false;
  } else if (which == 3) {  // narrow ranges: most codes are out of range
    c.e.range_v_per_m = {0.0, 1e5};
    c.d.range_c_per_m2 = {-1e-3, 1e-3};
  }
  return c;
}

// The ADC's bus: the emulator until feed(), then the input's frames (a failed transfer once
// they run out).
class SwitchedBus final : public spi::SpiBus {
 public:
  explicit SwitchedBus(spi::SpiBus& emulator) : emulator_(&emulator) {}
  void feed(std::span<const std::uint8_t> frames) noexcept {
    frames_ = frames;
    fuzzing_ = true;
  }
  void use_emulator(bool on) noexcept { fuzzing_ = !on; }
  [[nodiscard]] std::span<const std::uint8_t> left() const noexcept { return frames_; }
  [[nodiscard]] long transfers() const noexcept { return transfers_; }

  bool transfer(std::span<const std::uint8_t> tx, std::span<std::uint8_t> rx) noexcept override {
    ++transfers_;
    if (!fuzzing_) return emulator_->transfer(tx, rx);
    if (tx.size() != rx.size() || frames_.size() < rx.size()) return false;
    std::copy_n(frames_.begin(), rx.size(), rx.begin());
    frames_ = frames_.subspan(rx.size());
    return true;
  }

 private:
  spi::SpiBus* emulator_;
  std::span<const std::uint8_t> frames_{};
  bool fuzzing_{false};
  long transfers_{0};
};

struct Counts {
  rt::DriverCounters d;
  spi::SpiCounters s;
};

Counts counts(const spi::SpiDriver& driver) {
  return {driver.counters(), driver.spi_counters()};
}

// One re-initialisation attempt: exactly one of reinits and reinit_failures counts it.
void reinitialise(spi::SpiDriver& driver, selfsense::runtime::SimulatedClock& clock,
                  SwitchedBus& bus, bool from_input) {
  bus.use_emulator(!from_input);
  const Counts before = counts(driver);
  driver.service(0);
  const Counts after = counts(driver);
  const std::uint64_t ok = after.s.reinits - before.s.reinits;
  const std::uint64_t failed = after.s.reinit_failures - before.s.reinit_failures;
  require(ok + failed == 1, "a due re-initialisation counts one attempt");
  require((ok == 1) == (driver.adc_state() == spi::AdcState::kRunning),
          "a counted success hands the bus back");
  require(after.d.reconnects == after.s.reinits && after.d.retries == after.s.reinit_failures,
          "reconnects and retries are reinits and reinit_failures");
  if (ok == 0) {
    // Back to the emulator once the back-off has passed: the ADC comes back.
    bus.use_emulator(true);
    clock.advance_ns(1'000'000);
    driver.service(0);
    require(driver.adc_state() == spi::AdcState::kRunning,
            "a re-initialisation against the emulator succeeds");
  }
  bus.use_emulator(false);
}

// The stuck-converter rule on the frames read: E and D codes the same as the previous frame's
// (of those since the last (re-)initialisation that reached the comparison: right CRC, no
// STATUS.RESET) for stuck_frames frames in a row.
class StuckModel final {
 public:
  explicit StuckModel(int stuck_frames) : stuck_frames_(stuck_frames) {}
  // After a frame that reached the comparison; true when its codes count as stuck.
  bool next(std::int32_t e_code, std::int32_t d_code) {
    run_ = have_ && e_code == e_ && d_code == d_ ? run_ + 1 : 0;
    have_ = true;
    e_ = e_code;
    d_ = d_code;
    return stuck_frames_ > 0 && run_ >= stuck_frames_;
  }
  void restart() {
    have_ = false;
    run_ = 0;
  }

 private:
  int stuck_frames_;
  bool have_{false};
  int run_{0};
  std::int32_t e_{0};
  std::int32_t d_{0};
};

void check_read(const spi::SpiConfig& config, const adc::Frame& f, rt::DriverStatus status,
                const rt::InputSample& in, const Counts& b, const Counts& a, StuckModel& model) {
  const std::string what = hex(f) + " status " + std::to_string(static_cast<int>(status));
  const auto moved = [](std::uint64_t before, std::uint64_t after) { return after - before; };
  const std::uint64_t bad = moved(b.d.bad_data, a.d.bad_data);
  const std::uint64_t stale = moved(b.d.stale, a.d.stale);
  const std::uint64_t crc = moved(b.s.crc_errors, a.s.crc_errors);
  const std::uint64_t clipped = moved(b.s.clipped, a.s.clipped);
  const std::uint64_t range = moved(b.s.out_of_range, a.s.out_of_range);
  const std::uint64_t stuck = moved(b.s.stuck, a.s.stuck);
  const std::uint64_t resets = moved(b.s.adc_resets, a.s.adc_resets);
  const std::uint64_t device = moved(b.d.device_faults, a.d.device_faults);
  require(moved(b.d.reads, a.d.reads) == 1, "every read counts", what);
  require(moved(b.d.crc_errors, a.d.crc_errors) ==
              crc + moved(b.s.input_crc_errors, a.s.input_crc_errors),
          "crc_errors counts both directions", what);
  require(device == resets + moved(b.s.amp_faults, a.s.amp_faults),
          "device_faults are resets and amplifier faults", what);

  if (!crc_right(f)) {
    require(status == rt::DriverStatus::kBadData, "a wrong CRC is bad data", what);
    require(std::isnan(in.e) && std::isnan(in.d), "a wrong CRC gives no number", what);
    require(crc == 1, "a wrong CRC counts a CRC error", what);
  }
  const auto ce = static_cast<std::size_t>(config.e.channel);
  const auto cd = static_cast<std::size_t>(config.d.channel);
  const std::int32_t e_code = adc::code(f, 1 + ce);
  const std::int32_t d_code = adc::code(f, 1 + cd);
  const unsigned drdy = (1U << ce) | (1U << cd);
  const bool compared = crc_right(f) && (adc::word16(f, 0) & adc::kStatusReset) == 0U;
  const bool stuck_codes = compared && model.next(e_code, d_code);
  if (compared && status != rt::DriverStatus::kBadData) {
    require(stuck_codes == (stuck == 1),
            "stuck counts exactly codes unchanged for stuck_frames frames after the first", what);
  }
  switch (status) {
    case rt::DriverStatus::kOk: {
      require(crc_right(f), "kOk only with the right CRC", what);
      require((adc::word16(f, 0) & adc::kStatusReset) == 0U, "kOk never with STATUS.RESET", what);
      require(in.device_status == adc::word16(f, 0), "device_status is the frame's STATUS", what);
      require(std::isfinite(in.e) && std::isfinite(in.d), "kOk is finite", what);
      require(in.e >= config.e.range_v_per_m[0] && in.e <= config.e.range_v_per_m[1],
              "kOk E is inside range_v_per_m", what);
      require(in.d >= config.d.range_c_per_m2[0] && in.d <= config.d.range_c_per_m2[1],
              "kOk D is inside range_c_per_m2", what);
      require(e_code > adc::kCodeMin && e_code < adc::kCodeMax && d_code > adc::kCodeMin &&
                  d_code < adc::kCodeMax,
              "kOk never at full scale", what);
      require(in.e == config.field_of(adc::volts(e_code, config.e.pga_gain)) &&
                  in.d == config.displacement_of(adc::volts(d_code, config.d.pga_gain)),
              "kOk is the frame's number", what);
      require(bad + stale + crc + clipped + range + stuck + resets + device == 0,
              "kOk moves no fault counter", what);
      break;
    }
    case rt::DriverStatus::kBadData:
      require(bad == 1 && crc + clipped + range == 1 && stale + stuck + resets == 0,
              "bad data counts bad_data and exactly one cause", what);
      break;
    case rt::DriverStatus::kStale:
      require(stale == 1 && bad + crc + clipped + range + resets == 0 && stuck <= 1,
              "stale counts stale", what);
      require(stuck == 1 || (adc::word16(f, 0) & drdy) != drdy,
              "stale is stuck codes or a missing conversion (STATUS.DRDY)", what);
      break;
    case rt::DriverStatus::kDeviceFault:
      require(resets == 1 && device == 1 && bad + stale + crc + clipped + range + stuck == 0,
              "a device fault from the frame counts an ADC reset", what);
      require((adc::word16(f, 0) & adc::kStatusReset) != 0U, "a device fault is STATUS.RESET",
              what);
      break;
    default:
      require(false, "a read of a frame is ok, bad data, stale or a device fault", what);
  }
}

}  // namespace

// NOLINTNEXTLINE(readability-identifier-naming): the name libFuzzer calls.
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const bool check_value = [] {
    constexpr std::array<std::uint8_t, 9> kNine{'1', '2', '3', '4', '5', '6', '7', '8', '9'};
    require(reference_crc(kNine) == 0x29B1 && adc::crc16(kNine) == 0x29B1,
            "CRC-16/CCITT-FALSE of 123456789 is 0x29B1");
    return true;
  }();
  static_cast<void>(check_value);
  const std::span<const std::uint8_t> input(data, size);
  if (input.empty()) return 0;
  const std::uint8_t setup = input.front();
  const std::span<const std::uint8_t> bytes = input.subspan(1);
  const std::size_t frames = std::min(bytes.size() / adc::kFrameBytes, kMaxFrames);
  const auto frame_at = [&](std::span<const std::uint8_t> from) {
    adc::Frame f{};
    std::copy_n(from.begin(), f.size(), f.begin());
    return f;
  };
  for (std::size_t i = 0; i < frames; ++i)
    check_codec(frame_at(bytes.subspan(i * adc::kFrameBytes)));

  spi::SpiConfig config = front_end(setup & 3U);
  config.faults.stuck_frames = kStuckFrames.at((setup >> 2U) & 3U);
  config.faults.stale_frames = kStaleFrames.at((setup >> 4U) & 3U);
  config.adc.input_crc = (setup & 0x40U) == 0;
  const bool reinit_from_input = (setup & 0x80U) != 0;

  selfsense::runtime::SimulatedClock clock;
  selfsense::test::Ads131m04Emulator emulator(clock, config.adc.clkin_hz,
                                              [](std::int64_t /*t_ns*/) {
                                                return std::array<double, 4>{0.3, -0.2, 0.01, -0.4};
                                              });
  selfsense::test::Dac8563Emulator dac(config.dac.full_scale_v);
  selfsense::test::EmulatedLine enable{false};
  selfsense::test::EmulatedLine fault{true};  // active low: no fault
  SwitchedBus bus(emulator);
  spi::SpiDriver driver(config, {&bus, &dac, &emulator.drdy_line(), &enable, &fault, &clock},
                        false);
  std::string why;
  require(driver.configure({1.0 / kRate}, &why) && driver.activate(&why),
          "the driver activates against the emulators (harness)", why);

  bus.feed(bytes.first(frames * adc::kFrameBytes));
  rt::InputSample in{};
  int crc_run = 0;  // bad CRCs in a row
  StuckModel stuck(config.faults.stuck_frames);
  while (bus.left().size() >= adc::kFrameBytes) {
    clock.advance_ns(kPeriodNs);
    const adc::Frame f = frame_at(bus.left());
    const Counts before = counts(driver);
    const std::size_t left = bus.left().size();
    const rt::DriverStatus status = driver.read(in);
    require(bus.left().size() == left - adc::kFrameBytes, "a read takes one frame", hex(f));
    check_read(driver.config(), f, status, in, before, counts(driver), stuck);
    crc_run = crc_right(f) ? 0 : crc_run + 1;
    const bool reset = crc_right(f) && (adc::word16(f, 0) & adc::kStatusReset) != 0U;
    require((driver.adc_state() != spi::AdcState::kRunning) ==
                (reset || crc_run >= config.faults.crc_errors_to_reinit),
            "a reset or crc_errors_to_reinit bad CRCs in a row ask for a re-initialisation",
            hex(f));
    if (driver.adc_state() == spi::AdcState::kRunning) continue;
    crc_run = 0;
    stuck.restart();
    // Meanwhile the loop's reads leave the bus alone.
    const long transfers = bus.transfers();
    const Counts held = counts(driver);
    require(driver.read(in) == rt::DriverStatus::kDisconnected && bus.transfers() == transfers,
            "a read during a re-initialisation is disconnected and touches no bus");
    require(counts(driver).d.reads == held.d.reads + 1, "every read counts");
    reinitialise(driver, clock, bus, reinit_from_input);
  }
  driver.deactivate();
  return 0;
}
