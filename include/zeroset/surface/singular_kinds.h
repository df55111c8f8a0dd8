#pragma once
/// The kinds of curves and points of a surface's singular set (docs/singular.md), shared by the
/// analysis (zeroset/surface/singular_set.h) and the meshes that carry singular curves.
#include <cstdint>
#include <string_view>

namespace zeroset {

/// What a singular curve looks like across it, read from the Hessian H restricted to the plane
/// normal to the curve (a 2×2 form Q).
enum class CurveKind : std::uint8_t {
  kCrossing,    ///< Q indefinite: two real sheets cross along the curve (x·y = 0)
  kIsolated,    ///< Q definite: a real curve with no sheet through it (Whitney's handle)
  kDegenerate,  ///< Q singular all along (a cuspidal edge, or worse)
};

/// Special points of the singular set.
enum class SingularPointKind : std::uint8_t {
  kNode,        ///< an isolated singular point with an invertible Hessian (node, cone point)
  kPinch,       ///< a crossing curve turns isolated (Whitney umbrella point): det Q = 0
  kTriple,      ///< several curves meet, H = 0 there (three sheets through one point)
  kClipEnd,     ///< a curve leaves the clip volume
  kDegenerate,  ///< an isolated singular point with a singular Hessian (x² + y³ + z⁵)
};

std::string_view to_string(CurveKind kind);
std::string_view to_string(SingularPointKind kind);

}  // namespace zeroset
