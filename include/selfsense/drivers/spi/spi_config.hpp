// The driver section of a daemon configuration for the SPI driver (docs/drivers/spi.md): an
// ADS131M04 ADC and a DAC8563 DAC on spidev, data-ready, amplifier-enable and amplifier-fault
// lines on libgpiod, and the analog front end that turns volts into E and D. Read strictly:
// unknown keys are errors, every problem names its key ("FILE:LINE: driver.adc.osr: ...").
// Not real-time code. The annotated example is config/spi-emulated.yaml.
//
//   type: spi
//   pace: drdy | timer          drdy: the ADC's data-ready edge starts each cycle
//   adc: {device, speed_hz, clkin_hz, osr, power, input_crc}
//   dac: {device, speed_hz, full_scale_v, internal_reference, output: a | b}
//   transducer: {layers, layer_thickness_m, electrode_area_m2}
//   e: {channel, pga_gain, divider, offset_v, range_v_per_m: [lo, hi]}
//        E = (v - offset_v) * divider / layer_thickness           (HV divider onto the ADC)
//   d: {channel, pga_gain, feedback_capacitance_f, inverting, offset_v, range_c_per_m2}
//        q = -+(v - offset_v) * C_f,  D = q / (layers * electrode_area)   (charge amplifier)
//   amplifier: {gain_v_per_v, input_offset_v}
//        u = gain * (v_dac - input_offset_v),  E = u / layer_thickness   (the HV amplifier)
//   temp: {channel, pga_gain, volts_at_0_degc, volts_per_degc, range_degc: [lo, hi]}   optional
//        theta = (v - volts_at_0_degc) / volts_per_degc   (a linear analog sensor on the stack,
//        e.g. 0.5 V + 10 mV/K behind a 2:1 divider; absent: no temperature, the recording has no
//        `temp` column)
//   gpio: {chip, drdy: {line}, enable: {line, active_low}, fault: {line, active_low}}
//   faults: {stale_frames, stuck_frames, crc_errors_to_reinit, transfer_errors_to_reinit,
//            reinit_backoff_s: [min, max]}
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "selfsense/io/yaml_map.hpp"

namespace selfsense::drivers::spi {

enum class Pace : std::uint8_t { kTimer, kDrdy };

struct AdcConfig {
  std::string device{"/dev/spidev0.0"};
  std::uint32_t speed_hz{8000000};
  double clkin_hz{8192000.0};
  int osr{128};          // 128, 256, 512, 1024, 2048, 4096, 8192, 16256
  int power{2};          // 0 very low, 1 low, 2 high resolution (CLOCK.PWR)
  bool input_crc{true};  // MODE.RX_CRC_EN: the ADC checks the CRC of our frames

  [[nodiscard]] double data_rate_hz() const noexcept {
    return clkin_hz / 2.0 / static_cast<double>(osr);
  }
  [[nodiscard]] std::uint8_t osr_code() const noexcept;  // 0..7; 0xFF: not a valid OSR
};

struct DacConfig {
  std::string device{"/dev/spidev0.1"};
  std::uint32_t speed_hz{10000000};
  double full_scale_v{5.0};       // V_REF times the output gain
  bool internal_reference{true};  // 2.5 V internal reference (gain 2: 5 V full scale)
  std::uint8_t output{0};         // 0: DAC-A, 1: DAC-B
};

struct Transducer {
  int layers{167};
  double layer_thickness_m{60e-6};
  double electrode_area_m2{25e-6};
};

struct FieldChannel {  // E: the HV divider onto an ADC input
  int channel{0};
  int pga_gain{1};
  double divider{125.0};  // actuator volts per ADC input volt
  double offset_v{0.0};   // ADC input volts at 0 V on the actuator
  std::array<double, 2> range_v_per_m{-0.5e6, 2.4e6};
};

struct ChargeChannel {  // D: the charge amplifier onto an ADC input
  int channel{1};
  int pga_gain{1};
  double feedback_capacitance_f{330e-6};
  bool inverting{true};  // v = -q / C_f
  double offset_v{0.0};
  std::array<double, 2> range_c_per_m2{-0.02, 0.09};
};

// The stack's temperature: a linear analog sensor (a silicon sensor's output, or a thermistor
// or RTD behind a linearising front end) onto a spare ADC input, sampled with E and D.
struct TemperatureChannel {
  bool wired{false};  // the section is present
  int channel{2};
  int pga_gain{1};
  double volts_at_0_degc{0.25};  // a 0.5 V + 10 mV/K sensor behind a 2:1 divider: 150 degC
  double volts_per_degc{0.005};  // is 1.0 V, inside the +-1.2 V full scale at gain 1
  std::array<double, 2> range_degc{-40.0, 150.0};  // outside: no temperature that cycle
};

struct AmplifierConfig {
  double gain_v_per_v{30.0};
  double input_offset_v{0.0};
};

struct LineConfig {
  int line{-1};  // -1: not wired
  bool active_low{false};
};

struct GpioConfig {
  std::string chip{"gpiochip0"};
  LineConfig drdy{-1, true};  // active low by the ADC's definition (falling edge: data ready)
  LineConfig enable{};        // amplifier enable output
  LineConfig fault{};         // amplifier fault input
};

struct FaultConfig {
  int stale_frames{2};          // frames in a row without new data answered kOk before kStale
  int stuck_frames{50};         // frames in a row with E and D codes unchanged: kStale (0: off)
  int crc_errors_to_reinit{3};  // CRC errors in a row that start a re-initialisation
  int transfer_errors_to_reinit{3};  // failed transfers in a row that start one
  std::array<double, 2> reinit_backoff_s{0.01, 1.0};
};

struct SpiConfig {
  Pace pace{Pace::kDrdy};
  AdcConfig adc{};
  DacConfig dac{};
  Transducer transducer{};
  FieldChannel e{};
  ChargeChannel d{};
  TemperatureChannel temp{};
  AmplifierConfig amplifier{};
  GpioConfig gpio{};
  FaultConfig faults{};

  // Each problem as "KEY.PATH: what is wrong" (relative to driver.), given the loop's rate.
  [[nodiscard]] std::vector<std::string> problems(double loop_rate_hz) const;

  // Front-end scaling. ADC input volts -> E [V/m] and D [C/m^2]; E [V/m] -> DAC volts.
  [[nodiscard]] double field_of(double v) const noexcept {
    return (v - e.offset_v) * e.divider / transducer.layer_thickness_m;
  }
  [[nodiscard]] double displacement_of(double v) const noexcept {
    const double q = (d.inverting ? -1.0 : 1.0) * (v - d.offset_v) * d.feedback_capacitance_f;
    return q / (static_cast<double>(transducer.layers) * transducer.electrode_area_m2);
  }
  [[nodiscard]] double temperature_of(double v) const noexcept {
    return (v - temp.volts_at_0_degc) / temp.volts_per_degc;
  }
  [[nodiscard]] double dac_volts_of(double field) const noexcept {
    return field * transducer.layer_thickness_m / amplifier.gain_v_per_v + amplifier.input_offset_v;
  }
};

// Reads the driver section's keys (driver.type is already read) into out and appends every
// problem located at its key. Structural problems (unknown keys, wrong types) throw
// io::YamlError like every strict read.
void read_spi_config(io::YamlMap& driver, double loop_rate_hz, SpiConfig& out,
                     std::vector<std::string>& problems);

}  // namespace selfsense::drivers::spi
