#pragma once
// Interval arithmetic over a field's tape: an enclosure of F over an axis-aligned box, used to
// ray cast expressions that are not polynomials. Private to the render module.
#include <span>
#include <vector>

#include "zeroset/expr/field.h"

namespace zeroset::detail {

struct Tape;
struct Program;

/// A closed interval [lo, hi]; empty when lo > hi (where F is undefined, e.g. sqrt of a
/// negative range). Infinite ends are allowed.
struct Interval {
  double lo = 0;
  double hi = 0;
  bool is_empty() const { return !(lo <= hi); }
  bool contains_zero() const { return lo <= 0 && hi >= 0; }
};

/// Evaluates the value program of a field's tape on intervals. Every operation rounds
/// outwards by a few ulps, so the result encloses F over the box despite rounding.
/// Owns scratch memory: one per thread.
class IntervalEvaluator {
 public:
  /// Throws InvalidArgument when a parameter has no value.
  explicit IntervalEvaluator(const Field& field);
  /// An enclosure of F over the box x × y × z.
  Interval eval(const Interval& x, const Interval& y, const Interval& z);
  /// Enclosures of F, ∂F/∂x, ∂F/∂y, ∂F/∂z over the box (the tape's gradient program).
  void eval_gradient(const Interval& x, const Interval& y, const Interval& z, Interval out[4]);

 private:
  void run(const Program& p, const Interval& x, const Interval& y, const Interval& z);
  Interval output(const Program& p, size_t i) const;

  Field field_;  // keeps the tape alive
  const Tape* tape_;
  std::vector<double> uniforms_;
  std::vector<Interval> slots_;
};

}  // namespace zeroset::detail
