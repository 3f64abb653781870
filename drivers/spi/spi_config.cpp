#include "selfsense/drivers/spi/spi_config.hpp"

#include <cmath>

#include "selfsense/base/format_number.hpp"
#include "selfsense/operators/parameter_error.hpp"

namespace selfsense::drivers::spi {
namespace {

bool power_of_two_up_to_128(int g) noexcept {
  return g >= 1 && g <= 128 && (g & (g - 1)) == 0;
}

void read_range(io::YamlMap& m, const char* key, std::array<double, 2>& out) {
  std::vector<double> v{out[0], out[1]};
  m.read_sequence(key, v);
  if (v.size() != 2) m.fail(key, "expected [min, max]");
  out = {v[0], v[1]};
}

void read_line(io::YamlMap& gpio, const char* key, LineConfig& out) {
  if (auto m = gpio.optional_map(key)) {
    out.line = m->required<int>("line");
    m->read("active_low", out.active_low);
    m->finish();
  }
}

std::uint32_t read_hz(io::YamlMap& m, std::uint32_t fallback) {
  std::uint64_t hz = fallback;
  m.read("speed_hz", hz);
  if (hz > 100000000U) m.fail("speed_hz", std::to_string(hz) + " Hz is beyond any SPI clock");
  return static_cast<std::uint32_t>(hz);
}

}  // namespace

std::uint8_t AdcConfig::osr_code() const noexcept {
  for (std::uint8_t c = 0; c < 8; ++c) {
    if ((c == 7 ? 16256 : 128 << c) == osr) return c;
  }
  return 0xFF;
}

std::vector<std::string> SpiConfig::problems(double loop_rate_hz) const {
  std::vector<std::string> p;
  const auto check = [&p](bool ok, const std::string& message) {
    if (!ok) p.push_back(message);
  };
  const auto num = [](double v) { return base::format_number(v); };
  check(!adc.device.empty(), "adc.device: must name a spidev device (/dev/spidevB.C)");
  check(adc.speed_hz >= 100000 && adc.speed_hz <= 25000000,
        "adc.speed_hz: " + std::to_string(adc.speed_hz) + " must be within [100000, 25000000]");
  check(adc.clkin_hz >= 300e3 && adc.clkin_hz <= 8.25e6,
        "adc.clkin_hz: " + num(adc.clkin_hz) + " must be within [300000, 8250000]");
  check(adc.osr_code() != 0xFF, "adc.osr: " + std::to_string(adc.osr) +
                                    " is not one of 128, 256, 512, 1024, 2048, 4096, 8192, 16256");
  check(adc.power >= 0 && adc.power <= 2,
        "adc.power: " + std::to_string(adc.power) + " must be 0, 1 or 2");
  if (adc.osr_code() != 0xFF && loop_rate_hz > 0.0) {
    const double rate = adc.data_rate_hz();
    if (pace == Pace::kDrdy) {
      check(std::abs(rate - loop_rate_hz) <= 1e-6 * loop_rate_hz,
            "adc.osr: the data rate clkin_hz / 2 / osr = " + num(rate) +
                " Hz must equal loop.rate_hz " + num(loop_rate_hz) + " when pace is drdy");
    } else {
      check(rate >= loop_rate_hz, "adc.osr: the data rate clkin_hz / 2 / osr = " + num(rate) +
                                      " Hz is below loop.rate_hz " + num(loop_rate_hz));
    }
  }
  check(!dac.device.empty(), "dac.device: must name a spidev device (/dev/spidevB.C)");
  check(dac.device != adc.device,
        "dac.device: the DAC needs its own chip select (not " + adc.device + ", the ADC's)");
  check(dac.speed_hz >= 100000 && dac.speed_hz <= 50000000,
        "dac.speed_hz: " + std::to_string(dac.speed_hz) + " must be within [100000, 50000000]");
  check(dac.full_scale_v > 0.0 && dac.full_scale_v <= 5.5,
        "dac.full_scale_v: " + num(dac.full_scale_v) + " must be within (0, 5.5]");
  check(transducer.layers >= 1, "transducer.layers: must be >= 1");
  check(transducer.layer_thickness_m > 0.0 && transducer.layer_thickness_m < 0.1,
        "transducer.layer_thickness_m: " + num(transducer.layer_thickness_m) +
            " must be within (0, 0.1)");
  check(transducer.electrode_area_m2 > 0.0 && transducer.electrode_area_m2 < 1.0,
        "transducer.electrode_area_m2: " + num(transducer.electrode_area_m2) +
            " must be within (0, 1)");
  check(e.channel >= 0 && e.channel <= 3, "e.channel: must be 0..3");
  check(d.channel >= 0 && d.channel <= 3, "d.channel: must be 0..3");
  check(e.channel != d.channel, "d.channel: " + std::to_string(d.channel) +
                                    " is also e.channel (E and D need their own inputs)");
  check(power_of_two_up_to_128(e.pga_gain),
        "e.pga_gain: " + std::to_string(e.pga_gain) + " is not one of 1, 2, 4, ..., 128");
  check(power_of_two_up_to_128(d.pga_gain),
        "d.pga_gain: " + std::to_string(d.pga_gain) + " is not one of 1, 2, 4, ..., 128");
  check(std::isfinite(e.divider) && e.divider > 0.0,
        "e.divider: " + num(e.divider) + " must be > 0 (actuator volts per ADC volt)");
  check(std::isfinite(d.feedback_capacitance_f) && d.feedback_capacitance_f > 0.0,
        "d.feedback_capacitance_f: " + num(d.feedback_capacitance_f) + " must be > 0");
  check(std::abs(e.offset_v) < 1.2, "e.offset_v: must be within (-1.2, 1.2) V");
  check(std::abs(d.offset_v) < 1.2, "d.offset_v: must be within (-1.2, 1.2) V");
  if (temp.wired) {
    check(temp.channel >= 0 && temp.channel <= 3, "temp.channel: must be 0..3");
    check(temp.channel != e.channel && temp.channel != d.channel,
          "temp.channel: " + std::to_string(temp.channel) +
              " is also the channel of E or D (the temperature needs its own input)");
    check(power_of_two_up_to_128(temp.pga_gain),
          "temp.pga_gain: " + std::to_string(temp.pga_gain) + " is not one of 1, 2, 4, ..., 128");
    check(std::isfinite(temp.volts_per_degc) && temp.volts_per_degc != 0.0,
          "temp.volts_per_degc: " + num(temp.volts_per_degc) + " must be finite and not 0");
    check(std::isfinite(temp.volts_at_0_degc), "temp.volts_at_0_degc: must be finite");
    const bool ordered = temp.range_degc[0] < temp.range_degc[1];
    check(ordered, "temp.range_degc: needs min < max");
    if (ordered && power_of_two_up_to_128(temp.pga_gain) && std::isfinite(temp.volts_per_degc)) {
      // Like E's: the whole range must be measurable, both ends inside the ADC's full scale.
      const double fs = 1.2 / temp.pga_gain;
      for (const double theta : temp.range_degc) {
        const double v = temp.volts_at_0_degc + temp.volts_per_degc * theta;
        check(std::abs(v) < fs, "temp.range_degc: " + num(theta) + " degC is " + num(v) +
                                    " V at the ADC, outside its full scale +-" + num(fs) +
                                    " V (narrow the range or lower temp.pga_gain)");
      }
    }
  }
  check(e.range_v_per_m[0] < e.range_v_per_m[1], "e.range_v_per_m: needs min < max");
  check(d.range_c_per_m2[0] < d.range_c_per_m2[1], "d.range_c_per_m2: needs min < max");
  check(std::isfinite(amplifier.gain_v_per_v) && amplifier.gain_v_per_v > 0.0,
        "amplifier.gain_v_per_v: " + num(amplifier.gain_v_per_v) + " must be > 0");
  const bool scaling_valid =
      power_of_two_up_to_128(e.pga_gain) && power_of_two_up_to_128(d.pga_gain) && e.divider > 0.0 &&
      d.feedback_capacitance_f > 0.0 && transducer.layers >= 1 &&
      transducer.layer_thickness_m > 0.0 && transducer.electrode_area_m2 > 0.0;
  if (scaling_valid) {
    // The whole E range must be measurable: both ends inside the ADC's full scale.
    const double fs = 1.2 / e.pga_gain;
    for (const double field : e.range_v_per_m) {
      const double v = field * transducer.layer_thickness_m / e.divider + e.offset_v;
      check(std::abs(v) < fs, "e.range_v_per_m: " + num(field) + " V/m is " + num(v) +
                                  " V at the ADC, outside its full scale +-" + num(fs) +
                                  " V (raise e.divider or lower e.pga_gain)");
    }
    const double fs_d = 1.2 / d.pga_gain;
    for (const double disp : d.range_c_per_m2) {
      const double q = disp * transducer.layers * transducer.electrode_area_m2;
      const double v = (d.inverting ? -1.0 : 1.0) * q / d.feedback_capacitance_f + d.offset_v;
      check(std::abs(v) < fs_d, "d.range_c_per_m2: " + num(disp) + " C/m^2 is " + num(v) +
                                    " V at the ADC, outside its full scale +-" + num(fs_d) +
                                    " V (raise d.feedback_capacitance_f or lower d.pga_gain)");
    }
  }
  check(gpio.drdy.line >= 0 || pace == Pace::kTimer,
        "gpio.drdy: pace drdy needs the data-ready line");
  check(gpio.drdy.active_low,
        "gpio.drdy.active_low: must be true (the ADS131M04's DRDY falls "
        "when a conversion is ready; the driver waits for falling edges)");
  check(gpio.drdy.line < 0 || !gpio.chip.empty(), "gpio.chip: must name the GPIO chip");
  check(faults.stale_frames >= 0 && faults.stale_frames <= 1000,
        "faults.stale_frames: must be within [0, 1000]");
  check(faults.stuck_frames >= 0 && faults.stuck_frames <= 1000000,
        "faults.stuck_frames: must be within [0, 1000000] (0: off)");
  check(faults.crc_errors_to_reinit >= 1 && faults.crc_errors_to_reinit <= 1000,
        "faults.crc_errors_to_reinit: must be within [1, 1000]");
  check(faults.transfer_errors_to_reinit >= 1 && faults.transfer_errors_to_reinit <= 1000,
        "faults.transfer_errors_to_reinit: must be within [1, 1000]");
  check(faults.reinit_backoff_s[0] > 0.0 &&
            faults.reinit_backoff_s[0] <= faults.reinit_backoff_s[1] &&
            faults.reinit_backoff_s[1] <= 60.0,
        "faults.reinit_backoff_s: needs 0 < min <= max <= 60");
  return p;
}

void read_spi_config(io::YamlMap& driver, double loop_rate_hz, SpiConfig& out,
                     std::vector<std::string>& problems) {
  out = SpiConfig{};
  std::string pace = "drdy";
  driver.read("pace", pace);
  if (pace == "drdy") {
    out.pace = Pace::kDrdy;
  } else if (pace == "timer") {
    out.pace = Pace::kTimer;
  } else {
    driver.fail("pace", "'" + pace + "' is not one of drdy, timer");
  }
  io::YamlMap adc = driver.map("adc");
  out.adc.device = adc.required<std::string>("device");
  out.adc.speed_hz = read_hz(adc, out.adc.speed_hz);
  adc.read("clkin_hz", out.adc.clkin_hz);
  adc.read("osr", out.adc.osr);
  std::string power = "high-resolution";
  adc.read("power", power);
  if (power == "very-low") {
    out.adc.power = 0;
  } else if (power == "low") {
    out.adc.power = 1;
  } else if (power == "high-resolution") {
    out.adc.power = 2;
  } else {
    adc.fail("power", "'" + power + "' is not one of very-low, low, high-resolution");
  }
  adc.read("input_crc", out.adc.input_crc);
  adc.finish();

  io::YamlMap dac = driver.map("dac");
  out.dac.device = dac.required<std::string>("device");
  out.dac.speed_hz = read_hz(dac, out.dac.speed_hz);
  dac.read("full_scale_v", out.dac.full_scale_v);
  dac.read("internal_reference", out.dac.internal_reference);
  std::string output = "a";
  dac.read("output", output);
  if (output != "a" && output != "b") dac.fail("output", "'" + output + "' is not one of a, b");
  out.dac.output = output == "a" ? 0 : 1;
  dac.finish();

  io::YamlMap t = driver.map("transducer");
  t.read("layers", out.transducer.layers);
  t.read("layer_thickness_m", out.transducer.layer_thickness_m);
  t.read("electrode_area_m2", out.transducer.electrode_area_m2);
  t.finish();

  io::YamlMap e = driver.map("e");
  e.read("channel", out.e.channel);
  e.read("pga_gain", out.e.pga_gain);
  e.read("divider", out.e.divider);
  e.read("offset_v", out.e.offset_v);
  read_range(e, "range_v_per_m", out.e.range_v_per_m);
  e.finish();

  io::YamlMap d = driver.map("d");
  d.read("channel", out.d.channel);
  d.read("pga_gain", out.d.pga_gain);
  d.read("feedback_capacitance_f", out.d.feedback_capacitance_f);
  d.read("inverting", out.d.inverting);
  d.read("offset_v", out.d.offset_v);
  read_range(d, "range_c_per_m2", out.d.range_c_per_m2);
  d.finish();

  if (auto th = driver.optional_map("temp")) {
    out.temp.wired = true;
    th->read("channel", out.temp.channel);
    th->read("pga_gain", out.temp.pga_gain);
    th->read("volts_at_0_degc", out.temp.volts_at_0_degc);
    th->read("volts_per_degc", out.temp.volts_per_degc);
    read_range(*th, "range_degc", out.temp.range_degc);
    th->finish();
  }
  if (auto a = driver.optional_map("amplifier")) {
    a->read("gain_v_per_v", out.amplifier.gain_v_per_v);
    a->read("input_offset_v", out.amplifier.input_offset_v);
    a->finish();
  }
  if (auto g = driver.optional_map("gpio")) {
    g->read("chip", out.gpio.chip);
    read_line(*g, "drdy", out.gpio.drdy);
    read_line(*g, "enable", out.gpio.enable);
    read_line(*g, "fault", out.gpio.fault);
    g->finish();
  }
  if (auto f = driver.optional_map("faults")) {
    f->read("stale_frames", out.faults.stale_frames);
    f->read("stuck_frames", out.faults.stuck_frames);
    f->read("crc_errors_to_reinit", out.faults.crc_errors_to_reinit);
    f->read("transfer_errors_to_reinit", out.faults.transfer_errors_to_reinit);
    read_range(*f, "reinit_backoff_s", out.faults.reinit_backoff_s);
    f->finish();
  }
  for (const std::string& p : out.problems(loop_rate_hz))
    problems.push_back(driver.locate("driver." + p));
}

}  // namespace selfsense::drivers::spi
