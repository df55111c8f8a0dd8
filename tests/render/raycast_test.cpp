#include "zeroset/render/raycast.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "render/ray_reference.h"
#include "zeroset/error.h"
#include "zeroset/expr/field.h"
#include "zeroset/expr/polynomial.h"
#include "zeroset/render/view.h"
#include "zeroset/surface/catalog.h"
#include "zeroset/surface/scene.h"

namespace zeroset {
namespace {

using test::random_unit;
using test::random_view;
using test::Reference;
using test::ReferenceCaster;

class CatalogRays : public testing::TestWithParam<const char*> {};

TEST_P(CatalogRays, FirstHitAgreesWithDenseReference) {
  const CatalogEntry* entry = find_catalog_entry(GetParam());
  ASSERT_NE(entry, nullptr);
  const Surface surface = make_surface(*entry);
  ASSERT_TRUE(surface.field.is_polynomial());
  ReferenceCaster reference(surface.field.polynomial());
  const Box3 box = surface.bounds();
  const double radius = surface.scene_radius();

  std::mt19937 rng(20240611);
  std::uniform_real_distribution<double> u(-1, 1);
  int hits = 0, ambiguous = 0, total = 0;
  constexpr int kEyes = 20, kRaysPerEye = 500;
  for (int e = 0; e < kEyes; ++e) {
    // Eyes outside the scene at camera-like distances, and a few inside the clip volume.
    const Vec3 eye =
        e % 5 == 4 ? Vec3(box.center() + 0.3 * radius * random_unit(rng))
                   : Vec3(box.center() + radius * (2.5 + 2 * std::abs(u(rng))) * random_unit(rng));
    SurfaceRayCaster caster(surface, eye);
    ASSERT_TRUE(caster.is_exact());
    for (int r = 0; r < kRaysPerEye; ++r) {
      const Vec3 aim(box.lo.x() + (box.hi.x() - box.lo.x()) * 0.5 * (u(rng) + 1),
                     box.lo.y() + (box.hi.y() - box.lo.y()) * 0.5 * (u(rng) + 1),
                     box.lo.z() + (box.hi.z() - box.lo.z()) * 0.5 * (u(rng) + 1));
      const Vec3 dir = (aim - eye).normalized();
      ++total;
      double t0 = 0, t1 = 0;
      const std::optional<double> got = caster.first_hit(dir);
      if (!surface.clip.ray_interval(eye, dir, 0, t0, t1)) {
        EXPECT_FALSE(got);
        continue;
      }
      const Reference ref = reference.first_hit(eye, dir, t0, t1);
      if (ref.kind == Reference::Kind::kAmbiguous) {
        ++ambiguous;
        continue;
      }
      if (ref.kind == Reference::Kind::kMiss) {
        EXPECT_FALSE(got) << "spurious hit at t = " << *got << ", eye " << eye.transpose()
                          << ", dir " << dir.transpose();
        continue;
      }
      ++hits;
      ASSERT_TRUE(got) << "missed hit at t = " << ref.t << ", eye " << eye.transpose() << ", dir "
                       << dir.transpose();
      EXPECT_NEAR(*got, ref.t, 1e-7) << "eye " << eye.transpose() << ", dir " << dir.transpose();
    }
  }
  EXPECT_EQ(total, kEyes * kRaysPerEye);
  // Near-tangent rays are rare; a large share would mean the reference is broken.
  EXPECT_LT(ambiguous, total / 50) << ambiguous << " ambiguous rays of " << total;
  EXPECT_GT(hits, total / 20) << "too few rays hit the surface to test anything";
  RecordProperty("hits", hits);
  RecordProperty("ambiguous", ambiguous);
}

/// The renderer's way: rows of rays eye + t·(base + s·step), each guided by the hits of the
/// rays before it, or misled on purpose by a random guess. Every hit must still agree with
/// the reference, and every ray that meets the clip must lie inside the row's extent.
TEST_P(CatalogRays, RowRaysAgreeWithDenseReferenceWhateverTheGuess) {
  const Surface surface = make_surface(*find_catalog_entry(GetParam()));
  ReferenceCaster reference(surface.field.polynomial());
  const Box3 box = surface.bounds();
  const double radius = surface.scene_radius();
  std::mt19937 rng(20240612);
  std::uniform_real_distribution<double> u(-1, 1), unit(0, 1);
  int hits = 0, guided = 0, misled = 0, ambiguous = 0;
  long long guided_roots = 0;  // found before the guess's limit
  constexpr int kEyes = 10, kRowsPerEye = 5, kRaysPerRow = 120;
  for (int e = 0; e < kEyes; ++e) {
    const View view = random_view(box.center(), radius, kRaysPerRow, rng);
    SurfaceRayCaster caster(surface, view.eye);
    for (int r = 0; r < kRowsPerEye; ++r) {
      Vec3 base, step;
      view.row(kRaysPerRow * unit(rng), base, step);
      caster.begin_row(base, step);
      double s_min, s_max;
      caster.row_extent(s_min, s_max);
      double last = NAN, before_last = NAN;
      for (int i = 0; i < kRaysPerRow; ++i) {
        const double s = i + 0.5;
        const Vec3 d = base + s * step;
        const Vec3 dir = d.normalized();
        double t0 = 0, t1 = 0;
        const bool in_clip = surface.clip.ray_interval(view.eye, dir, 0, t0, t1);
        if (in_clip) {
          EXPECT_GE(s, s_min);
          EXPECT_LE(s, s_max);
        }
        RootGuess guess;
        if (i % 3 == 2 && in_clip) {
          // Anywhere in the clipped segment, or before it, with any spread.
          guess.t = (t0 + (t1 - t0) * (1.2 * unit(rng) - 0.1)) / d.norm();
          guess.spread = (t1 - t0) * unit(rng) * unit(rng) / d.norm();
          ++misled;
        } else if (!std::isnan(last)) {
          guess.t = std::isnan(before_last) ? last : 2 * last - before_last;
          guess.spread =
              2 * (std::isnan(before_last) ? 0 : std::abs(last - before_last)) + 1e-4 * last;
          ++guided;
        }
        SurfaceHit hit;
        const bool got = caster.intersect_in_row(s, hit, guess);
        before_last = last;
        last = got ? hit.t : NAN;
        if (!in_clip) {
          EXPECT_FALSE(got);
          continue;
        }
        const Reference ref = reference.first_hit(view.eye, dir, t0, t1);
        if (ref.kind == Reference::Kind::kAmbiguous) {
          ++ambiguous;
          continue;
        }
        if (ref.kind == Reference::Kind::kMiss) {
          EXPECT_FALSE(got) << "spurious hit at t = " << hit.t * d.norm() << ", eye "
                            << view.eye.transpose() << ", dir " << dir.transpose();
          continue;
        }
        ++hits;
        ASSERT_TRUE(got) << "missed hit at t = " << ref.t << ", eye " << view.eye.transpose()
                         << ", dir " << dir.transpose();
        EXPECT_NEAR(hit.t * d.norm(), ref.t, 1e-7)
            << "eye " << view.eye.transpose() << ", dir " << dir.transpose();
        EXPECT_LT((hit.point - (view.eye + ref.t * dir)).norm(), 1e-6);
      }
    }
    guided_roots += caster.root_stats().guided_roots;
  }
  EXPECT_LT(ambiguous, kEyes * kRowsPerEye * kRaysPerRow / 50);
  EXPECT_GT(hits, kEyes * kRowsPerEye * kRaysPerRow / 20);
  EXPECT_GT(guided, hits / 2);
  EXPECT_GT(misled, 100);
  EXPECT_GT(guided_roots, hits / 4) << "the neighbours' guesses should mostly be good";
}

/// Orthographic rows: parallel rays origin + s·origin_step + t·forward from a random view,
/// F translated to the row's origin once (begin_parallel_row). Every hit agrees with the
/// reference restricted to the same ray, whatever the neighbours' guesses.
TEST_P(CatalogRays, ParallelRowRaysAgreeWithDenseReference) {
  const Surface surface = make_surface(*find_catalog_entry(GetParam()));
  ReferenceCaster reference(surface.field.polynomial());
  const Box3 box = surface.bounds();
  const double radius = surface.scene_radius();
  std::mt19937 rng(20261207);
  std::uniform_real_distribution<double> unit(0, 1);
  int hits = 0, ambiguous = 0, cast = 0;
  constexpr int kViews = 10, kRowsPerView = 5, kRaysPerRow = 120;
  for (int e = 0; e < kViews; ++e) {
    View view = random_view(box.center(), radius, kRaysPerRow, rng);
    view.orthographic = true;
    view.half_height = radius * (0.4 + 0.8 * unit(rng));
    SurfaceRayCaster caster(surface, view.eye);
    for (int r = 0; r < kRowsPerView; ++r) {
      Vec3 origin, origin_step;
      view.row_origins(kRaysPerRow * unit(rng), origin, origin_step);
      caster.begin_parallel_row(origin, origin_step, view.forward);
      double last = NAN, before_last = NAN;
      for (int i = 0; i < kRaysPerRow; ++i) {
        const double s = i + 0.5;
        const Vec3 o = origin + s * origin_step;
        RootGuess guess;
        if (!std::isnan(last)) {
          guess.t = std::isnan(before_last) ? last : 2 * last - before_last;
          guess.spread =
              2 * (std::isnan(before_last) ? 0 : std::abs(last - before_last)) + 1e-4 * last;
        }
        SurfaceHit hit;
        const bool got = caster.intersect_in_row(s, hit, guess);
        before_last = last;
        last = got ? hit.t : NAN;
        double t0 = 0, t1 = 0;
        if (!surface.clip.ray_interval(o, view.forward, 0, t0, t1)) {
          EXPECT_FALSE(got);
          continue;
        }
        ++cast;
        const Reference ref = reference.first_hit(o, view.forward, t0, t1);
        if (ref.kind == Reference::Kind::kAmbiguous) {
          ++ambiguous;
          continue;
        }
        if (ref.kind == Reference::Kind::kMiss) {
          EXPECT_FALSE(got) << "spurious hit at t = " << hit.t << ", origin " << o.transpose()
                            << ", dir " << view.forward.transpose();
          continue;
        }
        ++hits;
        ASSERT_TRUE(got) << "missed hit at t = " << ref.t << ", origin " << o.transpose()
                         << ", dir " << view.forward.transpose();
        EXPECT_NEAR(hit.t, ref.t, 1e-7 * radius)
            << "origin " << o.transpose() << ", dir " << view.forward.transpose();
        EXPECT_LT((hit.point - (o + ref.t * view.forward)).norm(), 1e-6 * radius);
        EXPECT_NEAR(hit.normal.norm(), 1.0, 1e-9);
      }
    }
  }
  EXPECT_LT(ambiguous, cast / 50 + 1);
  EXPECT_GT(hits, kViews * kRowsPerView * kRaysPerRow / 20);
}

/// Rows of rays take their normals from the row's expansions (G translated to the eye) where
/// ∇F is far from vanishing: they must agree with ∇F evaluated from the field at the hit.
TEST_P(CatalogRays, RowNormalsAgreeWithTheFieldsGradient) {
  const Surface surface = make_surface(*find_catalog_entry(GetParam()));
  Evaluator field(surface.field);
  const Box3 box = surface.bounds();
  const double radius = surface.scene_radius();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0, 1);
  int hits = 0, singular = 0;
  double worst = 0;
  constexpr int kEyes = 10, kRowsPerEye = 5, kRaysPerRow = 120;
  for (int e = 0; e < kEyes; ++e) {
    const View view = random_view(box.center(), radius, kRaysPerRow, rng);
    SurfaceRayCaster caster(surface, view.eye);
    for (int r = 0; r < kRowsPerEye; ++r) {
      Vec3 base, step;
      view.row(kRaysPerRow * unit(rng), base, step);
      caster.begin_row(base, step);
      for (int i = 0; i < kRaysPerRow; ++i) {
        SurfaceHit hit;
        if (!caster.intersect_in_row(i + 0.5, hit)) continue;
        if (hit.singular) {
          ++singular;
          continue;
        }
        Vec3 g;
        field.value_gradient(hit.point, g);
        // Near a node ∇F turns quickly: compare only where it is well above its rounding.
        if (!(g.norm() > 1e-6)) continue;
        const Vec3 d = base + (i + 0.5) * step;
        const Vec3 expected = (g.dot(d) > 0 ? -1.0 : 1.0) * g.normalized();
        worst = std::max(worst, (hit.normal - expected).norm());
        ++hits;
      }
    }
  }
  EXPECT_GT(hits, kEyes * kRowsPerEye * kRaysPerRow / 20);
  EXPECT_LT(singular, hits / 100);
  EXPECT_LT(worst, 1e-7) << "over " << hits << " hits";
}

/// Rays cast in packets of four (prepare_in_row, vectorized where the CPU allows), whether
/// completed one by one (intersect_in_row) or four at a time (first_hit_in_row, then
/// packet_hits), must give the same bits as rays cast alone: hit, point, normal, side and
/// singularity. The rays that prepare_in_row reports as misses must miss.
TEST_P(CatalogRays, PacketsCastTheSameAsSingleRays) {
  const Surface surface = make_surface(*find_catalog_entry(GetParam()));
  const Box3 box = surface.bounds();
  const double radius = surface.scene_radius();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0, 1);
  auto expect_same = [](const SurfaceHit& a, const SurfaceHit& b, int ray) {
    EXPECT_EQ(a.t, b.t) << "ray " << ray;
    EXPECT_EQ(a.point, b.point) << "ray " << ray;
    EXPECT_EQ(a.normal, b.normal) << "ray " << ray;
    EXPECT_EQ(a.front, b.front) << "ray " << ray;
    EXPECT_EQ(a.singular, b.singular) << "ray " << ray;
  };
  int hits = 0;
  constexpr int kEyes = 10, kRowsPerEye = 5, kRaysPerRow = 120;
  for (int e = 0; e < kEyes; ++e) {
    const View view = random_view(box.center(), radius, kRaysPerRow, rng);
    SurfaceRayCaster packets(surface, view.eye), deferred(surface, view.eye),
        single(surface, view.eye);
    for (int r = 0; r < kRowsPerEye; ++r) {
      Vec3 base, step;
      view.row(kRaysPerRow * unit(rng), base, step);
      packets.begin_row(base, step);
      deferred.begin_row(base, step);
      single.begin_row(base, step);
      double last = NAN;
      SurfaceHit expected[4];
      int expected_bits = 0, reported_misses = 0;
      for (int i = 0; i < kRaysPerRow; ++i) {
        const double s = i + 0.5;
        if (i % 4 == 0) {
          const double next[4] = {s, s + 1, s + 2, s + 3};
          reported_misses = packets.prepare_in_row(next);
          ASSERT_EQ(deferred.prepare_in_row(next), reported_misses);
        }
        RootGuess guess;
        if (!std::isnan(last)) guess = {last, 1e-3 * last};
        SurfaceHit a, b;
        const bool got = packets.intersect_in_row(s, a, guess);
        ASSERT_EQ(got, single.intersect_in_row(s, b, guess)) << "ray " << i;
        double t = NAN;
        ASSERT_EQ(got, deferred.first_hit_in_row(s, guess, t)) << "ray " << i;
        last = got ? a.t : NAN;
        if ((reported_misses >> (i % 4)) & 1) {
          EXPECT_FALSE(got) << "ray " << i << " was reported to miss";
        }
        if (got) {
          ++hits;
          expect_same(a, b, i);
          EXPECT_EQ(t, b.t);
          expected[i % 4] = b;
          expected_bits |= 1 << (i % 4);
        }
        if (i % 4 == 3) {
          SurfaceHit four[4];
          ASSERT_EQ(deferred.packet_hits(four), expected_bits) << "rays " << i - 3 << "-" << i;
          for (int k = 0; k < 4; ++k)
            if ((expected_bits >> k) & 1) expect_same(four[k], expected[k], i - 3 + k);
          expected_bits = 0;
        }
      }
    }
  }
  EXPECT_GT(hits, kEyes * kRowsPerEye * kRaysPerRow / 20);
}

