#include "selfsense/base/errno_text.hpp"

#include <system_error>

namespace selfsense::base {

std::string errno_text(int error) {
  return error == 0 ? std::string("unknown reason") : std::generic_category().message(error);
}

}  // namespace selfsense::base
