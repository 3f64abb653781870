#include "selfsense/drivers/spi/spi_driver.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

namespace selfsense::drivers::spi {
namespace {

namespace adc = ads131m04;

void bump(std::atomic<std::uint64_t>& c) noexcept {
  c.fetch_add(1, std::memory_order_relaxed);
}

std::string hex4(std::uint16_t v) {
  std::array<char, 8> b{};
  static_cast<void>(std::snprintf(b.data(), b.size(), "0x%04X", v));
  return b.data();
}

std::uint8_t gain_code(int gain) noexcept {
  std::uint8_t c = 0;
  while ((1 << c) < gain && c < 7)
    ++c;
  return c;
}

constexpr const char* kConsumer = "selfsensed";
constexpr std::int64_t kServiceWaitNs = 10'000'000;  // how soon the thread sees a stop request

}  // namespace

SpiDriver::SpiDriver(SpiConfig config) : config_(std::move(config)) {
  own_adc_ = std::make_unique<SpidevBus>(
      SpidevSettings{config_.adc.device, config_.adc.speed_hz, 1});  // ADS131M04: mode 1
  own_dac_ = std::make_unique<SpidevBus>(
      SpidevSettings{config_.dac.device, config_.dac.speed_hz, 1});  // DAC8563: mode 1
  hw_.adc = own_adc_.get();
  hw_.dac = own_dac_.get();
  const auto line = [this](const LineConfig& l, LineUse use, bool initial) {
    return l.line < 0 ? nullptr
                      : std::make_unique<GpiodLine>(GpiodSettings{
                            config_.gpio.chip, static_cast<unsigned>(l.line), use, initial});
  };
  own_drdy_ = line(config_.gpio.drdy, LineUse::kFallingEdges, false);
  // The enable line starts inactive: the amplifier is enabled after the DAC holds its safe code.
  own_enable_ = line(config_.gpio.enable, LineUse::kOutput, config_.gpio.enable.active_low);
  own_fault_ = line(config_.gpio.fault, LineUse::kBothEdges, false);
  hw_.drdy = own_drdy_.get();
  hw_.enable = own_enable_.get();
  hw_.fault = own_fault_.get();
  hw_.clock = &steady_;
}

SpiDriver::SpiDriver(SpiConfig config, SpiHardware hardware, bool maintenance_thread)
    : config_(std::move(config)), hw_(hardware), maintenance_thread_(maintenance_thread) {
  if (hw_.clock == nullptr) hw_.clock = &steady_;
}

SpiDriver::~SpiDriver() {
  deactivate();
}

bool SpiDriver::configure(const runtime::DriverSetup& setup, std::string* why) {
  const auto fail = [why](std::string m) {
    if (why != nullptr) *why = std::move(m);
    return false;
  };
  if (!(setup.sample_time > 0.0)) return fail("spi: the loop's sample time must be > 0");
  const std::vector<std::string> problems = config_.problems(1.0 / setup.sample_time);
  if (!problems.empty()) return fail("driver." + problems.front());
  if (hw_.adc == nullptr || hw_.dac == nullptr) return fail("spi: no ADC or DAC bus");
  if (config_.pace == Pace::kDrdy && hw_.drdy == nullptr) {
    return fail("driver.gpio.drdy: pace drdy needs the data-ready line");
  }
  period_ns_ = std::llround(setup.sample_time * 1e9);
  // The NULL frame of every read(), with its input CRC (checked by the ADC with input_crc).
  adc::encode_command(null_tx_, adc::kNull);
  configured_ = true;
  return true;
}

bool SpiDriver::exchange(std::uint16_t command, std::uint16_t data, bool with_data,
                         std::uint16_t* answer, std::string* why) noexcept {
  adc::Frame tx{};
  const std::array<std::uint16_t, 1> words{data};
  adc::encode_command(
      tx, command,
      with_data ? std::span<const std::uint16_t>(words) : std::span<const std::uint16_t>{});
  adc::Frame rx{};
  adc::Frame rx2{};
  if (!hw_.adc->transfer(tx, rx) || !hw_.adc->transfer(null_tx_, rx2)) {
    if (why != nullptr) *why = "adc: the SPI transfer failed (command " + hex4(command) + ")";
    return false;
  }
  const adc::Reply r = adc::decode_reply(rx2);
  if (!r.crc_ok) {
    if (why != nullptr) *why = "adc: CRC error in the answer to command " + hex4(command);
    bump(n_.crc_errors);
    return false;
  }
  *answer = r.response;
  return true;
}

bool SpiDriver::initialise_adc(std::string* why) noexcept {
  const auto fail = [why](const std::string& m) {
    if (why != nullptr && why->empty()) *why = m;
    return false;
  };
  std::uint16_t answer = 0;
  // RESET: answered FF24h; the device needs t_REGACQ (5 us) before the next command.
  if (!exchange(adc::kReset, 0, false, &answer, why)) return false;
  if (answer != adc::kResetAnswer) {
    return fail("adc: RESET answered " + hex4(answer) + ", not " + hex4(adc::kResetAnswer) +
                " (no ADS131M04 on " + config_.adc.device + "? check wiring, SPI mode 1)");
  }
  hw_.clock->sleep_until_ns(hw_.clock->now_ns() + 10'000);
  if (!exchange(adc::rreg(adc::kRegId), 0, false, &answer, why)) return false;
  if ((answer & 0xFF00U) != adc::kIdValue) {
    return fail("adc: ID register reads " + hex4(answer) + ", not an ADS131M04 (0x24xx)");
  }
  std::array<std::uint8_t, 4> gains{};
  gains.at(static_cast<std::size_t>(config_.e.channel)) = gain_code(config_.e.pga_gain);
  gains.at(static_cast<std::size_t>(config_.d.channel)) = gain_code(config_.d.pga_gain);
  if (config_.temp.wired) {
    gains.at(static_cast<std::size_t>(config_.temp.channel)) = gain_code(config_.temp.pga_gain);
  }
  // MODE: 24-bit words, SPI timeout on, STATUS.RESET cleared (written 0), DRDY on the most
  // lagging channel as a level, input CRC as configured.
  const std::uint16_t mode = static_cast<std::uint16_t>(
      adc::kModeWord24 | adc::kModeTimeout | (config_.adc.input_crc ? adc::kModeRxCrcEn : 0U));
  const std::array<std::pair<std::uint8_t, std::uint16_t>, 3> regs{
      {{adc::kRegMode, mode},
       {adc::kRegClock,
        adc::clock_register(config_.adc.osr_code(), static_cast<std::uint8_t>(config_.adc.power))},
       {adc::kRegGain, adc::gain_register(gains)}}};
  for (const auto& [address, value] : regs) {
    if (!exchange(adc::wreg(address), value, true, &answer, why)) return false;
    if (answer != adc::wreg_answer(address)) {
      return fail("adc: WREG of register " + hex4(address) + " answered " + hex4(answer) +
                  ", not " + hex4(adc::wreg_answer(address)));
    }
  }
  for (const auto& [address, value] : regs) {
    if (!exchange(adc::rreg(address), 0, false, &answer, why)) return false;
    if (answer != value) {
      return fail("adc: register " + hex4(address) + " reads back " + hex4(answer) +
                  " after writing " + hex4(value) + " (read-back verification)");
    }
  }
  // STATUS (the answer to NULL) must show the reset acknowledged.
  if (!exchange(adc::kNull, 0, false, &answer, why)) return false;
  if ((answer & adc::kStatusReset) != 0U) {
    return fail("adc: STATUS " + hex4(answer) + " still shows RESET after MODE was written");
  }
  crc_run_ = 0;
  transfer_run_ = 0;
  no_data_run_ = 0;
  stuck_run_ = 0;
  have_codes_ = false;
  return true;
}

bool SpiDriver::set_enable(bool on) const noexcept {
  if (hw_.enable == nullptr) return true;
  return hw_.enable->write(on != config_.gpio.enable.active_low);
}

bool SpiDriver::write_dac(double field) noexcept {
  if (!std::isfinite(field)) field = 0.0;
  const dac8563::Code c = dac8563::code_of(config_.dac_volts_of(field), config_.dac.full_scale_v);
  if (c.clipped) bump(n_.command_clipped);
  const dac8563::Frame tx =
      dac8563::frame(dac8563::Command::kWriteUpdate, config_.dac.output, c.code);
  dac8563::Frame rx{};
  return hw_.dac->transfer(tx, rx);
}

bool SpiDriver::activate(std::string* why) {
  const auto fail = [this, why](const std::string& m) {
    if (why != nullptr) *why = m;
    if (own_adc_) own_adc_->close();
    if (own_dac_) own_dac_->close();
    for (GpiodLine* l : {own_drdy_.get(), own_enable_.get(), own_fault_.get()})
      if (l != nullptr) l->close();
    return false;
  };
  if (!configured_) return fail("spi: activate() before configure()");
  if (active_) return true;
  if (why != nullptr) why->clear();
  std::string e;
  if (own_adc_ && !own_adc_->open(&e)) return fail("driver.adc.device: " + e);
  if (own_dac_ && !own_dac_->open(&e)) return fail("driver.dac.device: " + e);
  const std::array<std::pair<GpiodLine*, const char*>, 3> lines{
      {{own_drdy_.get(), "drdy"}, {own_enable_.get(), "enable"}, {own_fault_.get(), "fault"}}};
  for (const auto& [l, key] : lines) {
    if (l != nullptr && !l->open(kConsumer, &e)) {
      return fail(std::string("driver.gpio.") + key + ": " + e);
    }
  }
  // The DAC first, at the safe output, with the amplifier still disabled.
  static_cast<void>(set_enable(false));
  for (const dac8563::Frame& f : dac8563::startup(config_.dac.internal_reference)) {
    dac8563::Frame rx{};
    if (!hw_.dac->transfer(f, rx)) return fail("driver.dac.device: the SPI transfer failed");
  }
  if (!write_dac(0.0)) return fail("driver.dac.device: the SPI transfer failed");
  if (!initialise_adc(&e)) return fail("driver.adc: " + e);
  amp_fault_.store(hw_.fault != nullptr && fault_active(hw_.fault->read()),
                   std::memory_order_relaxed);
  if (!set_enable(true)) return fail("driver.gpio.enable: the line could not be set");
  state_.store(AdcState::kRunning, std::memory_order_release);
  backoff_ns_ = std::llround(config_.faults.reinit_backoff_s[0] * 1e9);
  next_attempt_ns_ = 0;
  read_ns_ = hw_.clock->now_ns();
  read_to_write_.reset();
  stop_.store(false);
  active_ = true;
  if (maintenance_thread_) thread_ = std::thread([this] { maintenance_loop(); });
  return true;
}

void SpiDriver::deactivate() noexcept {
  if (!active_) return;
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
  // The safe output, then the amplifier off.
  if (write_dac(0.0)) bump(n_.writes);
  static_cast<void>(set_enable(false));
  if (own_adc_) own_adc_->close();
  if (own_dac_) own_dac_->close();
  for (GpiodLine* l : {own_drdy_.get(), own_enable_.get(), own_fault_.get()})
    if (l != nullptr) l->close();
  active_ = false;
}

void SpiDriver::request_reinit() noexcept {
  state_.store(AdcState::kReinitRequested, std::memory_order_release);
}

runtime::DriverStatus SpiDriver::read(runtime::InputSample& out) noexcept {
  if (!active_) return runtime::DriverStatus::kNotActive;
  bump(n_.reads);
  const std::int64_t now = hw_.clock->now_ns();
  read_ns_ = now;
  out = runtime::InputSample{};
  out.timestamp_ns = now;
  // The maintenance thread owns the ADC bus until it has re-initialised the ADC.
  if (state_.load(std::memory_order_acquire) != AdcState::kRunning) {
    return runtime::DriverStatus::kDisconnected;
  }
  if (!hw_.adc->transfer(null_tx_, rx_)) {
    bump(n_.errors);
    if (++transfer_run_ >= config_.faults.transfer_errors_to_reinit) request_reinit();
    return runtime::DriverStatus::kDisconnected;
  }
  transfer_run_ = 0;
  const adc::Reply r = adc::decode_reply(rx_);
  if (!r.crc_ok) {
    bump(n_.crc_errors);
    bump(n_.bad_data);
    if (++crc_run_ >= config_.faults.crc_errors_to_reinit) request_reinit();
    return runtime::DriverStatus::kBadData;
  }
  crc_run_ = 0;
  const std::uint16_t status = r.response;
  out.device_status = status;
  if ((status & adc::kStatusReset) != 0U) {
    // The ADC was reset behind our back (supply dip, SYNC/RESET pin): its registers are lost.
    bump(n_.adc_resets);
    request_reinit();
    return runtime::DriverStatus::kDeviceFault;
  }
  if ((status & adc::kStatusCrcErr) != 0U) {
    bump(n_.input_crc_errors);  // the ADC saw our last frame corrupted; its data is still good
    bump(n_.errors);
  }
  const auto ce = static_cast<std::size_t>(config_.e.channel);
  const auto cd = static_cast<std::size_t>(config_.d.channel);
  const std::int32_t e_code = r.code.at(ce);
  const std::int32_t d_code = r.code.at(cd);
  out.e = config_.field_of(adc::volts(e_code, config_.e.pga_gain));
  out.d = config_.displacement_of(adc::volts(d_code, config_.d.pga_gain));
  if (config_.temp.wired) {
    // Slow and auxiliary: a bad reading is no temperature this cycle (counted), not a fault.
    const std::int32_t code = r.code.at(static_cast<std::size_t>(config_.temp.channel));
    const double theta = config_.temperature_of(adc::volts(code, config_.temp.pga_gain));
    if (code < adc::kCodeMax && code > adc::kCodeMin && std::isfinite(theta) &&
        theta >= config_.temp.range_degc[0] && theta <= config_.temp.range_degc[1]) {
      out.temp_ref = theta;
    } else {
      bump(n_.temp_out_of_range);
    }
  }
  const std::uint16_t drdy = static_cast<std::uint16_t>((1U << ce) | (1U << cd));
  if ((status & drdy) != drdy) {
    bump(n_.no_new_data);
    ++no_data_run_;
  } else {
    no_data_run_ = 0;
  }
  // Unchanged from the previous frame of this (re-)initialisation: the first has none.
  if (have_codes_ && e_code == last_e_code_ && d_code == last_d_code_) {
    ++stuck_run_;
  } else {
    stuck_run_ = 0;
  }
  have_codes_ = true;
  last_e_code_ = e_code;
  last_d_code_ = d_code;
  const auto clipped = [](std::int32_t c) { return c >= adc::kCodeMax || c <= adc::kCodeMin; };
  if (clipped(e_code) || clipped(d_code)) {
    bump(n_.clipped);
    bump(n_.bad_data);
    return runtime::DriverStatus::kBadData;
  }
  const auto inside = [](double v, const std::array<double, 2>& range) {
    return std::isfinite(v) && v >= range[0] && v <= range[1];
  };
  if (!inside(out.e, config_.e.range_v_per_m) || !inside(out.d, config_.d.range_c_per_m2)) {
    bump(n_.out_of_range);
    bump(n_.bad_data);
    return runtime::DriverStatus::kBadData;
  }
  if (amp_fault_.load(std::memory_order_relaxed)) return runtime::DriverStatus::kDeviceFault;
  if (config_.faults.stuck_frames > 0 && stuck_run_ >= config_.faults.stuck_frames) {
    bump(n_.stuck);
    bump(n_.stale);
    return runtime::DriverStatus::kStale;
  }
  if (no_data_run_ > config_.faults.stale_frames) {
    bump(n_.stale);
    return runtime::DriverStatus::kStale;
  }
  return runtime::DriverStatus::kOk;
}

runtime::DriverStatus SpiDriver::write(const runtime::OutputCommand& command) noexcept {
  if (!active_) return runtime::DriverStatus::kNotActive;
  if (!write_dac(command.e)) {
    bump(n_.errors);
    return runtime::DriverStatus::kDisconnected;
  }
  bump(n_.writes);
  read_to_write_.record(hw_.clock->now_ns() - read_ns_);
  return runtime::DriverStatus::kOk;
}

runtime::CycleTrigger::Result SpiDriver::wait(std::int64_t timeout_ns) noexcept {
  Edge edge{};
  const EdgeWait w = hw_.drdy->wait_edge(timeout_ns, &edge);
  if (w == EdgeWait::kTimeout) {
    bump(n_.timeouts);
    return Result::kTimeout;
  }
  if (w == EdgeWait::kError) {
    bump(n_.errors);
    return Result::kError;
  }
  // Edges queued while the loop was late: skip to the newest, counting the ones missed.
  while (hw_.clock->now_ns() - edge.timestamp_ns > period_ns_) {
    if (hw_.drdy->wait_edge(0, &edge) != EdgeWait::kEdge) break;
    bump(n_.drdy_missed);
  }
  fired_ns_ = edge.timestamp_ns;
  return Result::kReady;
}

void SpiDriver::service(std::int64_t wait_ns) noexcept {
  if (hw_.fault != nullptr) {
    Edge edge{};
    const EdgeWait w = hw_.fault->wait_edge(wait_ns, &edge);
    if (w == EdgeWait::kError) bump(n_.errors);
    // The level after the edge(s) decides (an edge pair may have been coalesced).
    const bool now_faulted = fault_active(hw_.fault->read());
    if (now_faulted && !amp_fault_.exchange(true)) bump(n_.amp_faults);
    if (!now_faulted) amp_fault_.store(false);
  } else if (maintenance_thread_) {
    hw_.clock->sleep_until_ns(hw_.clock->now_ns() + wait_ns);
  }
  if (state_.load(std::memory_order_acquire) == AdcState::kRunning) return;
  const std::int64_t now = hw_.clock->now_ns();
  if (now < next_attempt_ns_) return;
  std::string why;
  if (initialise_adc(&why)) {
    bump(n_.reinits);
    backoff_ns_ = std::llround(config_.faults.reinit_backoff_s[0] * 1e9);
    next_attempt_ns_ = 0;
    state_.store(AdcState::kRunning, std::memory_order_release);
    return;
  }
  bump(n_.reinit_failures);
  next_attempt_ns_ = now + backoff_ns_;
  backoff_ns_ = std::min<std::int64_t>(2 * backoff_ns_,
                                       std::llround(config_.faults.reinit_backoff_s[1] * 1e9));
  state_.store(AdcState::kReinitFailing, std::memory_order_release);
}

void SpiDriver::maintenance_loop() noexcept {
  while (!stop_.load(std::memory_order_relaxed))
    service(kServiceWaitNs);
}

runtime::DriverCounters SpiDriver::counters() const noexcept {
  const auto get = [](const std::atomic<std::uint64_t>& a) {
    return a.load(std::memory_order_relaxed);
  };
  runtime::DriverCounters c;
  c.reads = get(n_.reads);
  c.writes = get(n_.writes);
  c.errors = get(n_.errors);
  c.timeouts = get(n_.timeouts);
  c.stale = get(n_.stale);
  c.bad_data = get(n_.bad_data);
  c.retries = get(n_.reinit_failures);
  c.reconnects = get(n_.reinits);
  c.device_faults = get(n_.amp_faults) + get(n_.adc_resets);
  c.crc_errors = get(n_.crc_errors) + get(n_.input_crc_errors);
  // Every cause apart (SpiCounters), under the same names.
  const SpiCounters s = spi_counters();
  c.add_event("crc_errors", s.crc_errors);
  c.add_event("input_crc_errors", s.input_crc_errors);
  c.add_event("clipped", s.clipped);
  c.add_event("out_of_range", s.out_of_range);
  c.add_event("no_new_data", s.no_new_data);
  c.add_event("stuck", s.stuck);
  c.add_event("drdy_missed", s.drdy_missed);
  c.add_event("command_clipped", s.command_clipped);
  c.add_event("amp_faults", s.amp_faults);
  c.add_event("adc_resets", s.adc_resets);
  c.add_event("reinit_failures", s.reinit_failures);
  c.add_event("reinits", s.reinits);
  c.add_event("temp_out_of_range", s.temp_out_of_range);
  return c;
}

SpiCounters SpiDriver::spi_counters() const noexcept {
  const auto get = [](const std::atomic<std::uint64_t>& a) {
    return a.load(std::memory_order_relaxed);
  };
  SpiCounters c;
  c.crc_errors = get(n_.crc_errors);
  c.input_crc_errors = get(n_.input_crc_errors);
  c.clipped = get(n_.clipped);
  c.out_of_range = get(n_.out_of_range);
  c.no_new_data = get(n_.no_new_data);
  c.stuck = get(n_.stuck);
  c.drdy_missed = get(n_.drdy_missed);
  c.command_clipped = get(n_.command_clipped);
  c.amp_faults = get(n_.amp_faults);
  c.adc_resets = get(n_.adc_resets);
  c.reinit_failures = get(n_.reinit_failures);
  c.reinits = get(n_.reinits);
  c.temp_out_of_range = get(n_.temp_out_of_range);
  return c;
}

}  // namespace selfsense::drivers::spi
