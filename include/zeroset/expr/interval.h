#pragma once
/// Interval arithmetic over a field's tape: an enclosure of F (and of ∇F) over an axis-aligned
/// box. The ray caster uses it for expressions that are not polynomials.
#include <cstddef>
#include <vector>

#include "zeroset/expr/field.h"

namespace zeroset {

namespace detail {
struct Program;
}  // namespace detail

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
  void run(const detail::Program& p, const Interval& x, const Interval& y, const Interval& z);
  Interval output(const detail::Program& p, size_t i) const;

  Field field_;  // keeps the tape alive
  const detail::Tape* tape_;
  std::vector<double> uniforms_;
  std::vector<Interval> slots_;
};

}  // namespace zeroset
