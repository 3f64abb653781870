// Hinges on plays: a piecewise-linear function of each play's output, added to a PI operator.
//
//   H[x] = sum_i w_i p_i[x] + sum_h c_h max(0, p_{r_h}[x] - b_h)
//
// A play of threshold r carries the relays of half-width r: the relay with switching fields
// alpha = b + r, beta = b - r is up exactly when p_r > b. Weighting each play's output by a
// piecewise-linear function of it is therefore a Preisach operator whose density is point
// masses in the half-width r and piecewise constant in the bias b = (alpha + beta) / 2
// (Mayergoyz's representation of the Preisach model through plays). A PI operator's minor
// loops of one amplitude have one shape wherever they sit; with hinges at levels b_h the
// loops change their shape with their offset, as those of real ceramics do. The output stays
// linear in the weights c_h, so identification stays a least-squares problem.
//
// Units: b_h has the unit of the input x, c_h that of the output per unit of x.
#pragma once

#include <string>
#include <vector>

namespace selfsense::operators {

struct PlayHinges {
  std::vector<double> thresholds{};  // r_h >= 0: the play each hinge reads (0: the input)
  std::vector<double> levels{};      // b_h, finite
  std::vector<double> weights{};     // c_h, finite (either sign)

  [[nodiscard]] bool empty() const noexcept { return thresholds.empty(); }
  [[nodiscard]] bool is_valid(std::string* why) const;
};

}  // namespace selfsense::operators
