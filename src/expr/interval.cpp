#include "zeroset/expr/interval.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "tape_detail.h"

namespace zeroset::detail {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr Interval kEmpty{kInf, -kInf};
constexpr Interval kEntire{-kInf, kInf};

// libm's functions are faithful to an ulp or two; arithmetic rounds to nearest. Widening
// every result by 4 ulps (relative) plus the smallest normal keeps a true enclosure.
inline double down(double v) {
  return v - (std::abs(v) * 4 * std::numeric_limits<double>::epsilon() +
              std::numeric_limits<double>::min());
}
inline double up(double v) {
  return v + (std::abs(v) * 4 * std::numeric_limits<double>::epsilon() +
              std::numeric_limits<double>::min());
}
inline Interval outward(double lo, double hi) {
  // A NaN end (inf - inf, 0 · inf) means the bound is unknown: open it up.
  if (std::isnan(lo)) lo = -kInf;
  if (std::isnan(hi)) hi = kInf;
  return {down(lo), up(hi)};
}

Interval mul(Interval a, Interval b) {
  const double p[4] = {a.lo * b.lo, a.lo * b.hi, a.hi * b.lo, a.hi * b.hi};
  double lo = p[0], hi = p[0];
  for (double v : p) {
    if (std::isnan(v)) return kEntire;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  return outward(lo, hi);
}

Interval square(Interval a) {
  const double l = a.lo * a.lo, h = a.hi * a.hi;
  if (a.contains_zero()) return {0, up(std::max(l, h))};
  return outward(std::min(l, h), std::max(l, h));
}

Interval reciprocal(Interval a) {
  if (a.lo == 0 && a.hi == 0) return kEmpty;
  if (a.contains_zero()) return kEntire;
  return outward(1 / a.hi, 1 / a.lo);
}

Interval int_power(Interval a, long long n) {
  if (n == 0) return {1, 1};
  if (n < 0) return reciprocal(int_power(a, -n));
  const double l = int_pow(a.lo, n), h = int_pow(a.hi, n);
  if (n % 2 == 1) return outward(l, h);
  if (a.contains_zero()) return {0, up(std::max(l, h))};
  return outward(std::min(l, h), std::max(l, h));
}

Interval power(Interval a, double u) {
  if (is_exact_exponent(u)) return int_power(a, static_cast<long long>(u));
  // Non-integer exponent: defined for a ≥ 0 only; monotone there.
  const double lo = std::max(a.lo, 0.0);
  if (lo > a.hi) return kEmpty;
  const double l = std::pow(lo, u), h = std::pow(a.hi, u);
  return outward(std::min(l, h), std::max(l, h));
}

/// Does [lo, hi] contain phase + 2kπ for some integer k?
bool contains_phase(double lo, double hi, double phase) {
  const double two_pi = 2 * std::numbers::pi;
  const double k = std::ceil((lo - phase) / two_pi);
  return phase + k * two_pi <= hi;
}

Interval sine_like(Interval a, double max_phase, double (*f)(double)) {
  if (!(a.hi - a.lo < 2 * std::numbers::pi)) return {-1, 1};
  const double fl = f(a.lo), fh = f(a.hi);
  double lo = std::min(fl, fh), hi = std::max(fl, fh);
  if (contains_phase(a.lo, a.hi, max_phase)) hi = 1;
  if (contains_phase(a.lo, a.hi, max_phase + std::numbers::pi)) lo = -1;
  const Interval r = outward(lo, hi);
  return {std::max(r.lo, -1.0), std::min(r.hi, 1.0)};
}

double sin_fn(double v) { return std::sin(v); }
double cos_fn(double v) { return std::cos(v); }

Interval tangent(Interval a) {
  // A pole π/2 + kπ inside the interval makes it unbounded.
  if (!(a.hi - a.lo < std::numbers::pi) ||
      std::floor((a.lo - std::numbers::pi / 2) / std::numbers::pi) !=
          std::floor((a.hi - std::numbers::pi / 2) / std::numbers::pi))
    return kEntire;
  return outward(std::tan(a.lo), std::tan(a.hi));
}

Interval apply_interval(Code code, Interval a, Interval b) {
  if (a.is_empty() || b.is_empty()) return kEmpty;
  switch (code) {
    case Code::kNeg:
      return {-a.hi, -a.lo};
    case Code::kSquare:
      return square(a);
    case Code::kSqrt:
      if (a.hi < 0) return kEmpty;
      return {std::max(0.0, down(std::sqrt(std::max(a.lo, 0.0)))), up(std::sqrt(a.hi))};
    case Code::kExp:
      return {std::max(0.0, down(std::exp(a.lo))), up(std::exp(a.hi))};
    case Code::kLog:
      if (a.hi < 0) return kEmpty;
      return {a.lo <= 0 ? -kInf : down(std::log(a.lo)), up(std::log(a.hi))};
    case Code::kSin:
      return sine_like(a, std::numbers::pi / 2, sin_fn);
    case Code::kCos:
      return sine_like(a, 0.0, cos_fn);
    case Code::kTan:
      return tangent(a);
    case Code::kAbs:
      if (a.contains_zero()) return {0, std::max(-a.lo, a.hi)};
      return a.lo > 0 ? a : Interval{-a.hi, -a.lo};
    case Code::kSign:
      return {sign(a.lo), sign(a.hi)};
    case Code::kAdd:
    case Code::kAddU:
      return outward(a.lo + b.lo, a.hi + b.hi);
    case Code::kSub:
    case Code::kSubVU:
    case Code::kSubUV:
      return outward(a.lo - b.hi, a.hi - b.lo);
    case Code::kMul:
    case Code::kMulU:
      return mul(a, b);
    case Code::kDiv:
    case Code::kDivVU:
    case Code::kDivUV:
      return mul(a, reciprocal(b));
    case Code::kPowU:
      return power(a, b.lo);
    case Code::kMulAdd:
    case Code::kMulSub:
    case Code::kSubMul:
    case Code::kMulUAdd:
    case Code::kMulUSub:
    case Code::kSubMulU:
      break;  // three operands: see IntervalEvaluator::eval
  }
  return kEntire;
}

}  // namespace
}  // namespace zeroset::detail

