#include <algorithm>
#include <bit>
#include <cstdint>
#include <span>
#include <vector>

#include "graph_detail.h"

namespace zeroset::detail {
namespace {

std::int64_t add_degrees(std::int64_t a, std::int64_t b) {
  if (a < 0 || b < 0) return -1;
  return std::min(a + b, Graph::kDegreeCap);
}

}  // namespace

std::size_t Graph::KeyHash::operator()(const Key& k) const {
  std::uint64_t h = k.bits * 0x9E3779B97F4A7C15ULL;
  h ^= (static_cast<std::uint64_t>(static_cast<std::uint32_t>(k.a)) << 32U) ^
       static_cast<std::uint32_t>(k.b);
  h *= 0xBF58476D1CE4E5B9ULL;
  h ^= static_cast<std::uint64_t>(k.op) + (h >> 29U);
  return static_cast<std::size_t>(h);
}

Graph::Graph() {
  for (const Op op : {Op::kX, Op::kY, Op::kZ}) intern({op, -1, -1, 0, true, 1});
}

int Graph::intern(Node node) {
  const Key key{node.op, node.a, node.b, std::bit_cast<std::uint64_t>(node.value)};
  const auto [it, inserted] = index_.try_emplace(key, size());
  if (inserted) nodes_.push_back(node);
  return it->second;
}

int Graph::constant(double value) { return intern({Op::kConst, -1, -1, value, false, 0}); }

int Graph::parameter(int index) { return intern({Op::kParam, index, -1, 0, false, 0}); }

int Graph::unary(Op op, int a) {
  const Node na = node(a);
  if (na.op == Op::kConst) return constant(apply(op, na.value, 0));
  if (op == Op::kNeg && na.op == Op::kNeg) return na.a;
  // -(u·r) = (-u)·r and (u·r)² = u²·r²: the uniform part is computed once per call.
  int factor = 0;
  int rest = 0;
  if ((op == Op::kNeg || op == Op::kSquare) && split_scaled(a, factor, rest))
    return binary(Op::kMul, unary(op, factor), op == Op::kNeg ? rest : unary(op, rest));
  Node n{op, a, -1, 0, na.varying, 0};
  if (na.varying) {
    if (op == Op::kNeg)
      n.degree = na.degree;
    else if (op == Op::kSquare)
      n.degree = add_degrees(na.degree, na.degree);
    else
      n.degree = -1;
  }
  return intern(n);
}

int Graph::binary(Op op, int a, int b) {
  if (op == Op::kPow) return power(a, b);
  const Node& na = node(a);
  const Node& nb = node(b);
  if (na.op == Op::kConst && nb.op == Op::kConst) return constant(apply(op, na.value, nb.value));
  // Simplifications that keep the value (up to NaN propagation through a factor 0), so that
  // derivatives do not drag chains of zeros and ones around.
  switch (op) {
    case Op::kAdd:
      if (is_constant(a, 0)) return b;
      if (is_constant(b, 0)) return a;
      if (nb.op == Op::kNeg) return binary(Op::kSub, a, nb.a);
      if (na.op == Op::kNeg) return binary(Op::kSub, b, na.a);
      break;
    case Op::kSub:
      if (is_constant(b, 0)) return a;
      if (is_constant(a, 0)) return unary(Op::kNeg, b);
      if (nb.op == Op::kNeg) return binary(Op::kAdd, a, nb.a);
      break;
    case Op::kMul:
      if (is_constant(a, 0) || is_constant(b, 0)) return constant(0);
      if (is_constant(a, 1)) return b;
      if (is_constant(b, 1)) return a;
      if (is_constant(a, -1)) return unary(Op::kNeg, b);
      if (is_constant(b, -1)) return unary(Op::kNeg, a);
      if (a == b) return unary(Op::kSquare, a);
      if (const int scaled = mul_scaled(a, b); scaled >= 0) return scaled;
      break;
    case Op::kDiv:
      if (is_constant(b, 1)) return a;
      if (is_constant(a, 0)) return constant(0);
      break;
    default:
      break;
  }
  // Commutative operations in a canonical order, so that a*b and b*a are one node.
  if ((op == Op::kAdd || op == Op::kMul) && a > b) std::swap(a, b);
  const Node& first = node(a);
  const Node& second = node(b);
  Node n{op, a, b, 0, first.varying || second.varying, 0};
  if (n.varying) {
    switch (op) {
      case Op::kAdd:
      case Op::kSub:
        n.degree =
            first.degree < 0 || second.degree < 0 ? -1 : std::max(first.degree, second.degree);
        break;
      case Op::kMul:
        n.degree = add_degrees(first.degree, second.degree);
        break;
      case Op::kDiv:
        n.degree = second.varying ? -1 : first.degree;
        break;
      default:
        n.degree = -1;
        break;
    }
  }
  return intern(n);
}

bool Graph::split_scaled(int id, int& factor, int& rest) {
  const Node n = node(id);
  if (!n.varying) return false;
  if (n.op == Op::kNeg) {
    factor = constant(-1);
    rest = n.a;
    return true;
  }
  if (n.op != Op::kMul || node(n.a).varying == node(n.b).varying) return false;
  factor = node(n.a).varying ? n.b : n.a;
  rest = node(n.a).varying ? n.a : n.b;
  return true;
}

int Graph::mul_scaled(int a, int b) {
  // Uniform factors move outwards, (u·r)·s = u·(r·s) and v·(u·r) = (v·u)·r, so that the
  // constants of a product (and of its derivatives: 2·a·da, …) meet and fold into one.
  const bool va = node(a).varying;
  const bool vb = node(b).varying;
  int factor = 0;
  int rest = 0;
  if (va && vb) {
    if (split_scaled(a, factor, rest)) return binary(Op::kMul, factor, binary(Op::kMul, rest, b));
    if (split_scaled(b, factor, rest)) return binary(Op::kMul, factor, binary(Op::kMul, a, rest));
  } else if (va != vb) {
    const int uniform = va ? b : a;
    if (split_scaled(va ? a : b, factor, rest))
      return binary(Op::kMul, binary(Op::kMul, uniform, factor), rest);
  }
  return -1;
}

int Graph::power(int a, int b) {
  const Node na = node(a);
  const Node nb = node(b);
  if (na.op == Op::kConst && nb.op == Op::kConst)
    return constant(detail::power(na.value, nb.value));
  if (nb.varying) return unary(Op::kExp, binary(Op::kMul, b, unary(Op::kLog, a)));
  if (nb.op == Op::kConst && is_exact_exponent(nb.value))
    return integer_power(a, static_cast<std::int64_t>(nb.value));
  // A parameter exponent: decided at run time (exact when it evaluates to an integer).
  return intern({Op::kPow, a, b, 0, na.varying, na.varying ? -1 : 0});
}

int Graph::integer_power(int a, std::int64_t n) {
  if (n == 0) return constant(1);
  if (n < 0) return binary(Op::kDiv, constant(1), integer_power(a, -n));
  // Square and multiply from the lowest bit, the same order as int_pow at run time; every
  // a^(2^k) is a node of its own and shared with the rest of the expression.
  int result = -1;
  int square = a;
  while (n != 0) {
    if (n & 1) result = result < 0 ? square : binary(Op::kMul, result, square);
    n >>= 1;
    if (n != 0) square = unary(Op::kSquare, square);
  }
  return result;
}

int Graph::derivative(int root, int wrt) {
  // Nodes are created after their operands, so ids are a topological order: one forward
  // sweep over the nodes root depends on differentiates each exactly once (no recursion,
  // whatever the depth of the expression).
  const auto count = static_cast<std::size_t>(root) + 1;
  std::vector<char> live(count, 0);
  live[count - 1] = 1;
  for (std::size_t id = count; id-- > 0;) {
    if (live[id] == 0) continue;
    const Node& n = nodes_[id];
    if (n.op == Op::kConst || n.op == Op::kParam || n.a < 0) continue;
    live[static_cast<std::size_t>(n.a)] = 1;
    if (n.b >= 0) live[static_cast<std::size_t>(n.b)] = 1;
  }
  std::vector<int> d(count, -1);
  const int zero = constant(0);
  const int one = constant(1);
  for (std::size_t id = 0; id < count; ++id) {
    if (live[id] == 0) continue;
    const int i = static_cast<int>(id);
    if (i == wrt)
      d[id] = one;
    else if (nodes_[id].op == Op::kConst || nodes_[id].op == Op::kParam || nodes_[id].a < 0 ||
             (wrt <= 2 && !nodes_[id].varying))
      d[id] = zero;
    else
      d[id] = derivative_rule(i, d);
  }
  return d[count - 1];
}

std::vector<int> Graph::parameter_derivatives(int root, int count) {
  const auto n = static_cast<std::size_t>(root) + 1;
  // Which nodes depend on some parameter: adjoints flow only through them.
  std::vector<char> dep(n, 0);
  for (std::size_t id = 0; id < n; ++id) {
    const Node& nd = nodes_[id];
    if (nd.op == Op::kParam)
      dep[id] = 1;
    else if (nd.op != Op::kConst && nd.a >= 0)
      dep[id] =
          dep[static_cast<std::size_t>(nd.a)] || (nd.b >= 0 && dep[static_cast<std::size_t>(nd.b)]);
  }
  const int zero = constant(0);
  std::vector<int> adj(n, -1);  // ∂root/∂node as a node, -1 while nothing flowed in
  if (dep[n - 1]) adj[n - 1] = constant(1);
  const auto flow = [&](int to, int contribution) {
    const auto t = static_cast<std::size_t>(to);
    if (!dep[t]) return;
    adj[t] = adj[t] < 0 ? contribution : binary(Op::kAdd, adj[t], contribution);
  };
  // Ids are a topological order, so a node's adjoint is complete when the sweep reaches it.
  for (std::size_t i = n; i-- > 0;) {
    if (adj[i] < 0 || nodes_[i].op == Op::kParam) continue;
    const Node nd = nodes_[i];  // a copy: creating nodes may reallocate nodes_
    const int id = static_cast<int>(i), a = nd.a, b = nd.b, g = adj[i];
    switch (nd.op) {
      case Op::kNeg:
        flow(a, unary(Op::kNeg, g));
        break;
      case Op::kSquare:
        flow(a, binary(Op::kMul, binary(Op::kMul, constant(2), a), g));
        break;
      case Op::kSqrt:
        flow(a, binary(Op::kDiv, g, binary(Op::kMul, constant(2), id)));
        break;
      case Op::kExp:
        flow(a, binary(Op::kMul, id, g));
        break;
      case Op::kLog:
        flow(a, binary(Op::kDiv, g, a));
        break;
      case Op::kSin:
        flow(a, binary(Op::kMul, unary(Op::kCos, a), g));
        break;
      case Op::kCos:
        flow(a, unary(Op::kNeg, binary(Op::kMul, unary(Op::kSin, a), g)));
        break;
      case Op::kTan:
        flow(a, binary(Op::kMul, binary(Op::kAdd, constant(1), unary(Op::kSquare, id)), g));
        break;
      case Op::kAbs:
        flow(a, binary(Op::kMul, unary(Op::kSign, a), g));
        break;
      case Op::kAdd:
        flow(a, g);
        flow(b, g);
        break;
      case Op::kSub:
        flow(a, g);
        flow(b, unary(Op::kNeg, g));
        break;
      case Op::kMul:
        flow(a, binary(Op::kMul, g, b));
        flow(b, binary(Op::kMul, a, g));
        break;
      case Op::kDiv:  // ∂(a/b)/∂b = -(a/b)/b
        flow(a, binary(Op::kDiv, g, b));
        flow(b, unary(Op::kNeg, binary(Op::kDiv, binary(Op::kMul, id, g), b)));
        break;
      case Op::kPow:  // as in derivative_rule
        flow(a,
             binary(Op::kMul, binary(Op::kMul, b, power(a, binary(Op::kSub, b, constant(1)))), g));
        if (dep[static_cast<std::size_t>(b)])
          flow(b, binary(Op::kMul, binary(Op::kMul, id, unary(Op::kLog, a)), g));
        break;
      default:  // kSign (derivative 0), constants, coordinates
        break;
    }
  }
  std::vector<int> out(static_cast<std::size_t>(count), zero);
  for (int k = 0; k < count; ++k) {
    const auto it = index_.find(Key{Op::kParam, k, -1, std::bit_cast<std::uint64_t>(0.0)});
    if (it != index_.end() && static_cast<std::size_t>(it->second) < n &&
        adj[static_cast<std::size_t>(it->second)] >= 0)
      out[static_cast<std::size_t>(k)] = adj[static_cast<std::size_t>(it->second)];
  }
  return out;
}

int Graph::derivative_rule(int id, std::span<const int> d) {
  // A copy: creating nodes below may reallocate nodes_.
  const Node n = node(id);
  const int a = n.a;
  const int b = n.b;
  const int da = d[static_cast<std::size_t>(a)];
  const int db = b >= 0 ? d[static_cast<std::size_t>(b)] : constant(0);
  switch (n.op) {
    case Op::kNeg:
      return unary(Op::kNeg, da);
    case Op::kSquare:
      return binary(Op::kMul, binary(Op::kMul, constant(2), a), da);
    case Op::kSqrt:
      return binary(Op::kDiv, da, binary(Op::kMul, constant(2), id));
    case Op::kExp:
      return binary(Op::kMul, id, da);
    case Op::kLog:
      return binary(Op::kDiv, da, a);
    case Op::kSin:
      return binary(Op::kMul, unary(Op::kCos, a), da);
    case Op::kCos:
      return unary(Op::kNeg, binary(Op::kMul, unary(Op::kSin, a), da));
    case Op::kTan:
      return binary(Op::kMul, binary(Op::kAdd, constant(1), unary(Op::kSquare, id)), da);
    case Op::kAbs:
      return binary(Op::kMul, unary(Op::kSign, a), da);
    case Op::kSign:
      return constant(0);
    case Op::kAdd:
      return binary(Op::kAdd, da, db);
    case Op::kSub:
      return binary(Op::kSub, da, db);
    case Op::kMul:
      return binary(Op::kAdd, binary(Op::kMul, da, b), binary(Op::kMul, a, db));
    case Op::kDiv:
      return binary(Op::kDiv, binary(Op::kSub, da, binary(Op::kMul, id, db)), b);
    case Op::kPow: {
      // d(a^b) = b·a^(b-1)·da + a^b·log(a)·db; the exponent never depends on x, y, z, and the
      // second term only appears for the parameter it depends on.
      const int base_term =
          binary(Op::kMul, binary(Op::kMul, b, power(a, binary(Op::kSub, b, constant(1)))), da);
      if (is_constant(db, 0)) return base_term;
      const int exponent_term = binary(Op::kMul, binary(Op::kMul, id, unary(Op::kLog, a)), db);
      return binary(Op::kAdd, base_term, exponent_term);
    }
    case Op::kConst:
    case Op::kX:
    case Op::kY:
    case Op::kZ:
    case Op::kParam:
      break;
  }
  return constant(0);
}

}  // namespace zeroset::detail
