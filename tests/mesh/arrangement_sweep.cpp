// The arrangements sweep (docs/meshing.md, "Crossings: the arrangements sweep"): meshes random
// products of quadrics with the whole pipeline of `zeroset mesh` and checks each against its
// exactly known double curves. Prints one line per product and the figures of the sweep.
//
//   arrangement_sweep [--count N] [--cells C] [--seed S] [--only K] [--verbose] [--no-improve] [--paper]
#include <fmt/core.h>

#include <chrono>
#include <map>
#include <cstdlib>
#include <string>
#include <string_view>

#include "arrangements.h"
#include "support/equation.h"
#include "zeroset/mesh/mesh_surface.h"

using namespace zeroset;

int main(int argc, char** argv) {
  int count = 200, cells = 64, only = -1;
  unsigned seed = 1;
  bool verbose = false, improve = true;
  std::string improver = "remesh";
  for (int i = 1; i < argc; ++i) {
    const std::string_view a = argv[i];
    auto value = [&] {
      if (i + 1 >= argc) {
        fmt::print(stderr, "arrangement_sweep: {} needs a value\n", a);
        std::exit(2);
      }
      return std::atoi(argv[++i]);
    };
    if (a == "--count") count = value();
    else if (a == "--cells") cells = value();
    else if (a == "--seed") seed = static_cast<unsigned>(value());
    else if (a == "--only") only = value();
    else if (a == "--verbose") verbose = true;
    else if (a == "--no-improve") improve = false;
    else if (a == "--paper") improver = "paper";
    else {
      fmt::print(stderr, "usage: arrangement_sweep [--count N] [--cells C] [--seed S] [--only K] [--verbose] [--no-improve] [--paper]\n");
      return 2;
    }
  }
  test::ArrangementGenerator gen(seed);
  int passed = 0, gave_up = 0, degraded = 0, not_at_rest = 0, ran = 0;
  long long sheet_points = 0, sheet_on = 0, curve_points = 0, curve_on = 0;
  double seconds = 0;
  for (int k = 0; k < count; ++k) {
    const test::Arrangement arr = gen.next();
    if (only >= 0 && k != only) continue;
    ++ran;
    const Surface s = test::equation(arr.expression(), Clip::sphere(1));
    MeshSettings settings;
    settings.cells = cells;
    settings.improve = improve;
    settings.improver = parse_improver(improver);
    const auto t0 = std::chrono::steady_clock::now();
    MeshRun run;
    run.survey = false;
    const MeshResult r = mesh_surface(s, settings, run);
    const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    seconds += sec;
    const test::ArrangementFigures fig = test::check_arrangement(r.mesh, arr);
    const bool rest = !improve || (r.improvement && r.improvement->summary().converged);
    const std::string failure = r.crossings ? r.crossings->failure : "";
    const long long local =
        r.crossings ? static_cast<long long>(r.crossings->left_as_marching_cubes.size()) : 0;
    const bool ok = fig.sheet_fraction() >= 0.99 && fig.curve_fraction() >= 1.0 && rest;
    passed += ok;
    gave_up += !failure.empty();
    degraded += local > 0;
    not_at_rest += !rest;
    sheet_points += fig.sheet_points, sheet_on += fig.sheet_on_mesh;
    curve_points += fig.curve_points, curve_on += fig.curve_on_four;
    fmt::print("{:3d} {} sheets {:6.2f}% curves {:6.2f}% {} {:5.2f} s  {}{}{}\n", k,
               ok ? "pass" : "FAIL", 100 * fig.sheet_fraction(), 100 * fig.curve_fraction(),
               rest ? "rest" : "moving", sec, arr.kinds(),
               local > 0 ? fmt::format("  [{} places left as marching cubes]", local) : "",
               failure.empty() ? "" : "  [" + failure + "]");
    if (verbose) {
      fmt::print("    {}\n", arr.expression());
      std::map<std::pair<std::uint32_t, std::uint32_t>, int> count;
      for (const auto& t : r.mesh.triangles)
        for (int c = 0; c < 3; ++c) {
          const auto u = t[c], v = t[(c + 1) % 3];
          ++count[{std::min(u, v), std::max(u, v)}];
        }
      std::map<int, int> histogram;
      for (const MeshCurve& c : r.mesh.curves)
        for (size_t i = 0; i + 1 < c.vertices.size(); ++i) {
          const auto u = c.vertices[i], v = c.vertices[i + 1];
          const int n = count[{std::min(u, v), std::max(u, v)}];
          ++histogram[n];
          if (n != 4 && histogram[n] <= 4) {
            const Vec3 m = 0.5 * (r.mesh.positions[u] + r.mesh.positions[v]);
            fmt::print("    curve edge with {} triangles at ({:.4f}, {:.4f}, {:.4f})\n", n, m.x(), m.y(), m.z());
          }
        }
      for (const auto& [n, k] : histogram) fmt::print("    {} curve edges with {} triangles\n", k, n);
      if (r.singular)
        for (const SingularCurve& c : r.singular->curves)
          fmt::print("    {} curve{}, {} vertices, ({:.3f}, {:.3f}, {:.3f}) to ({:.3f}, {:.3f}, {:.3f})\n",
                     to_string(c.kind), c.closed ? " (closed)" : "", c.points.size(),
                     c.points.front().x(), c.points.front().y(), c.points.front().z(),
                     c.points.back().x(), c.points.back().y(), c.points.back().z());
      if (r.singular)
        for (const SingularPoint& p : r.singular->points)
          fmt::print("    {} point ({:.3f}, {:.3f}, {:.3f})\n", to_string(p.kind), p.position.x(),
                     p.position.y(), p.position.z());
      for (const char* what : {"sheet", "curve"})
        for (const auto& m : what[0] == 's' ? fig.sheet_misses : fig.curve_misses)
          fmt::print("    {} miss ({:.4f}, {:.4f}, {:.4f}): {:.3f} edges off, sheets at sin {:.2f}\n",
                     what, m.p.x(), m.p.y(), m.p.z(), m.distance, m.sin_angle);
    }
  }
  fmt::print(
      "{} products at {} cells (seed {}): {} pass ({:.1f}%); sheets {:.2f}% of {} points, "
      "curves {:.2f}% of {} points on four-triangle edges; {} gave up, {} degraded locally, {} "
      "not at rest; {:.1f} s\n",
      ran, cells, seed, passed, 100.0 * passed / std::max(ran, 1),
      100.0 * static_cast<double>(sheet_on) / static_cast<double>(std::max(sheet_points, 1LL)),
      sheet_points,
      100.0 * static_cast<double>(curve_on) / static_cast<double>(std::max(curve_points, 1LL)),
      curve_points, gave_up, degraded, not_at_rest, seconds);
  return 0;
}
