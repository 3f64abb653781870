// The SPI driver's bench in simulated time: the simulated transducer (selfsense::plant) behind
// its analog front end (HV divider onto ADC channel e, charge amplifier onto channel d, a linear
// temperature sensor onto channel temp when wired, the HV amplifier driven by the DAC), an
// ADS131M04 and a DAC8563 emulator at the SpiBus seam, emulated enable and fault lines, and the
// driver on them (maintenance run by the test through service()). The plant steps once per ADC
// conversion with the field the DAC commands, so the loop closes through the same frames and codes
// as on hardware.
#pragma once

#include <array>
#include <cmath>

#include "selfsense/drivers/spi/spi_config.hpp"
#include "selfsense/drivers/spi/spi_driver.hpp"
#include "selfsense/plant/config.hpp"
#include "selfsense/plant/plant.hpp"
#include "selfsense/runtime/pacer.hpp"
#include "support/spi/ads131m04_emulator.hpp"
#include "support/spi/dac8563_emulator.hpp"
#include "support/spi/emulated_line.hpp"

namespace selfsense::test {

// A driver section for the emulated bench: the ADC at rate_hz (OSR 128, f_CLKIN = 256 rate),
// data-ready pacing, the enable and fault lines wired (fault active low), the transducer's
// geometry that of the plant's defaults.
inline drivers::spi::SpiConfig emulated_spi_config(double rate_hz) {
  drivers::spi::SpiConfig c;
  c.pace = drivers::spi::Pace::kDrdy;
  c.adc.device = "emulated-adc";
  c.dac.device = "emulated-dac";
  c.adc.osr = 128;
  c.adc.clkin_hz = rate_hz * 2.0 * 128.0;
  c.gpio.drdy = {0, true};
  c.gpio.enable = {1, false};
  c.gpio.fault = {2, true};
  const plant::GeometryConfig g;
  c.transducer = {g.layers, g.layer_thickness_m, g.electrode_area_m2};
  return c;
}

struct SpiBench {
  SpiBench(const drivers::spi::SpiConfig& c, const plant::PlantConfig& plant_config)
      : config(c),
        plant(plant_config),
        dac(c.dac.full_scale_v),
        adc(clock, c.adc.clkin_hz, [this](std::int64_t /*t_ns*/) { return convert(); }),
        driver(c, {&adc, &dac, &adc.drdy_line(), &enable, &fault, &clock}, false) {}

  // One conversion: the amplifier applies the DAC's output, the plant steps, the front end
  // turns the measured E and D into ADC input volts (independently of the driver's scaling).
  std::array<double, 4> convert() {
    const double h = config.transducer.layer_thickness_m;
    const double u = config.amplifier.gain_v_per_v *
                     (dac.volts(config.dac.output) - config.amplifier.input_offset_v);
    last = plant.step({u / h, 0.0, ambient_degc});
    std::array<double, 4> v{};
    v.at(static_cast<std::size_t>(config.e.channel)) =
        last.e_meas_v_per_m * h / config.e.divider + config.e.offset_v;
    const double q =
        last.d_meas_c_per_m2 * config.transducer.layers * config.transducer.electrode_area_m2;
    v.at(static_cast<std::size_t>(config.d.channel)) =
        (config.d.inverting ? -q : q) / config.d.feedback_capacitance_f + config.d.offset_v;
    if (config.temp.wired) {
      v.at(static_cast<std::size_t>(config.temp.channel)) =
          config.temp.volts_at_0_degc + config.temp.volts_per_degc * last.temp_degc;
    }
    return v;
  }

  drivers::spi::SpiConfig config;
  runtime::SimulatedClock clock{};
  plant::Plant plant;
  plant::StepOutput last{};
  double ambient_degc{25.0};  // the plant's temperature input (the stack's, without heating)
  Dac8563Emulator dac;
  Ads131m04Emulator adc;
  EmulatedLine enable{false};
  EmulatedLine fault{true};  // active low: high is "no fault"
  drivers::spi::SpiDriver driver;
};

}  // namespace selfsense::test
