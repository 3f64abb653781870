#include <gpiod.h>

#include <cerrno>
#include <ctime>
#include <utility>

#include "selfsense/base/errno_text.hpp"
#include "selfsense/drivers/spi/gpio_line.hpp"

namespace selfsense::drivers::spi {

GpiodLine::GpiodLine(GpiodSettings settings) : settings_(std::move(settings)) {}

GpiodLine::~GpiodLine() {
  close();
}

bool GpiodLine::open(const char* consumer, std::string* why) {
  const auto fail = [&](const std::string& what) {
    if (why != nullptr) {
      *why = settings_.chip + " line " + std::to_string(settings_.offset) + ": " + what + ": " +
             base::errno_text(errno);
    }
    close();
    return false;
  };
  chip_ = gpiod_chip_open_lookup(settings_.chip.c_str());
  if (chip_ == nullptr) return fail("gpiod_chip_open_lookup");
  line_ = gpiod_chip_get_line(chip_, settings_.offset);
  if (line_ == nullptr) return fail("gpiod_chip_get_line");
  int rc = -1;
  switch (settings_.use) {
    case LineUse::kInput:
      rc = gpiod_line_request_input(line_, consumer);
      break;
    case LineUse::kOutput:
      rc = gpiod_line_request_output(line_, consumer, settings_.initial ? 1 : 0);
      break;
    case LineUse::kFallingEdges:
      rc = gpiod_line_request_falling_edge_events(line_, consumer);
      break;
    case LineUse::kBothEdges:
      rc = gpiod_line_request_both_edges_events(line_, consumer);
      break;
  }
  if (rc != 0) return fail("request (is another program holding the line?)");
  return true;
}

void GpiodLine::close() noexcept {
  if (line_ != nullptr) gpiod_line_release(line_);
  line_ = nullptr;
  if (chip_ != nullptr) gpiod_chip_close(chip_);
  chip_ = nullptr;
}

int GpiodLine::read() noexcept {
  return line_ == nullptr ? -1 : gpiod_line_get_value(line_);
}

bool GpiodLine::write(bool high) noexcept {
  return line_ != nullptr && gpiod_line_set_value(line_, high ? 1 : 0) == 0;
}

EdgeWait GpiodLine::wait_edge(std::int64_t timeout_ns, Edge* edge) noexcept {
  if (line_ == nullptr) return EdgeWait::kError;
  const timespec timeout{static_cast<time_t>(timeout_ns / 1'000'000'000),
                         static_cast<long>(timeout_ns % 1'000'000'000)};
  const int rc = gpiod_line_event_wait(line_, &timeout);
  if (rc == 0) return EdgeWait::kTimeout;
  if (rc < 0) return EdgeWait::kError;
  gpiod_line_event event{};
  if (gpiod_line_event_read(line_, &event) != 0) return EdgeWait::kError;
  if (edge != nullptr) {
    edge->rising = event.event_type == GPIOD_LINE_EVENT_RISING_EDGE;
    edge->timestamp_ns =
        static_cast<std::int64_t>(event.ts.tv_sec) * 1'000'000'000 + event.ts.tv_nsec;
  }
  return EdgeWait::kEdge;
}

}  // namespace selfsense::drivers::spi