INSTANTIATE_TEST_SUITE_P(Catalog, CatalogRays,
                         testing::Values("kummer", "cone", "planes", "sphere", "torus", "roman",
                                         "cayley", "clebsch", "barth6", "whitney", "dingdong"));

Surface equation_surface(const std::string& equation, double clip_radius) {
  Surface s = surface_from_equation(equation);
  s.clip = Clip::sphere(clip_radius);
  return s;
}

TEST(Raycast, HitsDoubleSphere) {
  const Surface s = equation_surface("(x^2 + y^2 + z^2 - 1)^2", 2);
  SurfaceRayCaster caster(s, Vec3(0, 0, 5));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.9, 0.9);
  for (int i = 0; i < 200; ++i) {
    // Aim at a point of the unit disk in the plane z = 0: the ray enters the sphere there.
    const Vec3 aim(u(rng), u(rng), 0);
    if (aim.norm() > 0.95) continue;
    const Vec3 dir = (aim - Vec3(0, 0, 5)).normalized();
    SurfaceHit hit;
    ASSERT_TRUE(caster.intersect(dir, hit)) << "aim " << aim.transpose();
    // |o + t d|² = 1: t = -(o·d) - sqrt((o·d)² - |o|² + 1).
    const double b = Vec3(0, 0, 5).dot(dir);
    const double expected = -b - std::sqrt(b * b - 24);
    EXPECT_NEAR(hit.t, expected, 1e-6);
    EXPECT_GT(hit.normal.dot(hit.point.normalized()), 0.999) << "normal must be radial";
  }
}

