#include "zeroset/expr/field.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "tape_detail.h"
#include "zeroset/error.h"
#include "zeroset/expr/parse.h"
#include "zeroset/expr/polynomial.h"

namespace zeroset {
namespace {

const Field& zero_field() {
  static const Field zero = compile_field("0");
  return zero;
}

std::string join(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

/// Expands the value program over sparse polynomials. A term's exponents (i, j, k) are packed
/// as the offset (i·(D+1) + j)·(D+1) + k, D the total degree: the offset of a product of two
/// terms is the sum of their offsets, so multiplication needs no unpacking.
class Expander {
 public:
  using Terms = std::vector<std::pair<std::int64_t, double>>;  // sorted by offset

  Expander(const detail::Tape& tape, std::span<const double> uniforms)
      : tape_(tape),
        uniforms_(uniforms),
        side_(tape.degree + 1),
        dense_(static_cast<std::size_t>(side_) * side_ * side_, 0.0),
        touched_(dense_.size(), 0) {}

  Polynomial run() {
    const detail::Program& p = tape_.value;
    std::vector<Terms> slots(static_cast<std::size_t>(p.slot_count));
    for (int axis = 0; axis < detail::kInputSlots; ++axis) {
      const std::int64_t stride = axis == 0 ? std::int64_t{side_} * side_ : axis == 1 ? side_ : 1;
      slots[static_cast<std::size_t>(axis)] = {{stride, 1.0}};
    }
    for (const detail::Instr& in : p.code) {
      const Terms& a = slots[static_cast<std::size_t>(in.a)];
      Terms result;
      switch (in.code) {
        case detail::Code::kNeg:
          result = scaled(a, -1.0);
          break;
        case detail::Code::kSquare:
          result = product(a, a);
          break;
        case detail::Code::kAdd:
          result = combined(a, slots[static_cast<std::size_t>(in.b)], 1);
          break;
        case detail::Code::kSub:
          result = combined(a, slots[static_cast<std::size_t>(in.b)], -1);
          break;
        case detail::Code::kMul:
          result = product(a, slots[static_cast<std::size_t>(in.b)]);
          break;
        case detail::Code::kAddU:
          result = combined(a, {{0, uniform(in.b)}}, 1);
          break;
        case detail::Code::kSubVU:
          result = combined(a, {{0, uniform(in.b)}}, -1);
          break;
        case detail::Code::kSubUV:
          result = combined({{0, uniform(in.b)}}, a, -1);
          break;
        case detail::Code::kMulU:
          result = scaled(a, uniform(in.b));
          break;
        case detail::Code::kDivVU:
          result = scaled(a, 1.0 / uniform(in.b));
          break;
        case detail::Code::kMulAdd:
        case detail::Code::kMulSub:
        case detail::Code::kSubMul:
        case detail::Code::kMulUAdd:
        case detail::Code::kMulUSub:
        case detail::Code::kSubMulU:
          result = fused(in, slots);
          break;
        default:
          ZS_ASSERT(!"a polynomial tape has only ring operations");
      }
      slots[static_cast<std::size_t>(in.dst)] = std::move(result);
    }
    const std::int32_t out = p.outputs[0];
    const Terms f = out >= 0 ? slots[static_cast<std::size_t>(out)] : Terms{{0, uniform(~out)}};
    std::vector<Monomial> monomials;
    monomials.reserve(f.size());
    for (const auto& [offset, c] : f) {
      const auto s = static_cast<std::int64_t>(side_);
      monomials.push_back({static_cast<int>(offset / (s * s)), static_cast<int>(offset / s % s),
                           static_cast<int>(offset % s), c});
    }
    return Polynomial(std::move(monomials));
  }

 private:
  double uniform(std::int32_t r) const { return uniforms_[static_cast<std::size_t>(r)]; }

  /// a·b ± c for the fused codes.
  Terms fused(const detail::Instr& in, const std::vector<Terms>& slots) {
    using detail::Code;
    const Terms& a = slots[static_cast<std::size_t>(in.a)];
    const Terms& c = slots[static_cast<std::size_t>(in.c)];
    const bool by_uniform =
        in.code == Code::kMulUAdd || in.code == Code::kMulUSub || in.code == Code::kSubMulU;
    const Terms ab =
        by_uniform ? scaled(a, uniform(in.b)) : product(a, slots[static_cast<std::size_t>(in.b)]);
    if (in.code == Code::kMulAdd || in.code == Code::kMulUAdd) return combined(ab, c, 1);
    if (in.code == Code::kMulSub || in.code == Code::kMulUSub) return combined(ab, c, -1);
    return combined(c, ab, -1);
  }

  static Terms scaled(const Terms& a, double s) {
    Terms r = a;
    for (auto& t : r) t.second *= s;
    return r;
  }

  static Terms combined(const Terms& a, const Terms& b, double sign) {
    Terms r;
    r.reserve(a.size() + b.size());
    std::size_t i = 0, j = 0;
    while (i < a.size() || j < b.size()) {
      if (j == b.size() || (i < a.size() && a[i].first < b[j].first)) {
        r.push_back(a[i++]);
      } else if (i == a.size() || b[j].first < a[i].first) {
        r.emplace_back(b[j].first, sign * b[j].second);
        ++j;
      } else {
        r.emplace_back(a[i].first, a[i].second + sign * b[j].second);
        ++i, ++j;
      }
    }
    return r;
  }

  Terms product(const Terms& a, const Terms& b) {
    std::vector<std::int64_t> offsets;
    for (const auto& [oa, ca] : a) {
      for (const auto& [ob, cb] : b) {
        const auto o = static_cast<std::size_t>(oa + ob);
        if (touched_[o] == 0) {
          touched_[o] = 1;
          offsets.push_back(oa + ob);
        }
        dense_[o] += ca * cb;
      }
    }
    std::sort(offsets.begin(), offsets.end());
    Terms r;
    r.reserve(offsets.size());
    for (const std::int64_t o : offsets) {
      const auto i = static_cast<std::size_t>(o);
      r.emplace_back(o, dense_[i]);
      dense_[i] = 0;
      touched_[i] = 0;
    }
    return r;
  }

  const detail::Tape& tape_;
  std::span<const double> uniforms_;
  int side_;
  std::vector<double> dense_;  ///< accumulator for products, zero between uses
  std::vector<char> touched_;
};

}  // namespace

Field::Field() : Field(zero_field()) {}

Field::Field(std::shared_ptr<const detail::Tape> tape)
    : tape_(std::move(tape)),
      params_(tape_->parameters.size(), std::numeric_limits<double>::quiet_NaN()) {}

const std::vector<std::string>& Field::parameter_names() const { return tape_->parameters; }

int Field::parameter_index(std::string_view name) const {
  const auto it = tape_->parameter_indices.find(std::string(name));
  return it == tape_->parameter_indices.end() ? -1 : it->second;
}

void check_parameter_value(std::string_view name, double value) {
  if (!std::isfinite(value))
    throw InvalidArgument(std::string(name), fmt::format("{}", value),
                          "a parameter value must be finite");
  if (std::abs(value) > kMaxParameterMagnitude)
    throw InvalidArgument(std::string(name), fmt::format("{}", value),
                          fmt::format("a parameter value must lie in [-{:g}, {:g}]",
                                      kMaxParameterMagnitude, kMaxParameterMagnitude));
}

void Field::set_parameter(std::string_view name, double value) {
  const int index = parameter_index(name);
  if (index < 0) {
    const std::string has = tape_->parameters.empty()
                                ? "the surface has no parameters"
                                : "its parameters are " + join(tape_->parameters);
    throw InvalidArgument(std::string(name), fmt::format("{}", value),
                          "the surface has no parameter of that name (" + has + ")");
  }
  set_parameter(index, value);
}

void Field::set_parameter(int index, double value) {
  if (index < 0 || static_cast<std::size_t>(index) >= params_.size())
    throw InvalidArgument(fmt::format("parameter index {} is out of range (the surface has {})",
                                      index, params_.size()));
  check_parameter_value(tape_->parameters[static_cast<std::size_t>(index)], value);
  params_[static_cast<std::size_t>(index)] = value;
}

void Field::set_parameters(const std::map<std::string, double>& values) {
  for (const auto& [name, value] : values) set_parameter(name, value);
}

std::vector<std::string> Field::missing_parameters() const {
  std::vector<std::string> missing;
  for (std::size_t k = 0; k < params_.size(); ++k)
    if (std::isnan(params_[k])) missing.push_back(tape_->parameters[k]);
  return missing;
}

void Field::require_parameters() const {
  const std::vector<std::string> missing = missing_parameters();
  if (missing.empty()) return;
  if (missing.size() == 1)
    throw InvalidArgument(fmt::format(
        "missing value for parameter {0}; give it with --param {0}=... (or in the scene file)",
        missing[0]));
  throw InvalidArgument(fmt::format(
      "missing value for parameters {}; give them with --param {}=... (or in the scene file)",
      join(missing), missing[0]));
}

bool Field::is_polynomial() const { return tape_->degree >= 0; }

int Field::degree() const { return tape_->degree; }

bool Field::depends_on_position() const {
  // The compiler keeps what does not vary with x, y, z in uniform registers (negative refs).
  return tape_->value.outputs.empty() || tape_->value.outputs[0] >= 0;
}

bool Field::is_expandable() const {
  return is_polynomial() && tape_->degree <= kMaxExpansionDegree;
}

Polynomial Field::polynomial() const {
  if (!is_polynomial())
    throw BadInput("the surface '" + tape_->expression + "' is not a polynomial in x, y, z");
  if (tape_->degree > kMaxExpansionDegree)
    throw BadInput(
        fmt::format("the surface has degree {}; polynomials are expanded only up to "
                    "degree {}",
                    tape_->degree, kMaxExpansionDegree));
  require_parameters();
  std::vector<double> uniforms;
  detail::eval_uniforms(*tape_, params_, uniforms);
  return Expander(*tape_, uniforms).run();
}

const std::string& Field::source() const { return tape_->source; }

std::string Field::expression_string() const { return tape_->expression; }

}  // namespace zeroset
