#pragma once
// The monomials x^i y^j z^k of a polynomial's terms in graded order, each one product from an
// earlier one, and ∇F summed over them: the ray caster's set-up expands rows through them
// (raycast_setup.cpp, raycast_rows.cpp) and its normals evaluate ∇F at hit points
// (raycast_normals.cpp). Private to the render module.
#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <utility>
#include <vector>

#include "zeroset/types.h"

namespace zeroset::detail {

/// Number of monomials in x, y, z of degree ≤ D.
constexpr int monomial_count(int D) { return (D + 1) * (D + 2) * (D + 3) / 6; }

/// The same enumeration as MonomialTable for a degree known at compile time, so that the
/// monomials of a hit point are computed in fully unrolled code.
template <int D>
struct FixedMonomials {
  static constexpr int kCount = monomial_count(D);
  std::array<int, kCount> parent{};
  std::array<int, kCount> axis{};
  constexpr FixedMonomials() {
    constexpr int n = D + 1;
    std::array<int, n * n * n> index{};
    int pos = 0;
    for (int total = 0; total <= D; ++total) {
      for (int i = total; i >= 0; --i)
        for (int j = total - i; j >= 0; --j) {
          const int k = total - i - j;
          index[static_cast<size_t>((i * n + j) * n + k)] = pos;
          if (total > 0) {
            const int a = i > 0 ? 0 : (j > 0 ? 1 : 2);
            const int pi = i - (a == 0), pj = j - (a == 1), pk = k - (a == 2);
            parent[static_cast<size_t>(pos)] = index[static_cast<size_t>((pi * n + pj) * n + pk)];
            axis[static_cast<size_t>(pos)] = a;
          }
          ++pos;
        }
    }
  }
};

/// mono[m] = v^monomial m for every monomial of degree ≤ D, unrolled.
template <int D>
void monomials_fixed(const double* v, double* mono) {
  static constexpr FixedMonomials<D> t{};
  mono[0] = 1;
  [&]<size_t... I>(std::index_sequence<I...>) {
    ((mono[I + 1] = mono[t.parent[I + 1]] * v[t.axis[I + 1]]), ...);
  }
  (std::make_index_sequence<FixedMonomials<D>::kCount - 1>{});
}

/// coeffs[k] = Σ_j row[k(k+1)/2 + j] s^j for k ≤ d: each coefficient of the ray's
/// polynomial from its polynomial in s (Horner), unrolled when D > 0. Returns the rounding

/// A monomial of the partial derivatives of F: its position in a MonomialTable and its
/// coefficients in ∂F/∂x, ∂F/∂y, ∂F/∂z and a zero, four lanes summed as one vector.
struct GradientTerm {
  size_t position;
  Eigen::Matrix<double, 4, 1, Eigen::DontAlign> c;
};

/// g = (∂F/∂x, ∂F/∂y, ∂F/∂z) from the monomials of a point. Two sums, so that consecutive
/// multiply-adds do not wait for each other.
inline void sparse_gradient(const std::vector<GradientTerm>& terms, const double* mono, double* g) {
  Eigen::Vector4d even = Eigen::Vector4d::Zero(), odd = Eigen::Vector4d::Zero();
  size_t i = 0;
  for (; i + 1 < terms.size(); i += 2) {
    even += terms[i].c * mono[terms[i].position];
    odd += terms[i + 1].c * mono[terms[i + 1].position];
  }
  if (i < terms.size()) even += terms[i].c * mono[terms[i].position];
  for (int k = 0; k < 3; ++k) g[k] = even[k] + odd[k];
}

/// Every monomial x^i y^j z^k of degree ≤ D in graded order (degree, then descending i, j),
/// each one the product of an earlier one (`parent`) and one variable (`axis`): the monomials
/// of a point are then one multiplication each.
struct MonomialTable {
  std::vector<int> parent;
  std::vector<int> axis;
  std::vector<int> index;  // (i, j, k) → position, at (i·(D+1) + j)·(D+1) + k
  int D = 0;

  explicit MonomialTable(int degree) : D(degree) {
    const int n = D + 1;
    index.assign(static_cast<size_t>(n) * n * n, -1);
    for (int total = 0; total <= D; ++total) {
      for (int i = total; i >= 0; --i)
        for (int j = total - i; j >= 0; --j) {
          const int k = total - i - j;
          const int pos = static_cast<int>(parent.size());
          index[static_cast<size_t>((i * n + j) * n + k)] = pos;
          if (total == 0) {
            parent.push_back(-1);
            axis.push_back(0);
          } else {
            // Divide by the first variable present: x if i > 0, else y, else z.
            const int a = i > 0 ? 0 : (j > 0 ? 1 : 2);
            const int pi = i - (a == 0), pj = j - (a == 1), pk = k - (a == 2);
            parent.push_back(index[static_cast<size_t>((pi * n + pj) * n + pk)]);
            axis.push_back(a);
          }
        }
    }
  }
  int at(int i, int j, int k) const {
    const int n = D + 1;
    return index[static_cast<size_t>((i * n + j) * n + k)];
  }
  size_t size() const { return parent.size(); }

  /// mono[m] = v^monomial m (size() entries).
  void evaluate(const Vec3& v, double* mono) const {
    const double x[3] = {v.x(), v.y(), v.z()};
    switch (D) {
      case 1:
        return monomials_fixed<1>(x, mono);
      case 2:
        return monomials_fixed<2>(x, mono);
      case 3:
        return monomials_fixed<3>(x, mono);
      case 4:
        return monomials_fixed<4>(x, mono);
      case 5:
        return monomials_fixed<5>(x, mono);
      case 6:
        return monomials_fixed<6>(x, mono);
      default:
        break;
    }
    // Local pointers: the stores to `mono` could otherwise alias the tables' storage.
    const int* par = parent.data();
    const int* ax = axis.data();
    mono[0] = 1;
    for (size_t m = 1; m < size(); ++m) mono[m] = mono[par[m]] * x[ax[m]];
  }
};

}  // namespace zeroset::detail
