#pragma once
// Placing the polygonizer's vertices on the crossing edges (vertex_placement.cpp).
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <stop_token>
#include <vector>

#include "line_restriction_detail.h"
#include "polygonize_detail.h"
#include "zeroset/detail/bracket.h"
#include "zeroset/expr/field.h"
#include "zeroset/expr/polynomial.h"

namespace zeroset::detail {

// Places one vertex on each crossing edge: linear interpolation, then refinement on F
// restricted to the edge. Polynomials: F along the edge is a univariate polynomial (its grid
// line's restriction), so each step is one Horner pass for F and F', and Newton's method
// converges in three or four steps from the linear start; it runs inside the Illinois
// bracket, whose estimate takes over when Newton's steps stop shrinking fast (a double root,
// where Newton would crawl). Other fields: the Illinois method, all edges of a batch
// evaluated together through the field's tape. One per worker.
class VertexPlacer {
 public:
  VertexPlacer(const Field& field, const Grid& grid, const Polynomial* poly, int steps)
      : grid_(grid), steps_(steps) {
    if (steps <= 0) return;  // linear points only: place_batched evaluates nothing
    if (!poly || poly->degree() < 1) {
      eval_.emplace(field);
      return;
    }
    for (int a = 0; a < 3; ++a) lines_[static_cast<size_t>(a)].emplace(*poly, grid, a);
    nc_ = static_cast<size_t>(poly->degree() + 1);
    coeffs_.resize(nc_ * kStride);
  }

  /// False when vertices stay at the linear interpolation (no refinement steps).
  bool refines() const { return steps_ > 0; }

  /// Places the vertices of `in` into `out`; a crossing that is not a zero of F (an end where
  /// F is not finite, or a pole: see clearly_refined) gets no_vertex(). Counts the refinement
  /// evaluations, and the crossings refused for a pole or a jump in `poles`.
  void place(std::span<const Crossing> in, Vec3* out, long long& evaluations, long long& poles) {
    if (lines_[0])
      place_polynomial(in, out, evaluations);
    else
      place_batched(in, out, evaluations, poles);
    for (size_t n = 0; n < in.size(); ++n)
      if (!finite_ends(in[n].fa, in[n].fb)) out[n] = no_vertex();
  }

 private:
  Vec3 point(const Crossing& c, double s) const {
    Vec3 p = grid_.node(c.i, c.j, c.k);
    p[c.axis] += std::clamp(s, 0.0, 1.0) * grid_.h;
    return p;
  }

  // Edges are refined in lockstep blocks of kLanes: each step is a chain of dependent
  // multiply-adds and divisions, so independent edges side by side keep the processor busy
  // (and the Horner loop is one vector operation per four lanes). Finished lanes stay put.
  // The coefficients of kChunk edges at a time are held lane by lane: coeffs_[m · kStride +
  // edge], kLanes columns to spare for a last block or four-line pass that runs over.
  static constexpr int kLanes = 8;
  static constexpr size_t kChunk = 256, kStride = kChunk + kLanes;

  void place_polynomial(std::span<const Crossing> in, Vec3* out, long long& evaluations);
  void fill_chunk(std::span<const Crossing> in, const std::uint32_t* edge, size_t len);
  long long refine_block(size_t b, int lanes);
  void place_batched(std::span<const Crossing> in, Vec3* out, long long& evaluations,
                     long long& poles);

  std::optional<Evaluator> eval_;  // fields that are not polynomials
  const Grid& grid_;
  int steps_;
  std::array<std::optional<LineRestriction>, 3> lines_;
  // Polynomials: the edges in the order they are taken, counting-sort buckets, and per edge of
  // a chunk its line's coefficients (nc_ of them), t of its lower node, end values and
  // fraction s.
  std::vector<std::uint32_t> order_;
  std::vector<size_t> bucket_;
  std::vector<double> fraction_;
  size_t nc_ = 0;
  std::vector<double> coeffs_;
  double t0_[kChunk + kLanes], fa_[kChunk + kLanes], fb_[kChunk + kLanes], s_[kChunk + kLanes];
  // Other fields.
  std::vector<IllinoisBracket> brackets_;
  std::vector<double> t_, x_, y_, z_, f_, smallest_;
  std::vector<size_t> active_;
};

// Places a batch of crossings split over the workers (chunks of a few thousand edges).
void place_vertices_parallel(std::vector<std::unique_ptr<VertexPlacer>>& placers, int workers,
                             const std::vector<Crossing>& in, Vec3* out, long long& evaluations,
                             long long& poles, const std::stop_token& stop);

}  // namespace zeroset::detail
