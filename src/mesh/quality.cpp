#include "zeroset/mesh/quality.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <tuple>

#include "mesh_detail.h"
#include "zeroset/detail/parallel.h"
#include "zeroset/surface/analysis.h"

namespace zeroset {
namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;

// F and ∇F at many points, batched and parallel.
void evaluate(const Surface& surface, const std::vector<Vec3>& pts, int workers,
              std::vector<double>& f, std::vector<Vec3>& g) {
  detail::EvaluatorPool pool(surface.field, workers);
  detail::values_gradients(pool, workers, pts, f, g);
}

}  // namespace

DegenerateCount count_degenerate(const Mesh& mesh) {
  DegenerateCount d;
  const auto& P = mesh.positions;
  for (const auto& t : mesh.triangles)
    d.zero_area_triangles += (P[t[1]] - P[t[0]]).cross(P[t[2]] - P[t[0]]).squaredNorm() == 0;
  std::vector<Vec3> sorted = P;  // equal points end up side by side
  std::sort(sorted.begin(), sorted.end(), [](const Vec3& a, const Vec3& b) {
    return std::tie(a.x(), a.y(), a.z()) < std::tie(b.x(), b.y(), b.z());
  });
  for (size_t v = 1; v < sorted.size(); ++v) d.coincident_vertices += sorted[v] == sorted[v - 1];
  return d;
}

double triangle_min_angle_deg(const Vec3& a, const Vec3& b, const Vec3& c) {
  if ((b - a).cross(c - a).squaredNorm() == 0) return 0;
  return kDeg * std::min({detail::corner_angle(a, b, c), detail::corner_angle(b, c, a),
                          detail::corner_angle(c, a, b)});
}

double triangle_radius_ratio(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double la = (b - c).norm(), lb = (c - a).norm(), lc = (a - b).norm();
  const double area = 0.5 * (b - a).cross(c - a).norm();
  const double den = (la + lb + lc) * la * lb * lc;
  return den > 0 ? 16 * area * area / den : 0.0;
}

MeshQuality measure_quality(const Mesh& mesh, const Surface& surface,
                            const QualityOptions& options) {
  const int workers = detail::worker_count(options.threads);
  MeshQuality q;
  q.vertices = mesh.positions.size();
  q.triangles = mesh.triangles.size();
  const auto& P = mesh.positions;
  const long long nt = static_cast<long long>(mesh.triangles.size());

  double edge_sum = 0, angle_sum = 0, ratio_sum = 0;
  double smallest = 180, min_ratio = 1;
  std::array<long long, 12> hist{};
  detail::ExceptionTrap trap;
#pragma omp parallel num_threads(workers)
  {
    std::array<long long, 12> local{};
#pragma omp for schedule(static) reduction(+ : edge_sum, angle_sum, ratio_sum) \
    reduction(min : smallest, min_ratio)
    for (long long t = 0; t < nt; ++t)
      trap.run([&] {
        const auto& tri = mesh.triangles[static_cast<size_t>(t)];
        const Vec3 &a = P[tri[0]], &b = P[tri[1]], &c = P[tri[2]];
        edge_sum += (b - a).norm() + (c - b).norm() + (a - c).norm();
        const double ang = triangle_min_angle_deg(a, b, c);
        const double ratio = triangle_radius_ratio(a, b, c);
        angle_sum += ang;
        ratio_sum += ratio;
        smallest = std::min(smallest, ang);
        min_ratio = std::min(min_ratio, ratio);
        ++local[static_cast<size_t>(std::clamp(static_cast<int>(ang / 5), 0, 11))];
      });
#pragma omp critical
    for (size_t k = 0; k < 12; ++k) hist[k] += local[k];
  }
  trap.rethrow();
  q.min_angle_histogram = hist;
  const DegenerateCount degenerate = count_degenerate(mesh);
  q.zero_area_triangles = degenerate.zero_area_triangles;
  q.coincident_vertices = degenerate.coincident_vertices;
  if (nt > 0) {
    const double n = static_cast<double>(nt);
    q.mean_edge_length = edge_sum / (3 * n);
    q.mean_min_angle_deg = angle_sum / n;
    q.mean_radius_ratio = ratio_sum / n;
    q.smallest_angle_deg = smallest;
    q.min_radius_ratio = min_ratio;
    q.percent_below_10 = 100.0 * static_cast<double>(hist[0] + hist[1]) / n;
    q.percent_below_20 = 100.0 * static_cast<double>(hist[0] + hist[1] + hist[2] + hist[3]) / n;
    long long below30 = 0;
    for (size_t k = 0; k < 6; ++k) below30 += hist[k];
    q.percent_below_30 = 100.0 * static_cast<double>(below30) / n;
  }

  q.singular_points = surface.singular_points();
  q.singular_radius =
      options.singular_radius > 0 ? options.singular_radius : 2 * q.mean_edge_length;
  auto near_singular = [&](const Vec3& p) {
    for (const Vec3& s : q.singular_points)
      if ((p - s).norm() < q.singular_radius) return true;
    return false;
  };
  for (const Vec3& s : q.singular_points) {
    double best = std::numeric_limits<double>::infinity();
    for (const Vec3& p : P) best = std::min(best, (p - s).norm());
    q.singular_point_distance.push_back(best);
  }

  // Residuals at the vertices.
  std::vector<double> f;
  std::vector<Vec3> g;
  evaluate(surface, P, workers, f, g);
  double sq = 0;
  for (size_t v = 0; v < P.size(); ++v) {
    const double gl = g[v].norm();
    if (!std::isfinite(f[v])) {
      ++q.undefined_vertices;
      q.max_residual = residual(f[v], gl);  // the largest double
      continue;
    }
    if (near_singular(P[v])) continue;
    if (!has_residual(f[v], gl)) continue;
    const double r = residual(f[v], gl);
    q.max_residual = std::max(q.max_residual, r);
    sq += r * r;
    ++q.residual_vertices;
  }
  if (q.residual_vertices > 0)
    q.rms_residual = std::sqrt(sq / static_cast<double>(q.residual_vertices));

  // Face normals against ∇F at the centroids.
  std::vector<Vec3> centroids(mesh.triangles.size());
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    centroids[t] = (P[tri[0]] + P[tri[1]] + P[tri[2]]) / 3;
  }
  evaluate(surface, centroids, workers, f, g);
  double dev_sum = 0;
  size_t dev_count = 0;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (near_singular(centroids[t])) continue;
    const auto& tri = mesh.triangles[t];
    const Vec3 n = detail::area_normal(P[tri[0]], P[tri[1]], P[tri[2]]);
    const double denom = n.norm() * g[t].norm();
    if (!(denom > 0) || !std::isfinite(denom)) continue;
    const double dev = kDeg * std::acos(std::clamp(n.dot(g[t]) / denom, -1.0, 1.0));
    dev_sum += dev;
    ++dev_count;
    q.max_normal_deviation_deg = std::max(q.max_normal_deviation_deg, dev);
    if (dev > 90) ++q.flipped_triangles;
  }
  if (dev_count > 0) q.mean_normal_deviation_deg = dev_sum / static_cast<double>(dev_count);

  if (mesh.is_boundary.size() == P.size())
    for (size_t v = 0; v < P.size(); ++v)
      if (mesh.is_boundary[v]) {
        ++q.boundary_vertices;
        if (!surface.clip.is_empty_spec())
          q.max_boundary_clip_value =
              std::max(q.max_boundary_clip_value, std::abs(surface.clip.value(P[v])));
      }
  return q;
}

}  // namespace zeroset
