// The set-up of a ray caster: F's terms translated to the eye and by monomial, its partial
// derivatives, and the coefficients of the rounding band.
#include <algorithm>
#include <cmath>
#include <optional>

#include "raycast_detail.h"
#include "zeroset/expr/polynomial.h"

namespace zeroset::detail {

void set_eye(RayCaster& rc, const Vec3& e) {
  rc.eye = e;
  rc.accurate_ready = false;
  if (!rc.exact) return;
  // G(p) = F(eye + p). A coefficient that overflowed (huge parameter values, a far eye and a
  // high degree) has no exact restriction: such a field goes through interval arithmetic,
  // which sees the overflow as undefined values rather than as a polynomial of NaNs.
  const std::vector<Monomial> translated = rc.polynomial.translated(e).terms();
  if (!std::all_of(translated.begin(), translated.end(),
                   [](const Monomial& m) { return std::isfinite(m.c); })) {
    rc.exact = false;
    rc.intervals = std::make_unique<IntervalEvaluator>(rc.surface.field);
    return;
  }
  const MonomialTable& table = rc.row_monomials;
  rc.row_terms.clear();
  rc.translated_gradient.clear();
  std::vector<Vec3> dense(table.size(), Vec3::Zero());
  for (const Monomial& m : translated) {
    rc.row_terms.push_back({table.at(m.i, m.j, m.k), m.degree(), m.c});
    if (m.i > 0) dense[static_cast<size_t>(table.at(m.i - 1, m.j, m.k))].x() = m.i * m.c;
    if (m.j > 0) dense[static_cast<size_t>(table.at(m.i, m.j - 1, m.k))].y() = m.j * m.c;
    if (m.k > 0) dense[static_cast<size_t>(table.at(m.i, m.j, m.k - 1))].z() = m.k * m.c;
  }
  for (size_t m = 0; m < dense.size(); ++m)
    if (!dense[m].isZero())
      rc.translated_gradient.push_back({static_cast<int>(m), rc.degree_of[m], dense[m]});
  const Polynomial gb = Polynomial(rc.abs_terms).translated(e.cwiseAbs());
  std::array<double, kN> bounds{};
  for (const Monomial& m : gb.terms()) bounds[static_cast<size_t>(m.degree())] += m.c;
  // rounding_band's polynomial in t_max, coefficient by coefficient.
  std::vector<double> unit(static_cast<size_t>(rc.degree + 1), 0.0);
  for (int k = 0; k <= rc.degree; ++k) {
    unit[static_cast<size_t>(k)] = bounds[static_cast<size_t>(k)];
    rc.band_coeffs[static_cast<size_t>(k)] = rounding_band(unit, 1.0);
    unit[static_cast<size_t>(k)] = 0;
  }
  if (rc.degree <= kPacketDegree) {
    broadcast(rc.band_coeffs.data(), rc.degree + 1, rc.band4);
    for (int k = 0; k <= rc.degree; ++k) {
      const double v = k * rc.band_coeffs[static_cast<size_t>(k)];
      broadcast(&v, 1, rc.k_band4 + k);
    }
  }
}

RayCaster::RayCaster(const Surface& s, const Vec3& e, const RaycastOptions& o)
    : surface(s), eye(e), options(o), evaluator(s.field), finder(o.roots) {
  (void)surface.bounds();  // throws BadInput naming the surface when the clip is unbounded
  scene_radius = surface.scene_radius();
  const Field& field = surface.field;
  exact = !o.force_interval && field.is_expandable() && field.degree() <= RootFinder::kMaxDegree;
  if (exact) {
    polynomial = field.polynomial();
    const auto& terms = polynomial.terms();
    exact = std::all_of(terms.begin(), terms.end(),
                        [](const Monomial& m) { return std::isfinite(m.c); });
  }
  if (exact) {
    degree = std::max(polynomial.degree(), 0);
    row_monomials = MonomialTable(degree);
    // The table's graded order: (total + 1)(total + 2)/2 monomials of each degree.
    int offset = 0;
    for (int total = 0; total <= degree; ++total)
      for (int m = 0; m < (total + 1) * (total + 2) / 2; ++m) {
        degree_of.push_back(total);
        mono_offset.push_back(offset);
        offset += total + 1;
      }
    mono_poly.assign(static_cast<size_t>(offset), 0.0);
    derivative_monomials = MonomialTable(std::max(degree - 1, 0));
    gradient_bound.assign(static_cast<size_t>(derivative_monomials.D + 1), 0.0);
    // Polynomial's terms are unique, so each derivative gets each monomial at most once.
    std::vector<GradientTerm> dense(derivative_monomials.size());
    for (size_t m = 0; m < dense.size(); ++m) dense[m] = {m, Eigen::Vector4d::Zero()};
    auto add_derivative = [&](int axis, int i, int j, int k, double c) {
      dense[static_cast<size_t>(derivative_monomials.at(i, j, k))].c[axis] = c;
      gradient_bound[static_cast<size_t>(i + j + k)] += std::abs(c);
    };
    for (const Monomial& m : polynomial.terms()) {
      abs_terms.push_back({m.i, m.j, m.k, std::abs(m.c)});
      if (m.i > 0) add_derivative(0, m.i - 1, m.j, m.k, m.i * m.c);
      if (m.j > 0) add_derivative(1, m.i, m.j - 1, m.k, m.j * m.c);
      if (m.k > 0) add_derivative(2, m.i, m.j, m.k - 1, m.k * m.c);
    }
    for (const GradientTerm& term : dense)
      if (!term.c.isZero()) derivative.push_back(term);
    powers.assign(derivative_monomials.size(), 0.0);
    if (degree <= kPacketDegree)
      broadcast(gradient_bound.data(), static_cast<int>(gradient_bound.size()), gradient_bound4);
    set_eye(*this, eye);
  }
  if (!exact) intervals = std::make_unique<IntervalEvaluator>(field);
  sphere_rows.resize(surface.clip.spheres.size());
  plane_rows.resize(surface.clip.planes.size());
}

}  // namespace zeroset::detail
