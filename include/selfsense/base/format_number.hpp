// The ground floor's number text: the shortest text that reads back as the same double
// (std::to_chars without a format: "0.1", "2000", "1e-07", "-inf", "nan"), for messages and
// files that must round-trip. Standard library only; every library may include it. Allocates;
// not for the real-time path (csv_row.cpp formats into its own buffer there).
#pragma once

#include <string>

namespace selfsense::base {

[[nodiscard]] std::string format_number(double value);

}  // namespace selfsense::base
