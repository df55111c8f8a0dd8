#pragma once
// The compiled form of a field: operations with their scalar semantics, and the flat SSA tape
// that Field shares and Evaluator runs. Private to the expr module.
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

namespace zeroset::detail {

/// Operations of the expression graph. Leaves first, then unary, then binary.
enum class Op : std::uint8_t {
  kConst,
  kX,
  kY,
  kZ,
  kParam,
  kNeg,
  kSquare,
  kSqrt,
  kExp,
  kLog,
  kSin,
  kCos,
  kTan,
  kAbs,
  kSign,
  kAdd,
  kSub,
  kMul,
  kDiv,
  kPow,  ///< exponent independent of x, y, z; a varying exponent is rewritten as exp(b·log a)
};

/// Integer exponents up to this magnitude are evaluated by repeated multiplication (exact for
/// small results, and the right sign for negative bases); larger ones go to std::pow.
inline constexpr double kMaxExactExponent = 1 << 20;

/// a^n by binary powering (square and multiply), n of any sign.
inline double int_pow(double a, std::int64_t n) {
  const bool invert = n < 0;
  std::uint64_t m = invert ? static_cast<std::uint64_t>(-n) : static_cast<std::uint64_t>(n);
  double result = 1.0;
  while (m != 0) {
    if (m & 1U) result *= a;
    m >>= 1U;
    if (m != 0) a *= a;
  }
  return invert ? 1.0 / result : result;
}

/// True when b is an integer small enough for int_pow.
inline bool is_exact_exponent(double b) {
  return b == std::trunc(b) && std::abs(b) <= kMaxExactExponent;
}

/// The language's power: exact repeated multiplication for integer exponents (so (-2)^3 = -8),
/// std::pow otherwise (NaN for a negative base and a non-integer exponent).
inline double power(double a, double b) {
  return is_exact_exponent(b) ? int_pow(a, static_cast<std::int64_t>(b)) : std::pow(a, b);
}

/// sign(a) ∈ {-1, 0, 1}, NaN for NaN: the derivative of |a|.
inline double sign(double a) { return a > 0 ? 1.0 : (a < 0 ? -1.0 : a); }

/// Scalar semantics of every non-leaf operation (b is ignored by unary ones). Constant folding
/// and the evaluator both use it, so folded and evaluated results agree bit for bit.
inline double apply(Op op, double a, double b) {
  switch (op) {
    case Op::kNeg:
      return -a;
    case Op::kSquare:
      return a * a;
    case Op::kSqrt:
      return std::sqrt(a);
    case Op::kExp:
      return std::exp(a);
    case Op::kLog:
      return std::log(a);
    case Op::kSin:
      return std::sin(a);
    case Op::kCos:
      return std::cos(a);
    case Op::kTan:
      return std::tan(a);
    case Op::kAbs:
      return std::abs(a);
    case Op::kSign:
      return sign(a);
    case Op::kAdd:
      return a + b;
    case Op::kSub:
      return a - b;
    case Op::kMul:
      return a * b;
    case Op::kDiv:
      return a / b;
    case Op::kPow:
      return power(a, b);
    case Op::kConst:
    case Op::kX:
    case Op::kY:
    case Op::kZ:
    case Op::kParam:
      break;
  }
  return std::nan("");
}

inline bool is_unary(Op op) { return op >= Op::kNeg && op <= Op::kSign; }

/// Instruction codes of the varying (per point) program. Operands `a` and `b` are slots, except
/// in the *U codes, where `a` is a slot and `b` a uniform register (a value that depends on
/// parameters and constants only, computed once per parameter change).
enum class Code : std::uint8_t {
  kNeg,
  kSquare,
  kSqrt,
  kExp,
  kLog,
  kSin,
  kCos,
  kTan,
  kAbs,
  kSign,
  kAdd,    ///< a + b
  kAddU,   ///< a + u
  kSub,    ///< a - b
  kSubVU,  ///< a - u
  kSubUV,  ///< u - a
  kMul,    ///< a * b
  kMulU,   ///< a * u
  kDiv,    ///< a / b
  kDivVU,  ///< a / u
  kDivUV,  ///< u / a
  kPowU,   ///< a ^ u (exact when u is an integer)
  // A product feeding a sum, fused so that the block makes one pass through memory instead
  // of two. Rounded twice, exactly like the two instructions it replaces.
  kMulAdd,   ///< a * b + c
  kMulSub,   ///< a * b - c
  kSubMul,   ///< c - a * b
  kMulUAdd,  ///< a * u + c
  kMulUSub,  ///< a * u - c
  kSubMulU,  ///< c - a * u
};

/// dst = code(a, b, c). SSA before register allocation; slots are reused once a value is
/// dead, but dst never equals an operand slot of the same instruction.
struct Instr {
  Code code;
  std::int32_t dst;
  std::int32_t a;
  std::int32_t b;
  std::int32_t c = 0;  ///< third operand (a slot) of the fused codes
};

/// Slots 0, 1, 2 hold x, y, z.
inline constexpr int kInputSlots = 3;

/// A per-point program with its outputs. An output (and any operand reference outside
/// Instr) is a slot when ≥ 0, and uniform register r when it is ~r (< 0).
struct Program {
  std::vector<Instr> code;
  int slot_count = kInputSlots;
  std::vector<std::int32_t> outputs;
};

/// One uniform register: a constant, a parameter, or an operation on earlier registers.
struct UniformInstr {
  Op op;
  std::int32_t a = 0;  ///< parameter index for kParam, else register
  std::int32_t b = 0;  ///< register (binary operations)
  double value = 0;    ///< kConst only
};

/// The compiled field: immutable, shared by every Field copy.
struct Tape {
  std::string source;
  std::string expression;               ///< readable final expression (Field::expression_string)
  std::vector<std::string> parameters;  ///< in order of first appearance
  /// Index of each name in `parameters` (Field::parameter_index: constant time, so looking up
  /// every parameter of an equation with thousands stays linear).
  std::unordered_map<std::string, int> parameter_indices;
  std::vector<UniformInstr> uniforms;  ///< registers used by the three programs
  Program value;                       ///< outputs: F
  Program gradient;                    ///< outputs: F, Fx, Fy, Fz
  Program full;     ///< outputs: F, Fx, Fy, Fz, Fxx, Fxy, Fxz, Fyy, Fyz, Fzz, ∂F/∂q_0, ...
  int degree = -1;  ///< total degree when F is a polynomial in x, y, z, else -1
};

/// Output positions in Tape::full.
inline constexpr int kFullHessian = 4;
inline constexpr int kFullParams = 10;

/// Computes every uniform register for the given parameter values.
void eval_uniforms(const Tape& tape, std::span<const double> params, std::vector<double>& out);

}  // namespace zeroset::detail
