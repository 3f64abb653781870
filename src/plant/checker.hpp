// Collects the first violated constraint of a configuration in the one message format of
// selfsense/base/check.hpp, "<prefix><key path>: <value> <constraint>" (internal to
// selfsense_plant: config.cpp and excitation.cpp).
#pragma once

#include <string>
#include <string_view>
#include <type_traits>
#include <utility>

#include "selfsense/base/check.hpp"

namespace selfsense::plant::detail {

class Checker final {
 public:
  Checker(std::string* why, std::string prefix) : why_{why}, prefix_{std::move(prefix)} {}
  [[nodiscard]] bool ok() const { return ok_; }

  template <typename T>
  requires std::is_arithmetic_v<T>
  void require(bool condition, const std::string& path, T value, std::string_view constraint) {
    if (!ok_) return;
    ok_ = base::check::require(condition, prefix_ + path, value, constraint, why_);
  }
  void positive(const std::string& path, double value) {
    if (ok_) ok_ = base::check::positive(prefix_ + path, value, why_);
  }
  void non_negative(const std::string& path, double value) {
    if (ok_) ok_ = base::check::non_negative(prefix_ + path, value, why_);
  }
  void finite(const std::string& path, double value) {
    if (ok_) ok_ = base::check::finite(prefix_ + path, value, why_);
  }

 private:
  std::string* why_;
  std::string prefix_;
  bool ok_{true};
};

}  // namespace selfsense::plant::detail