TEST(Raycast, HitsSphereAlongTangentRay) {
  const Surface s = equation_surface("x^2 + y^2 + z^2 - 1", 2);
  SurfaceRayCaster caster(s, Vec3(-5, 0, 1));
  SurfaceHit hit;
  ASSERT_TRUE(caster.intersect(Vec3(1, 0, 0), hit));
  EXPECT_NEAR(hit.t, 5.0, 1e-6);
  EXPECT_NEAR(hit.normal.z(), 1.0, 1e-6);
  // Just above the tangent point the ray misses.
  SurfaceRayCaster above(s, Vec3(-5, 0, 1 + 1e-6));
  EXPECT_FALSE(above.first_hit(Vec3(1, 0, 0)));
}

TEST(Raycast, HitsDoubleSphereAlongTangentRay) {
  const Surface s = equation_surface("(x^2 + y^2 + z^2 - 1)^2", 2);
  SurfaceRayCaster caster(s, Vec3(-5, 0.6, 0.8));
  const std::optional<double> t = caster.first_hit(Vec3(1, 0, 0));
  ASSERT_TRUE(t);
  EXPECT_NEAR(*t, 5.0, 1e-4);  // a quadruple root: accurate to the fourth root of rounding
}

/// Rows of rays from (-5, 0, 0) that sweep ever more finely across the rays tangent at z =
/// `tangent_z` to a unit sphere on the x axis: hit or miss is decided by the zero band near
/// the double root (or the quadruple root of a squared sphere). `packets` decides most misses
/// four rays at a time; it must decide each ray as `single` does alone, and report only rays
/// that miss. Counts the hits and misses.
void sweep_across_tangency(SurfaceRayCaster& packets, SurfaceRayCaster& single, double tangent_z,
                           int& hits, int& misses) {
  for (const double scale : {1e-2, 1e-3, 1e-5, 1e-8, 1e-11, 1e-14}) {
    // Directions (1, 0, z): s < 0 hits, s > 0 misses.
    const Vec3 base(1, 0, tangent_z), step(0, 0, scale);
    packets.begin_row(base, step);
    single.begin_row(base, step);
    for (int i = -64; i < 64; i += 4) {
      const double rays[4] = {i + 0.5, i + 1.5, i + 2.5, i + 3.5};
      const int reported = packets.prepare_in_row(rays);
      for (int k = 0; k < 4; ++k) {
        double t = NAN, expected = NAN;
        const bool got = packets.first_hit_in_row(rays[k], {}, t);
        ASSERT_EQ(got, single.first_hit_in_row(rays[k], {}, expected))
            << "scale " << scale << ", s " << rays[k];
        if (got) {
          EXPECT_EQ(t, expected) << "scale " << scale << ", s " << rays[k];
        }
        if ((reported >> k) & 1) {
          EXPECT_FALSE(got) << "scale " << scale << ", s " << rays[k];
        }
        hits += got;
        misses += !got;
      }
    }
  }
}