namespace zeroset {

using detail::apply_interval;
using detail::Code;
using detail::Instr;
using detail::Program;

IntervalEvaluator::IntervalEvaluator(const Field& field) : field_(field), tape_(&field_.tape()) {
  field_.require_parameters();
  detail::eval_uniforms(*tape_, field_.parameter_values(), uniforms_);
  slots_.resize(static_cast<size_t>(std::max(tape_->value.slot_count, tape_->gradient.slot_count)));
}

Interval IntervalEvaluator::output(const Program& p, size_t i) const {
  const std::int32_t out = p.outputs.at(i);
  if (out >= 0) return slots_[static_cast<size_t>(out)];
  const double u = uniforms_[static_cast<size_t>(~out)];
  return {u, u};
}

Interval IntervalEvaluator::eval(const Interval& x, const Interval& y, const Interval& z) {
  run(tape_->value, x, y, z);
  return output(tape_->value, 0);
}

void IntervalEvaluator::eval_gradient(const Interval& x, const Interval& y, const Interval& z,
                                      Interval out[4]) {
  run(tape_->gradient, x, y, z);
  for (size_t i = 0; i < 4; ++i) out[i] = output(tape_->gradient, i);
}

void IntervalEvaluator::run(const Program& p, const Interval& x, const Interval& y,
                            const Interval& z) {
  slots_[0] = x;
  slots_[1] = y;
  slots_[2] = z;
  auto uniform = [&](std::int32_t r) {
    const double u = uniforms_[static_cast<size_t>(r)];
    return Interval{u, u};
  };
  for (const Instr& in : p.code) {
    const Interval a = slots_[static_cast<size_t>(in.a)];
    Interval b{0, 0};
    switch (in.code) {
      case Code::kAdd:
      case Code::kSub:
      case Code::kMul:
      case Code::kDiv:
        b = slots_[static_cast<size_t>(in.b)];
        break;
      case Code::kAddU:
      case Code::kSubVU:
      case Code::kMulU:
      case Code::kDivVU:
      case Code::kPowU:
        b = uniform(in.b);
        break;
      case Code::kMulAdd:
      case Code::kMulSub:
      case Code::kSubMul:
      case Code::kMulUAdd:
      case Code::kMulUSub:
      case Code::kSubMulU: {
        // Fused product and sum: enclosed as the two operations it stands for.
        const bool uniform_factor =
            in.code == Code::kMulUAdd || in.code == Code::kMulUSub || in.code == Code::kSubMulU;
        const Interval p = apply_interval(
            Code::kMul, a, uniform_factor ? uniform(in.b) : slots_[static_cast<size_t>(in.b)]);
        const Interval c = slots_[static_cast<size_t>(in.c)];
        Interval r;
        if (in.code == Code::kMulAdd || in.code == Code::kMulUAdd)
          r = apply_interval(Code::kAdd, p, c);
        else if (in.code == Code::kMulSub || in.code == Code::kMulUSub)
          r = apply_interval(Code::kSub, p, c);
        else
          r = apply_interval(Code::kSub, c, p);
        slots_[static_cast<size_t>(in.dst)] = r;
        continue;
      }
      case Code::kSubUV:
      case Code::kDivUV: {
        // u - a and u / a: the uniform is the left operand.
        const Interval u = uniform(in.b);
        slots_[static_cast<size_t>(in.dst)] =
            apply_interval(in.code == Code::kSubUV ? Code::kSub : Code::kDiv, u, a);
        continue;
      }
      default:
        break;
    }
    slots_[static_cast<size_t>(in.dst)] = apply_interval(in.code, a, b);
  }
}

}  // namespace zeroset
