// The SPI driver of the loop (runtime::Driver, driver.type spi; docs/drivers/spi.md): an
// ADS131M04 ADC samples E (through the HV divider) and D (through the charge amplifier), a
// DAC8563 sets the HV amplifier's input, GPIO lines carry the ADC's data-ready, the amplifier's
// enable and its fault output.
//
// Threads and the real-time path.
//   read()  one full-duplex SPI transfer of the ADC's 18-byte frame (a NULL command out, the
//           STATUS word, four conversion codes and the CRC in), decoded and checked.
//   write() one 3-byte DAC frame (write and update the output).
// Both run on the loop's real-time thread and each does one ioctl(SPI_IOC_MESSAGE): the
// deliberate exception to "no I/O on the real-time path". For a converter on the loop's own SPI
// bus the transfer IS the sample acquisition (and the DAC frame the actuation): handing them to
// another thread would add that thread's wake-up to every sample and every command, which is
// what a bus thread costs the CAN and Modbus drivers. Nothing else there allocates, locks,
// throws or logs. With pace drdy the loop waits on the ADC's data-ready edge
// (cycle_trigger(): one poll() on the GPIO line, the cycle's pacing sleep).
//
// Everything slow is off the real-time thread, on the maintenance thread (service()): the
// amplifier-fault line's edges, and re-initialising the ADC. The real-time thread gives the ADC
// bus away by setting the state to kReinitRequested (after crc_errors_to_reinit CRC errors or
// transfer_errors_to_reinit failed transfers in a row, or a STATUS word showing the ADC was
// reset); from then read() returns kDisconnected without touching the bus, the maintenance
// thread resets and re-configures the ADC with read-back verification, retrying with a doubling
// back-off (reinit_backoff_s) and counting each failure, and hands the bus back (kRunning).
//
// InputSample::device_status is the ADC's STATUS word of the sample (LOCK, RESET, CRC_ERR,
// DRDY3..0). read() statuses:
//   kNotActive     outside activate() .. deactivate()
//   kDisconnected  the transfer failed, or the ADC is being re-initialised
//   kBadData       CRC error (the sample is NaN), a code at full scale (clipped input), E or D
//                  not finite or outside range_v_per_m / range_c_per_m2
//   kDeviceFault   the amplifier's fault line is active, or the ADC reports a reset
//   kStale         no new conversion for more than stale_frames frames in a row (STATUS.DRDY),
//                  or the E and D codes unchanged for stuck_frames frames (a stuck converter)
//   kOk            otherwise
// With a `temp` channel, InputSample::temp_ref is the stack's temperature from the same frame;
// a clipped reading or one outside temp.range_degc leaves it NaN (counted: temp_out_of_range)
// and does not change the status: the loop runs on without a temperature that cycle.
// write() statuses: kNotActive, kDisconnected (the DAC transfer failed), kOk. A command beyond
// the DAC's range is clamped to it and counted; a non-finite command writes E = 0.
//
// Counters (DriverCounters): reads, writes; errors (failed transfers, GPIO errors, input-CRC
// errors the ADC reported); timeouts (data-ready waits that timed out); stale; bad_data (reads
// answered kBadData); retries (failed re-initialisation attempts); reconnects (successful
// re-initialisations); device_faults (amplifier-fault assertions, ADC resets); crc_errors (ADC
// frames with a bad CRC plus frames of ours the ADC rejected). SpiCounters has the causes apart;
// counters() carries them as its events, under SpiCounters' field names.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>

#include "selfsense/drivers/spi/ads131m04.hpp"
#include "selfsense/drivers/spi/dac8563.hpp"
#include "selfsense/drivers/spi/gpio_line.hpp"
#include "selfsense/drivers/spi/spi_bus.hpp"
#include "selfsense/drivers/spi/spi_config.hpp"
#include "selfsense/runtime/cycle_trigger.hpp"
#include "selfsense/runtime/driver.hpp"
#include "selfsense/runtime/latency_histogram.hpp"
#include "selfsense/runtime/pacer.hpp"

namespace selfsense::drivers::spi {

// The causes behind DriverCounters, for the documentation, the status and the tests.
struct SpiCounters {
  std::uint64_t crc_errors{0};         // ADC frames whose CRC did not match
  std::uint64_t input_crc_errors{0};   // frames of ours the ADC rejected (STATUS.CRC_ERR)
  std::uint64_t clipped{0};            // E or D code at the ADC's full scale
  std::uint64_t out_of_range{0};       // E or D not finite or outside its range
  std::uint64_t no_new_data{0};        // frames without a new conversion (STATUS.DRDY clear)
  std::uint64_t stuck{0};              // reads answered kStale for unchanged codes
  std::uint64_t drdy_missed{0};        // data-ready edges the loop was too late for
  std::uint64_t command_clipped{0};    // commands beyond the DAC's range
  std::uint64_t amp_faults{0};         // amplifier fault line assertions
  std::uint64_t adc_resets{0};         // STATUS.RESET seen while running
  std::uint64_t reinit_failures{0};    // failed re-initialisation attempts
  std::uint64_t reinits{0};            // successful re-initialisations
  std::uint64_t temp_out_of_range{0};  // temperature readings clipped, outside range_degc: none
};

// The hardware the driver talks to, not owned. Tests give chip emulators; the one-argument
// constructor builds spidev and libgpiod ones from the configuration.
struct SpiHardware {
  SpiBus* adc{nullptr};
  SpiBus* dac{nullptr};
  GpioLine* drdy{nullptr};    // required with pace drdy
  GpioLine* enable{nullptr};  // optional
  GpioLine* fault{nullptr};   // optional
  runtime::Clock* clock{nullptr};
};

enum class AdcState : std::uint8_t { kRunning, kReinitRequested, kReinitFailing };

class SpiDriver final : public runtime::Driver, private runtime::CycleTrigger {
 public:
  // Linux: /dev/spidev* and /dev/gpiochip* as configured, opened by activate().
  explicit SpiDriver(SpiConfig config);
  // Given hardware. maintenance_thread false: no thread; the caller runs service() (tests, in
  // simulated time).
  SpiDriver(SpiConfig config, SpiHardware hardware, bool maintenance_thread);
  ~SpiDriver() override;
  SpiDriver(const SpiDriver&) = delete;
  SpiDriver& operator=(const SpiDriver&) = delete;
  SpiDriver(SpiDriver&&) = delete;
  SpiDriver& operator=(SpiDriver&&) = delete;

