#pragma once
/// The compiled field F(x, y, z; q): an immutable instruction tape plus parameter values.
#include <array>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "zeroset/types.h"

namespace zeroset {

class Polynomial;
namespace detail {
struct Tape;
}

/// A compiled scalar field. Copying is cheap (the tape is shared and immutable); each copy has
/// its own parameter values, and changing one never recompiles. Thread safety: a const Field
/// may be shared between threads; evaluate it through one `Evaluator` per thread.
/// The largest magnitude a parameter value (or a parameter range's end) may have. Beyond it
/// the products of a few parameters overflow, and a slider's span max − min is no longer a
/// finite number; every entry point (flags, scene files, scripts, the viewer's widgets) refuses
/// or clamps to it through `check_parameter_value`.
inline constexpr double kMaxParameterMagnitude = 1e100;

/// Throws InvalidArgument naming `name` when `value` is not finite or its magnitude exceeds
/// kMaxParameterMagnitude.
void check_parameter_value(std::string_view name, double value);

class Field {
 public:
  Field();  ///< the zero field (no parameters)
  explicit Field(std::shared_ptr<const detail::Tape> tape);

  /// Parameter names in order of first appearance in the source.
  const std::vector<std::string>& parameter_names() const;
  /// Index of a parameter, or -1.
  int parameter_index(std::string_view name) const;
  /// Current values (NaN for a parameter that has none yet).
  const std::vector<double>& parameter_values() const { return params_; }
  /// Sets one value. Throws InvalidArgument for an unknown name or a value
  /// `check_parameter_value` refuses.
  void set_parameter(std::string_view name, double value);
  void set_parameter(int index, double value);
  /// Sets every listed value; names the field does not have are an InvalidArgument.
  void set_parameters(const std::map<std::string, double>& values);
  /// Names of parameters that still have no value.
  std::vector<std::string> missing_parameters() const;
  /// Throws InvalidArgument naming every parameter without a value.
  void require_parameters() const;

  /// True when F is a polynomial in x, y, z (parameters and constants allowed in coefficients).
  bool is_polynomial() const;
  /// Total degree in x, y, z; -1 when not a polynomial.
  int degree() const;
  /// True when F depends on x, y, z at all; false for an expression of the parameters and
  /// constants only (a clip size, docs/scenes.md).
  bool depends_on_position() const;
  /// The highest degree polynomial() expands: a dense degree-24 polynomial has 2925 terms, and
  /// one product of two of them already takes a few milliseconds.
  static constexpr int kMaxExpansionDegree = 24;
  /// True when polynomial() can expand F: a polynomial of degree ≤ kMaxExpansionDegree. Higher
  /// degrees are still evaluated, differentiated, sampled, meshed and ray traced (by interval
  /// arithmetic) from the compiled expression.
  bool is_expandable() const;
  /// The expanded polynomial for the current parameter values. Throws BadInput when F is not
  /// expandable (not a polynomial, or of degree above kMaxExpansionDegree), or when a
  /// parameter has no value (InvalidArgument). Cost: milliseconds for degree ≤ 12.
  Polynomial polynomial() const;

  /// The source text it was compiled from.
  const std::string& source() const;
  /// The final expression as a readable string (definitions substituted), e.g. for `info`.
  std::string expression_string() const;

  const detail::Tape& tape() const { return *tape_; }

 private:
  std::shared_ptr<const detail::Tape> tape_;
  std::vector<double> params_;
};

/// Value and derivatives of F at one point.
struct FieldSample {
  double value = 0;
  Vec3 gradient = Vec3::Zero();  ///< ∇_x F
  Mat3 hessian = Mat3::Zero();   ///< ∇_x² F (only when requested)
  std::vector<double> dq;        ///< ∂F/∂q_k for every parameter (only when requested)
};

/// What Evaluator::sample() computes besides the value and the gradient; combine with |.
enum class Derivatives : unsigned {
  kGradient = 0,    ///< value and gradient only
  kHessian = 1,     ///< ∇_x² F
  kParameters = 2,  ///< ∂F/∂q_k
  kAll = 3,
};
constexpr Derivatives operator|(Derivatives a, Derivatives b) {
  return static_cast<Derivatives>(static_cast<unsigned>(a) | static_cast<unsigned>(b));
}
constexpr bool includes(Derivatives set, Derivatives what) {
  return (static_cast<unsigned>(set) & static_cast<unsigned>(what)) != 0;
}

/// Evaluates a Field. Owns scratch memory: one per thread, never shared. Holds a copy of the
/// field (cheap), so later changes to the caller's Field do not reach it; use
/// `set_parameter` or `reset` for that. Throws InvalidArgument at construction when a
/// parameter has no value. Non-finite results (log of a negative number, 0/0) come out as
/// NaN; they are never an exception.
class Evaluator {
 public:
  explicit Evaluator(const Field& field);
  ~Evaluator();
  Evaluator(Evaluator&&) noexcept;
  Evaluator& operator=(Evaluator&&) noexcept;

  void reset(const Field& field);
  void set_parameter(int index, double value);
  const Field& field() const { return field_; }

  double value(const Vec3& p);
  double value_gradient(const Vec3& p, Vec3& gradient);
  /// Value, gradient, and the derivatives asked for (the Hessian and parameter derivatives
  /// by default).
  FieldSample sample(const Vec3& p, Derivatives what = Derivatives::kAll);

  /// Batched, structure of arrays: out[i] = F(x[i], y[i], z[i]). All spans the same length.
  void values(std::span<const double> x, std::span<const double> y, std::span<const double> z,
              std::span<double> out);
  /// Batched value and gradient.
  void values_gradients(std::span<const double> x, std::span<const double> y,
                        std::span<const double> z, std::span<double> value, std::span<double> gx,
                        std::span<double> gy, std::span<double> gz);
  /// Batched value, gradient and Hessian: hessian[k][i] is entry k of the Hessian at point i,
  /// in the order xx, xy, xz, yy, yz, zz. The same numbers as sample() at each point.
  void values_gradients_hessians(std::span<const double> x, std::span<const double> y,
                                 std::span<const double> z, std::span<double> value,
                                 std::span<double> gx, std::span<double> gy, std::span<double> gz,
                                 const std::array<std::span<double>, 6>& hessian);

 private:
  struct Scratch;
  Field field_;
  std::unique_ptr<Scratch> scratch_;
};

}  // namespace zeroset