TEST(Raycast, PacketsCastTheSameAsSingleRaysAcrossTangency) {
  // Spheres about the origin, where the tangent point is the middle of the clipped segment,
  // and about (0.5, 0, 0), where it is not; plain and squared.
  struct Case {
    const char* equation;
    double tangent_z;  // 1 / sqrt(distance² − 1), the eye at `distance` from the centre
  };
  const Case cases[] = {{"x^2 + y^2 + z^2 - 1", 1 / std::sqrt(24.0)},
                        {"(x^2 + y^2 + z^2 - 1)^2", 1 / std::sqrt(24.0)},
                        {"(x - 0.5)^2 + y^2 + z^2 - 1", 1 / std::sqrt(29.25)},
                        {"((x - 0.5)^2 + y^2 + z^2 - 1)^2", 1 / std::sqrt(29.25)}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.equation);
    const Surface s = equation_surface(c.equation, 2);
    const Vec3 eye(-5, 0, 0);
    SurfaceRayCaster packets(s, eye), single(s, eye);
    int hits = 0, misses = 0;
    sweep_across_tangency(packets, single, c.tangent_z, hits, misses);
    EXPECT_GT(hits, 100);
    EXPECT_GT(misses, 100);
    // A tolerance so coarse that the search decides parts before the packets stop splitting.
    RaycastOptions coarse;
    coarse.roots.tolerance = 0.3;
    SurfaceRayCaster coarse_packets(s, eye, coarse), coarse_single(s, eye, coarse);
    sweep_across_tangency(coarse_packets, coarse_single, c.tangent_z, hits, misses);
  }
}

