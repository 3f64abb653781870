// What a runtime model says about each sample besides its estimate. Codes are stable: the tools
// write them as the `estimate_status` column of a recording and the daemon counts them.
//   0 ok                 the estimate is valid
//   1 input_not_finite   E or D was NaN or infinite: sample rejected, state unchanged
//   2 input_out_of_range E or D far outside the identification range: rejected, state unchanged
//   3 no_solution        no stress reproduces the measured D at this E (numerical models)
//   4 not_monotone       D is not monotone in T over the identified stress range: the inverse
//                        may not be unique (paper eq. 3)
//   5 not_converged      an iterative solver hit its limit
// A rejected sample returns the last accepted estimate, so a consumer that ignores the status
// still sees a plausible number; the status says it is stale.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

namespace selfsense::models {

enum class SampleStatus : std::uint8_t {
  kOk = 0,
  kInputNotFinite = 1,
  kInputOutOfRange = 2,
  kNoSolution = 3,
  kNotMonotone = 4,
  kNotConverged = 5,
};
inline constexpr std::size_t kSampleStatusCount = 6;

[[nodiscard]] constexpr std::string_view to_string(SampleStatus s) noexcept {
  constexpr std::array<std::string_view, kSampleStatusCount> kNames{
      "ok",          "input_not_finite", "input_out_of_range",
      "no_solution", "not_monotone",     "not_converged"};
  const auto i = static_cast<std::size_t>(s);
  return i < kNames.size() ? kNames[i] : std::string_view("unknown");
}

// How often each status occurred. Real-time safe.
class StatusCounts {
 public:
  void add(SampleStatus s) noexcept { ++counts_[static_cast<std::size_t>(s)]; }
  [[nodiscard]] std::uint64_t operator[](SampleStatus s) const noexcept {
    return counts_[static_cast<std::size_t>(s)];
  }
  [[nodiscard]] std::uint64_t total() const noexcept {
    std::uint64_t n = 0;
    for (const std::uint64_t c : counts_)
      n += c;
    return n;
  }
  [[nodiscard]] std::uint64_t not_ok() const noexcept {
    return total() - (*this)[SampleStatus::kOk];
  }
  void clear() noexcept { counts_.fill(0); }

 private:
  std::array<std::uint64_t, kSampleStatusCount> counts_{};
};

}  // namespace selfsense::models
