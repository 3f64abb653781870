// One output channel under diagnosis (D, S, or E under charge drive): the recording, the base
// model's output, and what the candidates read besides.
#pragma once

#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "selfsense/models/side_model.hpp"
#include "selfsense/models/transducer_model.hpp"

namespace selfsense::diagnosis::detail {

// The channel's side identified on the first half of the recording as recorded, per structure:
// the null of every judgement by re-identification on the channel and the first half of the
// stress's cross-fit (reidentified.hpp, first_half_fit). On a long record each identification
// costs seconds, so it runs once (docs/diagnose.md, "Speed").
class FirstHalfFits {
 public:
  [[nodiscard]] const models::TransducerModel* find(models::Structure structure) const {
    for (const auto& [s, m] : fits_) {
      if (s == structure) return &m;
    }
    return nullptr;
  }
  void keep(models::Structure structure, models::TransducerModel model) {
    fits_.emplace_back(structure, std::move(model));
  }

 private:
  std::vector<std::pair<models::Structure, models::TransducerModel>> fits_{};
};

struct ChannelData {
  std::string name;
  bool sensed{false};
  std::span<const double> recorded;
  std::vector<double> base;
  double coupling{0.0};                    // of the stress in the model's side
  std::span<const double> sensed_model{};  // the model's sensed response (electrostriction)
  bool affine{true};  // not the stress-hysteresis model: the response is G[x] + y0
  // The diagnosis replaced the model by a structure identified on this record, its loop too
  // (reidentified.hpp: reidentified_stress, or the model's structure with the stress's terms
  // undone, reidentified_stress_terms): a loop shape left over is that structure's own class,
  // so the generic loop candidates are not tried on it.
  bool loop_reidentified{false};
  // Shared by the channel's copies (the recording they read is the same).
  std::shared_ptr<FirstHalfFits> first_half{std::make_shared<FirstHalfFits>()};
};

// A channel's response to the drive alone, r = y - coupling T (y itself without a stress).
[[nodiscard]] std::vector<double> response_to_drive(std::span<const double> y, double coupling,
                                                    std::span<const double> stress);

// Non-finite model outputs (a rejected first sample) are held at the last finite value so no
// filter state sees them; the result marks the samples that were finite.
[[nodiscard]] std::vector<bool> hold_finite(std::vector<double>& y);

// The stress coupling of a side (its first linear gain), 0 without one.
[[nodiscard]] double coupling_of(const models::SideModel& side);
[[nodiscard]] double coupling_of(const std::optional<models::SideModel>& side);

}  // namespace selfsense::diagnosis::detail