TEST(Raycast, ReportsWhichSideTheEyeIsOn) {
  const Surface s = equation_surface("x^2 + y^2 + z^2 - 1", 2);
  SurfaceHit hit;
  SurfaceRayCaster outside(s, Vec3(0, 0, 3));
  ASSERT_TRUE(outside.intersect(Vec3(0, 0, -1), hit));
  EXPECT_TRUE(hit.front);  // F > 0 outside: ∇F points towards the eye
  EXPECT_NEAR(hit.t, 2.0, 1e-12);
  SurfaceRayCaster inside(s, Vec3(0, 0, 0.2));
  ASSERT_TRUE(inside.intersect(Vec3(0, 0, -1), hit));
  EXPECT_FALSE(hit.front);
  EXPECT_NEAR(hit.t, 1.2, 1e-12);
  EXPECT_NEAR(hit.normal.z(), 1.0, 1e-9) << "the normal faces the eye";
}

TEST(Raycast, HitsConeTipWithFallbackNormal) {
  const Surface s = equation_surface("x^2 + y^2 - z^2", 1);
  SurfaceRayCaster caster(s, Vec3(0, -3, 0));
  SurfaceHit hit;
  // Along the y axis the ray meets the cone only at its tip, where ∇F = 0.
  ASSERT_TRUE(caster.intersect(Vec3(0, 1, 0), hit));
  EXPECT_NEAR(hit.t, 3.0, 1e-6);
  EXPECT_TRUE(hit.normal.allFinite());
}

