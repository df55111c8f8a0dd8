#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include "tape_detail.h"
#include "zeroset/error.h"
#include "zeroset/expr/field.h"

namespace zeroset {
namespace detail {

void eval_uniforms(const Tape& tape, std::span<const double> params, std::vector<double>& out) {
  out.resize(tape.uniforms.size());
  for (std::size_t r = 0; r < tape.uniforms.size(); ++r) {
    const UniformInstr& u = tape.uniforms[r];
    switch (u.op) {
      case Op::kConst:
        out[r] = u.value;
        break;
      case Op::kParam:
        out[r] = params[static_cast<std::size_t>(u.a)];
        break;
      default:
        out[r] =
            apply(u.op, out[static_cast<std::size_t>(u.a)], out[static_cast<std::size_t>(u.b)]);
        break;
    }
  }
}

}  // namespace detail

namespace {

using detail::Code;

/// Points per block of the batched evaluation. Each instruction runs over a whole block before
/// the next one starts: the dispatch is paid once per block, the loops vectorize, and a block
/// of all live slots stays in the L1 cache.
constexpr int kBlock = 256;

// Element-wise loops over one block. `d` never aliases `a` or `b` (see Emitter), which the
// restrict qualifiers tell the compiler so that it vectorizes without run-time checks.
template <int N, class F>
inline void map1(double* __restrict d, const double* __restrict a, F f) {
#pragma GCC unroll 4
  for (int i = 0; i < N; ++i) d[i] = f(a[i]);
}
template <int N, class F>
inline void map2(double* __restrict d, const double* __restrict a, const double* __restrict b,
                 F f) {
#pragma GCC unroll 4
  for (int i = 0; i < N; ++i) d[i] = f(a[i], b[i]);
}
template <int N, class F>
inline void map3(double* __restrict d, const double* __restrict a, const double* __restrict b,
                 const double* __restrict c, F f) {
#pragma GCC unroll 4
  for (int i = 0; i < N; ++i) d[i] = f(a[i], b[i], c[i]);
}

/// Runs a program over N points whose x, y, z are in slots 0, 1, 2 (slot s holds
/// slots[s·N .. s·N + N)).
template <int N>
void run(const detail::Program& program, const double* uniforms, double* slots) {
  for (const detail::Instr& in : program.code) {
    double* d = slots + std::ptrdiff_t{in.dst} * N;
    const double* a = slots + std::ptrdiff_t{in.a} * N;
    switch (in.code) {
      case Code::kNeg:
        map1<N>(d, a, [](double v) { return -v; });
        break;
      case Code::kSquare:
        map1<N>(d, a, [](double v) { return v * v; });
        break;
      case Code::kSqrt:
        map1<N>(d, a, [](double v) { return std::sqrt(v); });
        break;
      case Code::kExp:
        map1<N>(d, a, [](double v) { return std::exp(v); });
        break;
      case Code::kLog:
        map1<N>(d, a, [](double v) { return std::log(v); });
        break;
      case Code::kSin:
        map1<N>(d, a, [](double v) { return std::sin(v); });
        break;
      case Code::kCos:
        map1<N>(d, a, [](double v) { return std::cos(v); });
        break;
      case Code::kTan:
        map1<N>(d, a, [](double v) { return std::tan(v); });
        break;
      case Code::kAbs:
        map1<N>(d, a, [](double v) { return std::abs(v); });
        break;
      case Code::kSign:
        map1<N>(d, a, [](double v) { return detail::sign(v); });
        break;
      case Code::kAdd:
        map2<N>(d, a, slots + std::ptrdiff_t{in.b} * N, [](double p, double q) { return p + q; });
        break;
      case Code::kSub:
        map2<N>(d, a, slots + std::ptrdiff_t{in.b} * N, [](double p, double q) { return p - q; });
        break;
      case Code::kMul:
        map2<N>(d, a, slots + std::ptrdiff_t{in.b} * N, [](double p, double q) { return p * q; });
        break;
      case Code::kDiv:
        map2<N>(d, a, slots + std::ptrdiff_t{in.b} * N, [](double p, double q) { return p / q; });
        break;
      case Code::kAddU: {
        const double u = uniforms[in.b];
        map1<N>(d, a, [u](double v) { return v + u; });
        break;
      }
      case Code::kSubVU: {
        const double u = uniforms[in.b];
        map1<N>(d, a, [u](double v) { return v - u; });
        break;
      }
      case Code::kSubUV: {
        const double u = uniforms[in.b];
        map1<N>(d, a, [u](double v) { return u - v; });
        break;
      }
      case Code::kMulU: {
        const double u = uniforms[in.b];
        map1<N>(d, a, [u](double v) { return v * u; });
        break;
      }
      case Code::kDivVU: {
        const double u = uniforms[in.b];
        map1<N>(d, a, [u](double v) { return v / u; });
        break;
      }
      case Code::kDivUV: {
        const double u = uniforms[in.b];
        map1<N>(d, a, [u](double v) { return u / v; });
        break;
      }
      case Code::kMulAdd:
        map3<N>(d, a, slots + std::ptrdiff_t{in.b} * N, slots + std::ptrdiff_t{in.c} * N,
                [](double p, double q, double r) { return p * q + r; });
        break;
      case Code::kMulSub:
        map3<N>(d, a, slots + std::ptrdiff_t{in.b} * N, slots + std::ptrdiff_t{in.c} * N,
                [](double p, double q, double r) { return p * q - r; });
        break;
      case Code::kSubMul:
        map3<N>(d, a, slots + std::ptrdiff_t{in.b} * N, slots + std::ptrdiff_t{in.c} * N,
                [](double p, double q, double r) { return r - p * q; });
        break;
      case Code::kMulUAdd: {
        const double u = uniforms[in.b];
        map2<N>(d, a, slots + std::ptrdiff_t{in.c} * N,
                [u](double p, double r) { return p * u + r; });
        break;
      }
      case Code::kMulUSub: {
        const double u = uniforms[in.b];
        map2<N>(d, a, slots + std::ptrdiff_t{in.c} * N,
                [u](double p, double r) { return p * u - r; });
        break;
      }
      case Code::kSubMulU: {
        const double u = uniforms[in.b];
        map2<N>(d, a, slots + std::ptrdiff_t{in.c} * N,
                [u](double p, double r) { return r - p * u; });
        break;
      }
      case Code::kPowU: {
        // The exponent is the same for the whole block: decide exact or not once.
        const double u = uniforms[in.b];
        if (detail::is_exact_exponent(u)) {
          const auto n = static_cast<std::int64_t>(u);
          map1<N>(d, a, [n](double v) { return detail::int_pow(v, n); });
        } else {
          map1<N>(d, a, [u](double v) { return std::pow(v, u); });
        }
        break;
      }
    }
  }
}

/// Output `ref` of a program run on one point: a slot or a uniform register.
inline double output(std::int32_t ref, const double* slots, const double* uniforms) {
  return ref >= 0 ? slots[ref] : uniforms[~ref];
}

void check_lengths(std::size_t n, std::initializer_list<std::size_t> others) {
  for (const std::size_t m : others)
    if (m != n)
      throw InvalidArgument(
          "batched evaluation: every coordinate and output span must have "
          "the same length");
}

}  // namespace

struct Evaluator::Scratch {
  std::vector<double> uniforms;  ///< uniform registers for the current parameter values
  std::vector<double> block;     ///< slots of one block, kBlock values per slot
  std::vector<double> single;    ///< slots of one point
};

Evaluator::Evaluator(const Field& field) : scratch_(std::make_unique<Scratch>()) { reset(field); }

Evaluator::~Evaluator() = default;
Evaluator::Evaluator(Evaluator&&) noexcept = default;
Evaluator& Evaluator::operator=(Evaluator&&) noexcept = default;

void Evaluator::reset(const Field& field) {
  field.require_parameters();
  field_ = field;
  const detail::Tape& tape = field_.tape();
  detail::eval_uniforms(tape, field_.parameter_values(), scratch_->uniforms);
  const int slots =
      std::max({tape.value.slot_count, tape.gradient.slot_count, tape.full.slot_count});
  scratch_->block.assign(static_cast<std::size_t>(slots) * kBlock, 0.0);
  scratch_->single.assign(static_cast<std::size_t>(slots), 0.0);
}

void Evaluator::set_parameter(int index, double value) {
  field_.set_parameter(index, value);
  detail::eval_uniforms(field_.tape(), field_.parameter_values(), scratch_->uniforms);
}

double Evaluator::value(const Vec3& p) {
  double* s = scratch_->single.data();
  s[0] = p.x();
  s[1] = p.y();
  s[2] = p.z();
  const detail::Program& program = field_.tape().value;
  run<1>(program, scratch_->uniforms.data(), s);
  return output(program.outputs[0], s, scratch_->uniforms.data());
}

double Evaluator::value_gradient(const Vec3& p, Vec3& gradient) {
  double* s = scratch_->single.data();
  s[0] = p.x();
  s[1] = p.y();
  s[2] = p.z();
  const detail::Program& program = field_.tape().gradient;
  const double* u = scratch_->uniforms.data();
  run<1>(program, u, s);
  for (int k = 0; k < 3; ++k)
    gradient[k] = output(program.outputs[static_cast<std::size_t>(1 + k)], s, u);
  return output(program.outputs[0], s, u);
}

FieldSample Evaluator::sample(const Vec3& p, Derivatives what) {
  const bool hessian = includes(what, Derivatives::kHessian);
  const bool parameter_derivatives = includes(what, Derivatives::kParameters);
  double* s = scratch_->single.data();
  s[0] = p.x();
  s[1] = p.y();
  s[2] = p.z();
  const detail::Tape& tape = field_.tape();
  const detail::Program& program = hessian || parameter_derivatives ? tape.full : tape.gradient;
  const double* u = scratch_->uniforms.data();
  run<1>(program, u, s);
  auto out = [&](int k) { return output(program.outputs[static_cast<std::size_t>(k)], s, u); };
  FieldSample result;
  result.value = out(0);
  result.gradient = {out(1), out(2), out(3)};
  if (hessian) {
    const int h = detail::kFullHessian;
    result.hessian << out(h), out(h + 1), out(h + 2),  //
        out(h + 1), out(h + 3), out(h + 4),            //
        out(h + 2), out(h + 4), out(h + 5);
  }
  if (parameter_derivatives) {
    result.dq.resize(tape.parameters.size());
    for (std::size_t k = 0; k < result.dq.size(); ++k)
      result.dq[k] = out(detail::kFullParams + static_cast<int>(k));
  }
  return result;
}

namespace {

/// Copies points [start, start + count) into slots 0, 1, 2 of a block. A partial last block
/// repeats its last point, so the padding raises no floating-point exception of its own.
void load_block(std::span<const double> x, std::span<const double> y, std::span<const double> z,
                std::size_t start, int count, double* slots) {
  const std::span<const double> coords[3] = {x, y, z};
  for (int axis = 0; axis < 3; ++axis) {
    double* dst = slots + std::ptrdiff_t{axis} * kBlock;
    const double* src = coords[axis].data() + start;
    std::copy(src, src + count, dst);
    std::fill(dst + count, dst + kBlock, src[count - 1]);
  }
}

/// Copies output `ref` of a block (a slot, or a uniform register) to dst[0, count).
void store_block(std::int32_t ref, const double* slots, const double* uniforms, int count,
                 double* dst) {
  if (ref >= 0) {
    const double* src = slots + std::ptrdiff_t{ref} * kBlock;
    std::copy(src, src + count, dst);
  } else {
    std::fill(dst, dst + count, uniforms[~ref]);
  }
}

}  // namespace

namespace {

/// Runs `program` over the points (x, y, z) a block at a time, copying output k of point i to
/// dst[i] for every (k, dst) of `outputs`.
void run_batched(const detail::Program& program, const double* u, double* s,
                 std::span<const double> x, std::span<const double> y, std::span<const double> z,
                 std::initializer_list<std::pair<int, double*>> outputs) {
  for (std::size_t start = 0; start < x.size(); start += kBlock) {
    const int count = static_cast<int>(std::min<std::size_t>(kBlock, x.size() - start));
    load_block(x, y, z, start, count, s);
    run<kBlock>(program, u, s);
    for (const auto& [k, dst] : outputs)
      store_block(program.outputs[static_cast<std::size_t>(k)], s, u, count, dst + start);
  }
}

}  // namespace

void Evaluator::values(std::span<const double> x, std::span<const double> y,
                       std::span<const double> z, std::span<double> out) {
  check_lengths(x.size(), {y.size(), z.size(), out.size()});
  run_batched(field_.tape().value, scratch_->uniforms.data(), scratch_->block.data(), x, y, z,
              {{0, out.data()}});
}

void Evaluator::values_gradients(std::span<const double> x, std::span<const double> y,
                                 std::span<const double> z, std::span<double> value,
                                 std::span<double> gx, std::span<double> gy, std::span<double> gz) {
  check_lengths(x.size(), {y.size(), z.size(), value.size(), gx.size(), gy.size(), gz.size()});
  run_batched(field_.tape().gradient, scratch_->uniforms.data(), scratch_->block.data(), x, y, z,
              {{0, value.data()}, {1, gx.data()}, {2, gy.data()}, {3, gz.data()}});
}

void Evaluator::values_gradients_hessians(std::span<const double> x, std::span<const double> y,
                                          std::span<const double> z, std::span<double> value,
                                          std::span<double> gx, std::span<double> gy,
                                          std::span<double> gz,
                                          const std::array<std::span<double>, 6>& hessian) {
  check_lengths(x.size(), {y.size(), z.size(), value.size(), gx.size(), gy.size(), gz.size(),
                           hessian[0].size(), hessian[1].size(), hessian[2].size(),
                           hessian[3].size(), hessian[4].size(), hessian[5].size()});
  const int h = detail::kFullHessian;
  run_batched(field_.tape().full, scratch_->uniforms.data(), scratch_->block.data(), x, y, z,
              {{0, value.data()},
               {1, gx.data()},
               {2, gy.data()},
               {3, gz.data()},
               {h, hessian[0].data()},
               {h + 1, hessian[1].data()},
               {h + 2, hessian[2].data()},
               {h + 3, hessian[3].data()},
               {h + 4, hessian[4].data()},
               {h + 5, hessian[5].data()}});
}

}  // namespace zeroset