  [[nodiscard]] std::string_view name() const noexcept override { return "spi"; }
  bool configure(const runtime::DriverSetup& setup, std::string* why) override;
  // Opens the hardware, resets and configures the ADC (every register read back), starts the
  // DAC at the safe output, enables the amplifier, starts the maintenance thread.
  bool activate(std::string* why) override;
  runtime::DriverStatus read(runtime::InputSample& out) noexcept override;
  runtime::DriverStatus write(const runtime::OutputCommand& command) noexcept override;
  // The safe output on the DAC, the amplifier disabled, the thread stopped, the hardware closed.
  void deactivate() noexcept override;
  [[nodiscard]] runtime::DriverCounters counters() const noexcept override;
  // With a `temp` section: read() fills temp_ref [degC] (NaN when the reading is clipped or
  // outside range_degc; counted, not a fault).
  [[nodiscard]] bool has_temperature() const noexcept override { return config_.temp.wired; }
  [[nodiscard]] runtime::CycleTrigger* cycle_trigger() noexcept override {
    return config_.pace == Pace::kDrdy && active_ ? this : nullptr;
  }

  // One maintenance step (not real-time): waits up to wait_ns for an edge of the amplifier's
  // fault line, then runs a due re-initialisation attempt.
  void service(std::int64_t wait_ns) noexcept;

  [[nodiscard]] SpiCounters spi_counters() const noexcept;
  [[nodiscard]] AdcState adc_state() const noexcept {
    return state_.load(std::memory_order_acquire);
  }
  [[nodiscard]] bool amplifier_fault() const noexcept {
    return amp_fault_.load(std::memory_order_relaxed);
  }
  // read() to write() of one cycle (real-time thread; read after deactivate()).
  [[nodiscard]] const runtime::LatencyHistogram& read_to_write() const noexcept {
    return read_to_write_;
  }
  [[nodiscard]] const SpiConfig& config() const noexcept { return config_; }

 private:
  Result wait(std::int64_t timeout_ns) noexcept override;  // runtime::CycleTrigger
  // The newest data-ready edge the last wait() took (runtime::CycleTrigger).
  [[nodiscard]] std::int64_t fired_ns() const noexcept override { return fired_ns_; }
  // Resets and configures the ADC; false with *why. Maintenance thread or activate().
  bool initialise_adc(std::string* why) noexcept;
  // Sends command (+ data) in one frame and returns the answer from the next (NULL) frame.
  bool exchange(std::uint16_t command, std::uint16_t data, bool with_data, std::uint16_t* answer,
                std::string* why) noexcept;
  bool write_dac(double field) noexcept;
  void request_reinit() noexcept;
  bool set_enable(bool on) const noexcept;
  bool fault_active(int level) const noexcept {
    return level >= 0 && (level == 0) == config_.gpio.fault.active_low;
  }
  void maintenance_loop() noexcept;

  SpiConfig config_;
  SpiHardware hw_{};
  bool maintenance_thread_{true};
  runtime::SteadyClock steady_{};
  // Linux hardware (the one-argument constructor).
  std::unique_ptr<SpidevBus> own_adc_{};
  std::unique_ptr<SpidevBus> own_dac_{};
  std::unique_ptr<GpiodLine> own_drdy_{};
  std::unique_ptr<GpiodLine> own_enable_{};
  std::unique_ptr<GpiodLine> own_fault_{};

  bool configured_{false};
  bool active_{false};
  std::int64_t period_ns_{0};
  std::thread thread_{};
  std::atomic<bool> stop_{false};
  std::atomic<AdcState> state_{AdcState::kRunning};
  std::atomic<bool> amp_fault_{false};

  // Real-time thread only.
  ads131m04::Frame null_tx_{};
  ads131m04::Frame rx_{};
  int crc_run_{0};
  int transfer_run_{0};
  int no_data_run_{0};
  int stuck_run_{0};
  bool have_codes_{false};  // last_*_code_ hold a frame of this (re-)initialisation
  std::int32_t last_e_code_{0};
  std::int32_t last_d_code_{0};
  std::int64_t read_ns_{0};
  std::int64_t fired_ns_{-1};
  runtime::LatencyHistogram read_to_write_{};

  // Maintenance thread only.
  std::int64_t next_attempt_ns_{0};
  std::int64_t backoff_ns_{0};

  struct Atomics {
    std::atomic<std::uint64_t> reads{0}, writes{0}, errors{0}, timeouts{0}, stale{0}, bad_data{0},
        crc_errors{0}, input_crc_errors{0}, clipped{0}, out_of_range{0}, no_new_data{0}, stuck{0},
        drdy_missed{0}, command_clipped{0}, amp_faults{0}, adc_resets{0}, reinit_failures{0},
        reinits{0}, temp_out_of_range{0};
  };
  Atomics n_{};
};

}  // namespace selfsense::drivers::spi
