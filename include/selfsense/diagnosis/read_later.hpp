// A delay undone offline, so a channel sampled late can be re-identified without it
// (reidentified.cpp): the record read `samples` later,
//   v[k] = x(k + samples),
// between samples by the cubic Lagrange interpolator through x[i-1], x[i], x[i+1], x[i+2]
// (i = floor(k + samples), t = k + samples - i in [0, 1); models/cubic_read.hpp), linear where
// a neighbour falls outside the record, the last sample held beyond it.
// Why cubic: a linear read low-passes what it reads, which the side identified on the record
// takes in; the delay stage then smooths it once more, so a sub-sample delay re-identified on a
// linear read carried twice the interpolation error to fast excitation (development draw
// 900003: docs/diagnose.md, "A delay the rounds named, carried by the side identified with it").
// Not causal: the whole record at once.
#pragma once

#include <span>
#include <vector>

namespace selfsense::diagnosis {

// samples >= 0 (a negative or non-finite count reads the record as it is).
[[nodiscard]] std::vector<double> read_later(std::span<const double> x, double samples);

}  // namespace selfsense::diagnosis