TEST(Raycast, RejectsSurfaceWithoutBoundedClip) {
  const Surface s = surface_from_equation("x^2 + y^2 - z^2");
  EXPECT_THROW(SurfaceRayCaster(s, Vec3(0, 0, 5)), BadInput);
}

TEST(Raycast, IntervalPathAgreesWithExactPath) {
  for (const char* name : {"kummer", "barth6", "torus"}) {
    const Surface surface = make_surface(*find_catalog_entry(name));
    const Vec3 eye = surface.camera.eye(surface.scene_radius());
    SurfaceRayCaster exact(surface, eye);
    RaycastOptions forced;
    forced.force_interval = true;
    SurfaceRayCaster interval(surface, eye, forced);
    ASSERT_FALSE(interval.is_exact());
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1, 1);
    int agree = 0, both = 0, n = 300;
    for (int i = 0; i < n; ++i) {
      const Vec3 dir = (surface.camera.target +
                        0.8 * surface.scene_radius() * Vec3(u(rng), u(rng), u(rng)) - eye)
                           .normalized();
      const auto a = exact.first_hit(dir), b = interval.first_hit(dir);
      both += a.has_value() && b.has_value();
      agree += a.has_value() == b.has_value() && (!a || std::abs(*a - *b) < 1e-7);
    }
    EXPECT_GT(both, n / 5) << name;
    // The interval path may drop two roots closer than its leaf width; nothing else differs.
    EXPECT_GE(agree, n * 98 / 100) << name;
  }
}

