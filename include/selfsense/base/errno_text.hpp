// The ground floor's error text: what an errno value means ("No such file or directory"), or
// "unknown reason" for 0 (a call that failed without setting errno). Standard library only;
// thread-safe (unlike std::strerror). Allocates; not for the real-time path.
#pragma once

#include <string>

namespace selfsense::base {

[[nodiscard]] std::string errno_text(int error);

}  // namespace selfsense::base
