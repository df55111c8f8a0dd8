// CGAL's implicit surface mesher (Surface_mesher, Boissonnat & Oudot) on the Kummer surface
// mu = 1.5 clipped at R = 3 or Barth's sextic clipped at R = 1.8 (the catalog's clips), the peer
// of `zeroset mesh` in bench/mesh_peers.py.
// Usage: mesh_cgal RADIUS_BOUND DISTANCE_BOUND OUT.off [kummer|barth6]
//        → prints seconds, vertices, triangles.
// 200 initial points: with CGAL's default of 20 it can silently miss whole sheets.
#include <CGAL/Complex_2_in_triangulation_3.h>
#include <CGAL/IO/facets_in_complex_2_to_triangle_mesh.h>
#include <CGAL/Implicit_surface_3.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_default_triangulation_3.h>
#include <CGAL/make_surface_mesh.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <string>

using Tr = CGAL::Surface_mesh_default_triangulation_3;
using C2t3 = CGAL::Complex_2_in_triangulation_3<Tr>;
using GT = Tr::Geom_traits;
using Point_3 = GT::Point_3;
using FT = GT::FT;
using Function = FT (*)(Point_3);
using Surface_3 = CGAL::Implicit_surface_3<GT, Function>;

FT kummer(Point_3 p) {
  const double mu = 1.5, s2 = std::sqrt(2.0);
  const double x = p.x(), y = p.y(), z = p.z();
  const double pp = 1 - z - s2 * x, q = 1 - z + s2 * x, r = 1 + z + s2 * y, s = 1 + z - s2 * y;
  const double w = x * x + y * y + z * z - mu;
  return (3 - mu) * w * w - (3 * mu - 1) * pp * q * r * s;
}

FT barth6(Point_3 p) {
  const double phi = (1 + std::sqrt(5.0)) / 2, f2 = phi * phi;
  const double x = p.x(), y = p.y(), z = p.z();
  const double w = x * x + y * y + z * z - 1;
  return 4 * (f2 * x * x - y * y) * (f2 * y * y - z * z) * (f2 * z * z - x * x) -
         (1 + 2 * phi) * w * w;
}

int main(int argc, char** argv) {
  const std::string name = argc == 5 ? argv[4] : "kummer";
  if ((argc != 4 && argc != 5) || (name != "kummer" && name != "barth6")) {
    std::cerr << "usage: mesh_cgal RADIUS_BOUND DISTANCE_BOUND OUT.off [kummer|barth6]\n";
    return 2;
  }
  const double radius = std::atof(argv[1]), distance = std::atof(argv[2]);
  const auto t0 = std::chrono::steady_clock::now();
  Tr tr;
  C2t3 c2t3(tr);
  // Bounding sphere: centre 0 (where F < 0 for both), the catalog's clip radius.
  const bool is_kummer = name == "kummer";
  Surface_3 surface(is_kummer ? kummer : barth6,
                    GT::Sphere_3(CGAL::ORIGIN, is_kummer ? 9.0 : 1.8 * 1.8), 1e-7);
  CGAL::Surface_mesh_default_criteria_3<Tr> criteria(30.0, radius, distance);
  CGAL::make_surface_mesh(c2t3, surface, criteria, CGAL::Non_manifold_tag(), 200);
  CGAL::Surface_mesh<Point_3> sm;
  CGAL::facets_in_complex_2_to_triangle_mesh(c2t3, sm);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::ofstream out(argv[3]);
  out.precision(17);
  out << "OFF\n" << sm.number_of_vertices() << ' ' << sm.number_of_faces() << " 0\n";
  for (auto v : sm.vertices()) out << sm.point(v) << '\n';
  for (auto f : sm.faces()) {
    out << 3;
    for (auto v : CGAL::vertices_around_face(sm.halfedge(f), sm))
      out << ' ' << static_cast<std::size_t>(v);
    out << '\n';
  }
  std::cout << "{\"seconds\": " << seconds << ", \"vertices\": " << sm.number_of_vertices()
            << ", \"triangles\": " << sm.number_of_faces() << "}\n";
  return 0;
}
