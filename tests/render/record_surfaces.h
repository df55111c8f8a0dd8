#pragma once
// Surfaces with many nodes for their degree (the record holders SURFER's gallery shows), with
// the clip balls they are usually drawn in: the hardest inputs for exact ray casting, where
// F's terms are large and cancel near every node.
#include <algorithm>
#include <cmath>
#include <ostream>
#include <string>
#include <vector>

#include <fmt/core.h>

namespace zeroset::test {

struct RecordSurface {
  std::string name;
  std::string equation;           ///< or a catalog name
  std::vector<std::string> clip;  ///< --clip specs, intersected
};

/// The Chebyshev polynomial T_d(v) written out: T_0 = 1, T_1 = v, T_{k+1} = 2v T_k − T_{k−1}.
inline std::string chebyshev(int d, const char* v) {
  std::vector<long long> t0{1}, t1{0, 1};
  for (int k = 1; k < d; ++k) {
    std::vector<long long> t(t1.size() + 1, 0);
    for (size_t i = 0; i < t1.size(); ++i) t[i + 1] += 2 * t1[i];
    for (size_t i = 0; i < t0.size(); ++i) t[i] -= t0[i];
    t0 = t1;
    t1 = t;
  }
  const std::vector<long long>& c = d == 0 ? t0 : t1;
  std::string out;
  for (size_t i = 0; i < c.size(); ++i)
    if (c[i] != 0) out += fmt::format("{}({})*{}^{}", out.empty() ? "" : " + ", c[i], v, i);
  return "(" + out + ")";
}

/// Chmutov's surface of degree d: T_d(x) + T_d(y) + T_d(z) + 1 = 0, its nodes in the cube.
inline RecordSurface chmutov(int d) {
  return {fmt::format("chmutov{}", d),
          chebyshev(d, "x") + " + " + chebyshev(d, "y") + " + " + chebyshev(d, "z") + " + 1",
          {"sphere:1.8"}};
}

/// Labs' septic with 99 real nodes: a is the real root of 7a³ + 7a + 1 = 0.
inline RecordSurface labs_septic() {
  double a = -0.14;
  for (int k = 0; k < 20; ++k) a -= (7 * a * a * a + 7 * a + 1) / (21 * a * a + 7);
  const double a1 = (-12.0 / 7 * a - 384.0 / 49) * a - 8.0 / 7;
  const double a2 = (-32.0 / 7 * a + 24.0 / 49) * a - 4;
  const double a3 = (-4 * a + 24.0 / 49) * a - 4;
  const double a4 = (-8.0 / 7 * a + 8.0 / 49) * a - 8.0 / 7;
  const double a5 = (49 * a - 7) * a + 50;
  return {"labs7",
          fmt::format("r2 = x^2 + y^2\n"
                      "U = (z + 1)*r2 + ({:.17g}*z + {:.17g})*z^2 + ({:.17g}*z + {:.17g})\n"
                      "P = x*((x^2 - 21*y^2)*x^4 + (35*x^2 - 7*y^2)*y^4)"
                      " + z*(7*(((r2 - 8*z^2)*r2 + 16*z^4)*r2) - 64*z^6)\n"
                      "(z + {:.17g})*U^2 - P",
                      a1, a2, a3, a4, a5),
          {"sphere:3"}};
}

/// For test names and failure messages.
inline void PrintTo(const RecordSurface& s, std::ostream* os) { *os << s.name; }

inline std::vector<RecordSurface> record_surfaces() {
  std::vector<RecordSurface> s = {
      {"barth6",
       "phi = (1 + sqrt(5))/2\n"
       "4*(phi^2*x^2 - y^2)*(phi^2*y^2 - z^2)*(phi^2*z^2 - x^2) - (1 + 2*phi)*(x^2 + y^2 + z^2 - "
       "1)^2",
       {"sphere:1.8"}},
      {"barth10",
       "phi = (1 + sqrt(5))/2\n"
       "r2 = x^2 + y^2 + z^2\n"
       "8*(x^2 - phi^4*y^2)*(y^2 - phi^4*z^2)*(z^2 - phi^4*x^2)"
       "*(x^4 + y^4 + z^4 - 2*x^2*y^2 - 2*x^2*z^2 - 2*y^2*z^2)"
       " + (3 + 5*phi)*(r2 - 1)^2*(r2 - (2 - phi))^2",
       {"sphere:2.5"}},
      {"endrass8",
       "s = sqrt(2)\n"
       "r2 = x^2 + y^2\n"
       "V = -4*(1 + s)*r2^2 + (8*(2 + s)*z^2 + 2*(2 + 7*s))*r2 + z^2*(-16*z^2 + 8*(1 - 2*s))"
       " - (1 + 12*s)\n"
       "V^2 - 64*(x^2 - 1)*(y^2 - 1)*((x + y)^2 - 2)*((x - y)^2 - 2)",
       {"sphere:2.5"}},
      labs_septic(),
      {"togliatti5",
       "c = sqrt(5 - sqrt(5))\n"
       "64*(x - 1)*(x^4 - 4*x^3 - 10*x^2*y^2 - 4*x^2 + 16*x - 20*x*y^2 + 5*y^4 + 16 - 20*y^2)"
       " - 5*c*(2*z - c)*(4*(x^2 + y^2 + z^2) + (1 + 3*sqrt(5)))^2",
       {"sphere:3.0"}},
      {"sarti12",
       "l1 = x^4 + y^4 + z^4 + 1\n"
       "l2 = x^2*y^2 + z^2\n"
       "l3 = x^2*z^2 + y^2\n"
       "l4 = y^2*z^2 + x^2\n"
       "l5 = x*y*z\n"
       "22*(x^2 + y^2 + z^2 + 1)^6 - 243*(33*sqrt(5)*(l2*(l2 - l3)*l3 + l3*(l3 - l4)*l4"
       " + l4*(l4 - l2)*l2) + 19*(l2*(l2 + l3)*l3 + l3*(l3 + l4)*l4 + l4*(l4 + l2)*l2)"
       " + 10*(l2^3 + l3^3 + l4^3) - 14*l1*(l2*l3 + l2*l4 + l3*l4) + 2*l1^2*(l2 + l3 + l4)"
       " - 6*l1*(l2^2 + l3^2 + l4^2) - 352*l5^2*(l2 + l3 + l4) + 336*l5^2*l1 + 48*l2*l3*l4)",
       {"sphere:3.0"}},
      {"cayley", "4*(x^2 + y^2 + z^2) + 16*x*y*z - 1", {"sphere:1.5"}},
      {"cone", "x^2 + y^2 - z^2", {"sphere:1"}},
      {"cusp", "x^2 - y^3 + z^4 - z^2*y", {"sphere:1"}},
      {"tacnode", "(x^2 + y^2 + z^2 - 1)*(x^2 + y^2 + (z - 1.5)^2 - 0.25)", {"sphere:2"}},
      // Catalog surfaces, and record surfaces under other clips: boxes, cut-away planes, a
      // ball off the origin.
      {"clebsch", "clebsch", {"sphere:1.2"}},
      {"roman", "roman", {"sphere:0.6"}},
      {"whitney", "whitney", {"sphere:1"}},
      {"dingdong", "dingdong", {"sphere:1.5@0,0,0.2"}},
      {"torus", "torus", {"box:1.5"}},
      {"clebsch_plane", "clebsch", {"sphere:1.2", "plane:1,1,1,0.3"}},
  };
  for (int d = 6; d <= 12; ++d) s.push_back(chmutov(d));
  // The record surfaces again, cut open or boxed.
  const auto again = [&](const std::string& of, const std::string& name,
                         std::vector<std::string> clip) {
    for (const RecordSurface& r : std::vector<RecordSurface>(s))
      if (r.name == of) s.push_back({name, r.equation, std::move(clip)});
  };
  again("endrass8", "endrass8_box", {"box:1.6"});
  again("sarti12", "sarti12_cut", {"sphere:3", "plane:0,0,1,0.3"});
  again("barth10", "barth10_offset", {"sphere:2@0.5,0,0"});
  again("chmutov9", "chmutov9_box", {"box:1.1"});
  again("labs7", "labs7_cut", {"sphere:3", "plane:1,0,0,0.5"});
  for (double mu : {0.5, 1.0, 1.5, 2.0, 2.9, 5.0}) {
    // Kummer's quartic family in the catalog's form, across its range.
    s.push_back({fmt::format("kummer{}", mu),
                 fmt::format("mu = {}\n"
                             "p = 1 - z - sqrt(2)*x; q = 1 - z + sqrt(2)*x\n"
                             "r = 1 + z + sqrt(2)*y; s = 1 + z - sqrt(2)*y\n"
                             "(3 - mu)*(x^2 + y^2 + z^2 - mu)^2 - (3*mu - 1)*p*q*r*s",
                             mu),
                 {fmt::format("sphere:{}", std::max(3.0, 2 * std::sqrt(mu) + 1))}});
  }
  return s;
}

}  // namespace zeroset::test
