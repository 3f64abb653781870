#include "selfsense/operators/parameter_error.hpp"

namespace selfsense::operators {

void require_valid(bool valid, const std::string& why) {
  if (!valid) throw ParameterError(why);
}

}  // namespace selfsense::operators
