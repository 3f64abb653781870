// The search for the physics a channel's model leaves out (docs/diagnose.md, "How"): rounds of
// every candidate fitted on the fitting blocks and judged on the held-out ones (held_out.hpp),
// the best significant one accepted and refitted jointly with those accepted before; then a
// local pass for transients. Pure math.
#pragma once

#include <vector>

#include "candidates.hpp"
#include "held_out.hpp"

namespace selfsense::diagnosis::detail {

// What the search reads: the channel, its correction signals, the recording, the rows, the
// drive's holds.
struct SearchInput {
  const ChannelData& ch;
  const identification::CorrectionSignals& cs;
  const Signals& s;
  const Rows& rows;
  const std::vector<Segment>& holds;
  bool has_sensor;
  bool charge_drive;
  const Options& options;
};

// The search's state on one channel: what has been accepted so far.
struct SearchState {
  std::vector<CorrectionTerm> accepted_terms{};
  ChannelCorrection accepted{};
  std::vector<double> current{};  // the output with the accepted corrections
  std::vector<const Candidate*> used{};
  double current_sse{0.0};      // on the held-out blocks
  double original_sse{0.0};     // of the model's own output there
  std::size_t rounds_named{0};  // findings of search_rounds (whole-record, held-out blocks)
  // The most a lag (delay or mode) explained of the held-out residual in the first round,
  // significant or not: the evidence that decides whether a delay is worth re-identifying.
  double lag_explains{0.0};
  // The mode (frequency and damping) of the first round's dynamics candidate, fitted or not: the
  // seed of the modes tried beside the delay.
  ChannelCorrection lag_mode{};
  // The dynamics block of a named correction with two modes or a direct path (the filters
  // alone): tried as it is beside the modes around lag_mode when the lag is re-identified.
  ChannelCorrection named_modes{};
  // In the first round a stress candidate explained more of the held-out residual than any
  // other candidate, and more than nothing, significant or not: where the rounds name nothing,
  // the evidence that the side is worth re-identifying with the stress's terms undone.
  bool stress_leads{false};
};

// Rounds of candidates until none is significant (or options.max_effects): findings appended.
void search_rounds(const SearchInput& in, SearchState& st, std::vector<Finding>& findings);

// Transients the block statistics cannot see (ringing after one fast step is a few samples of a
// long record): each strong residual segment not already explained is fitted on its own samples;
// a candidate is named when it removes most of the segment's residual with strong evidence for
// its extra parameters (BIC: n ln(SSE1/SSE0) + p ln n < -kLocalEvidence), and, refitted with
// the accepted terms on the fitting blocks, does not make the held-out blocks worse.
void local_pass(const SearchInput& in, SearchState& st, std::vector<Finding>& findings);

// A model identified on the same recording has absorbed what its own terms can imitate: its
// residual is orthogonal to them over the whole record, so any term near them, fitted on the
// fitting blocks, loses on the held-out ones. When nothing is named on a channel, each specific
// candidate is fitted beside a refit of the model's own loop (gain, offset, a PI operator of the
// drive) and judged against that refit alone on the held-out blocks (the same rules as a round);
// the best one that also beats the model as it stands is named, its correction carrying the
// refit.
void absorbed_pass(const SearchInput& in, SearchState& st, std::vector<Finding>& findings);

}  // namespace selfsense::diagnosis::detail