TEST(Raycast, CastsNonPolynomialSurfaceWithIntervals) {
  // A sphere written with a square root, and a gyroid-like trigonometric surface.
  const Surface s = equation_surface("sqrt(x^2 + y^2 + z^2) - 1", 2);
  SurfaceRayCaster caster(s, Vec3(0.3, 0.2, 5));
  ASSERT_FALSE(caster.is_exact());
  SurfaceHit hit;
  ASSERT_TRUE(caster.intersect(Vec3(0, 0, -1), hit));
  EXPECT_NEAR(hit.t, 5 - std::sqrt(1 - 0.13), 1e-9);
  EXPECT_TRUE(hit.front);

  const Surface g =
      equation_surface("sin(3*x)*cos(3*y) + sin(3*y)*cos(3*z) + sin(3*z)*cos(3*x)", 2);
  SurfaceRayCaster gyroid(g, Vec3(4, 3, 2));
  Evaluator ev(g.field);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  int hits = 0;
  for (int i = 0; i < 100; ++i) {
    const Vec3 dir = (Vec3(u(rng), u(rng), u(rng)) - Vec3(4, 3, 2)).normalized();
    if (gyroid.intersect(dir, hit)) {
      ++hits;
      EXPECT_LT(std::abs(ev.value(hit.point)), 1e-9);
    }
  }
  EXPECT_GT(hits, 50);
}

TEST(Raycast, PolynomialsTooHighToExpandAreCastWithIntervals) {
  // Degree 26 (below the root finder's limit, above the expansion limit) and degree 600: the
  // unit sphere either way.
  for (const char* equation : {"(x^2 + y^2 + z^2)^13 - 1", "(x^2 + y^2 + z^2)^300 - 1"}) {
    const Surface s = equation_surface(equation, 2);
    ASSERT_FALSE(s.field.is_expandable()) << equation;
    SurfaceRayCaster caster(s, Vec3(0.3, 0.2, 5));
    EXPECT_FALSE(caster.is_exact()) << equation;
    SurfaceHit hit;
    ASSERT_TRUE(caster.intersect(Vec3(0, 0, -1), hit)) << equation;
    EXPECT_NEAR(hit.t, 5 - std::sqrt(1 - 0.13), 1e-9) << equation;
  }
}

}  // namespace
}  // namespace zeroset
