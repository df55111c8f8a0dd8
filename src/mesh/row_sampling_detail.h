#pragma once
// Sampling F and its signs at rows of grid nodes, for the dense slabs and the sparse bricks.
#include <cstdint>
#include <optional>
#include <vector>

#include "line_restriction_detail.h"
#include "polygonize_detail.h"
#include "zeroset/expr/field.h"
#include "zeroset/expr/polynomial.h"

namespace zeroset::detail {

// Samples F at runs of grid nodes along x: through the line restriction for polynomials
// (vectorised Horner), otherwise through the field over structure-of-arrays rows. One per
// worker.
class RowSampler {
 public:
  RowSampler(const Field& field, const Grid& grid, const Polynomial* poly);

  /// F at nodes i0 .. i0 + count − 1 of row (j, k) into out. With `bits`, also their sign bits
  /// (bit n for node i0 + n set where the value counts as positive, is_positive), and returns
  /// how many values are NaN.
  long long sample(long long i0, long long count, long long j, long long k, double* out,
                   std::uint64_t* bits = nullptr);

 private:
  std::optional<Evaluator> eval_;  // fields that are not polynomials
  const Grid& grid_;
  std::optional<LineRestriction> line_;
  std::vector<double> coeffs_, t_, x_, y_, z_;
};

}  // namespace zeroset::detail
