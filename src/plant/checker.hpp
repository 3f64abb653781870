// Collects the first violated constraint of a configuration as "<prefix><key path>: <value>:
// <constraint>" (internal to selfsense_plant: config.cpp and excitation.cpp).
#pragma once

#include <cmath>
#include <sstream>
#include <string>
#include <utility>

namespace selfsense::plant::detail {

class Checker final {
 public:
  Checker(std::string* why, std::string prefix) : why_{why}, prefix_{std::move(prefix)} {}
  [[nodiscard]] bool ok() const { return ok_; }

  template <typename T>
  void require(bool condition, const std::string& path, T value, const std::string& constraint) {
    if (!ok_ || condition) return;
    ok_ = false;
    if (why_ != nullptr) {
      std::ostringstream out;
      out << prefix_ << path << ": " << value << ": " << constraint;
      *why_ = out.str();
    }
  }
  void positive(const std::string& path, double value) {
    require(std::isfinite(value) && value > 0.0, path, value, "must be a finite number > 0");
  }
  void non_negative(const std::string& path, double value) {
    require(std::isfinite(value) && value >= 0.0, path, value, "must be a finite number >= 0");
  }
  void finite(const std::string& path, double value) {
    require(std::isfinite(value), path, value, "must be finite");
  }

 private:
  std::string* why_;
  std::string prefix_;
  bool ok_{true};
};

}  // namespace selfsense::plant::detail
