#pragma once
// The expression graph between the syntax tree and the tape: hash-consed (every distinct
// operation exists once, so common subexpressions are shared), constant-folded, and
// differentiated symbolically. Private to the expr module.
#include <cstddef>
#include <cstdint>
#include <span>
#include <unordered_map>
#include <vector>

#include "tape_detail.h"

namespace zeroset::detail {

class Graph {
 public:
  struct Node {
    Op op;
    std::int32_t a = -1;   ///< first operand, or the parameter index of kParam
    std::int32_t b = -1;   ///< second operand of a binary operation
    double value = 0;      ///< kConst only
    bool varying = false;  ///< depends on x, y or z
    /// Total degree when a polynomial in x, y, z (anything not varying counts as a
    /// coefficient, degree 0); -1 otherwise. Saturates at kDegreeCap.
    std::int64_t degree = 0;
  };
  static constexpr std::int64_t kDegreeCap = std::int64_t{1} << 40;

  Graph();

  const Node& node(int id) const { return nodes_[static_cast<std::size_t>(id)]; }
  int size() const { return static_cast<int>(nodes_.size()); }

  int constant(double value);
  int coordinate(int axis) const { return axis; }  ///< x, y, z are nodes 0, 1, 2
  int parameter(int index);
  /// Operations, folded and simplified where that keeps the value (x+0 → x, x*1 → x, …).
  int unary(Op op, int a);
  int binary(Op op, int a, int b);
  /// a^b with the language's semantics: integer constant exponents become repeated
  /// multiplication, varying exponents exp(b·log a).
  int power(int a, int b);

  /// ∂root/∂wrt where wrt is a coordinate or parameter node.
  int derivative(int root, int wrt);
  /// ∂root/∂q_k for the parameters k = 0 .. count-1, all from one backward sweep (reverse
  /// mode): the work is the graph's size once, where `derivative` per parameter would take it
  /// once per parameter (quadratic for p1*x + ... + pn*x).
  std::vector<int> parameter_derivatives(int root, int count);

 private:
  struct Key {
    Op op;
    std::int32_t a, b;
    std::uint64_t bits;
    bool operator==(const Key&) const = default;
  };
  struct KeyHash {
    std::size_t operator()(const Key& k) const;
  };

  int intern(Node node);
  bool is_constant(int id, double value) const {
    return node(id).op == Op::kConst && node(id).value == value;
  }
  int integer_power(int a, std::int64_t n);
  /// True when `id` is u·r (or -r, u = -1) with u uniform and r varying.
  bool split_scaled(int id, int& factor, int& rest);
  /// a·b with uniform factors moved outwards, or -1 when neither operand has one.
  int mul_scaled(int a, int b);
  int derivative_rule(int id, std::span<const int> d);

  std::vector<Node> nodes_;
  std::unordered_map<Key, int, KeyHash> index_;
};

}  // namespace zeroset::detail
