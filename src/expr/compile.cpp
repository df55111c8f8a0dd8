#include <algorithm>
#include <array>
#include <climits>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "graph_detail.h"
#include "syntax_detail.h"
#include "tape_detail.h"
#include "zeroset/error.h"
#include "zeroset/expr/parse.h"

namespace zeroset {
namespace detail {
namespace {

/// Builds graph nodes from the syntax tree. Definitions are built once, in order, and shared
/// by every use (substitution without copying).
class Builder {
 public:
  Builder(const ProgramAst& program, Graph& graph) : program_(program), graph_(graph) {}

  int run() {
    for (const Definition& d : program_.definitions) locals_.push_back(build(d.root));
    return build(program_.root);
  }

 private:
  // Recursion is bounded by the parser's nesting limit: sums and products are flat nodes.
  int build(int index) {
    const AstNode& n = program_.nodes[static_cast<std::size_t>(index)];
    switch (n.kind) {
      case AstKind::kNumber:
      case AstKind::kConstant:
        return graph_.constant(n.value);
      case AstKind::kCoordinate:
        return graph_.coordinate(n.index);
      case AstKind::kParameter:
        return graph_.parameter(n.index);
      case AstKind::kLocal:
        return locals_[static_cast<std::size_t>(n.index)];
      case AstKind::kNeg:
        return graph_.unary(Op::kNeg, build(n.children[0]));
      case AstKind::kSum:
      case AstKind::kProduct: {
        const bool sum = n.kind == AstKind::kSum;
        int acc = build(n.children[0]);
        for (std::size_t i = 1; i < n.children.size(); ++i) {
          const bool first_op = n.signs[i] == (sum ? '+' : '*');
          const Op op = sum ? (first_op ? Op::kAdd : Op::kSub) : (first_op ? Op::kMul : Op::kDiv);
          acc = graph_.binary(op, acc, build(n.children[i]));
        }
        return acc;
      }
      case AstKind::kPower:
        return graph_.power(build(n.children[0]), build(n.children[1]));
      case AstKind::kCall:
        return graph_.unary(function_op(n.index), build(n.children[0]));
    }
    ZS_ASSERT(false);
  }

  static Op function_op(int f) {
    switch (static_cast<Function>(f)) {
      case Function::kSqrt:
        return Op::kSqrt;
      case Function::kExp:
        return Op::kExp;
      case Function::kLog:
        return Op::kLog;
      case Function::kSin:
        return Op::kSin;
      case Function::kCos:
        return Op::kCos;
      case Function::kTan:
        return Op::kTan;
      case Function::kAbs:
        return Op::kAbs;
    }
    ZS_ASSERT(false);
  }

  const ProgramAst& program_;
  Graph& graph_;
  std::vector<int> locals_;
};

Code unary_code(Op op) {
  switch (op) {
    case Op::kNeg:
      return Code::kNeg;
    case Op::kSquare:
      return Code::kSquare;
    case Op::kSqrt:
      return Code::kSqrt;
    case Op::kExp:
      return Code::kExp;
    case Op::kLog:
      return Code::kLog;
    case Op::kSin:
      return Code::kSin;
    case Op::kCos:
      return Code::kCos;
    case Op::kTan:
      return Code::kTan;
    case Op::kAbs:
      return Code::kAbs;
    case Op::kSign:
      return Code::kSign;
    default:
      break;
  }
  ZS_ASSERT(false);
}

/// Turns graph nodes into programs: uniform nodes (independent of x, y, z) become uniform
/// registers shared by all programs of the tape, varying nodes become instructions whose
/// slots are reused once their value is dead, which keeps a block's working set in L1.
class Emitter {
 public:
  Emitter(const Graph& graph, Tape& tape) : graph_(graph), tape_(tape) {}

  Program emit(std::span<const int> roots) {
    const auto count = std::max<std::size_t>(
        kInputSlots, static_cast<std::size_t>(*std::max_element(roots.begin(), roots.end())) + 1);
    std::vector<char> live(count, 0);
    for (const int r : roots) live[static_cast<std::size_t>(r)] = 1;
    for (std::size_t id = count; id-- > 0;) {
      if (live[id] == 0 || !has_operands(graph_.node(static_cast<int>(id)))) continue;
      const Graph::Node& n = graph_.node(static_cast<int>(id));
      live[static_cast<std::size_t>(n.a)] = 1;
      if (n.b >= 0) live[static_cast<std::size_t>(n.b)] = 1;
    }
    for (std::size_t id = 0; id < count; ++id)
      if (live[id] != 0 && !graph_.node(static_cast<int>(id)).varying)
        uniform_register(static_cast<int>(id));

    // A product whose only use is a sum is fused into it (a·b + c in one pass).
    std::vector<int> uses(count, 0);
    for (std::size_t id = 0; id < count; ++id) {
      const Graph::Node& n = graph_.node(static_cast<int>(id));
      if (live[id] == 0 || !n.varying || !has_operands(n)) continue;
      ++uses[static_cast<std::size_t>(n.a)];
      if (n.b >= 0) ++uses[static_cast<std::size_t>(n.b)];
    }
    for (const int r : roots) ++uses[static_cast<std::size_t>(r)];
    fused_.assign(count, -1);
    std::vector<char> absorbed(count, 0);
    for (std::size_t id = 0; id < count; ++id) {
      const Graph::Node& n = graph_.node(static_cast<int>(id));
      if (live[id] == 0 || (n.op != Op::kAdd && n.op != Op::kSub) || !graph_.node(n.a).varying ||
          !graph_.node(n.b).varying)
        continue;
      for (const int m : {n.a, n.b}) {
        const auto mi = static_cast<std::size_t>(m);
        if (graph_.node(m).op == Op::kMul && uses[mi] == 1 && absorbed[mi] == 0) {
          fused_[id] = m;
          absorbed[mi] = 1;
          break;
        }
      }
    }

    // Last instruction (node id) reading each varying value; roots stay live to the end.
    std::vector<int> last_use(count, -1);
    for (std::size_t id = 0; id < count; ++id) {
      const Graph::Node& n = graph_.node(static_cast<int>(id));
      if (live[id] == 0 || !n.varying || !has_operands(n) || absorbed[id] != 0) continue;
      for (const int o : reads(static_cast<int>(id)))
        if (o >= 0) last_use[static_cast<std::size_t>(o)] = static_cast<int>(id);
    }
    for (const int r : roots) last_use[static_cast<std::size_t>(r)] = INT_MAX;

    Program program;
    std::vector<std::int32_t> slot(count, -1);
    for (int axis = 0; axis < kInputSlots; ++axis) slot[static_cast<std::size_t>(axis)] = axis;
    std::vector<std::int32_t> free_slots;
    for (std::size_t id = kInputSlots; id < count; ++id) {
      const Graph::Node& n = graph_.node(static_cast<int>(id));
      if (live[id] == 0 || !n.varying || absorbed[id] != 0) continue;
      std::int32_t dst = program.slot_count;
      if (free_slots.empty()) {
        ++program.slot_count;
      } else {
        dst = free_slots.back();
        free_slots.pop_back();
      }
      program.code.push_back(fused_[id] >= 0 ? fused_instruction(static_cast<int>(id), dst, slot)
                                             : instruction(n, dst, slot));
      slot[id] = dst;
      // Freed only after dst is chosen, so no instruction writes a slot it reads.
      for (const int operand : reads(static_cast<int>(id))) {
        if (operand < kInputSlots) continue;
        const auto o = static_cast<std::size_t>(operand);
        if (last_use[o] == static_cast<int>(id) && slot[o] >= 0) {
          free_slots.push_back(slot[o]);
          slot[o] = -1;  // also guards against freeing it twice when a == b
        }
      }
    }
    for (const int r : roots) {
      const auto i = static_cast<std::size_t>(r);
      program.outputs.push_back(graph_.node(r).varying ? slot[i] : ~uniform_register(r));
    }
    return program;
  }

 private:
  static bool has_operands(const Graph::Node& n) {
    return n.op != Op::kConst && n.op != Op::kParam && n.a >= 0;
  }

  /// The varying values the instruction of node `id` reads (-1: none): its operands, or for
  /// a sum with a fused product, the product's operands and the other term.
  std::array<int, 3> reads(int id) const {
    const Graph::Node& n = graph_.node(id);
    std::array<int, 3> r = {n.a, n.b, -1};
    if (const int m = fused_[static_cast<std::size_t>(id)]; m >= 0)
      r = {graph_.node(m).a, graph_.node(m).b, n.a == m ? n.b : n.a};
    for (int& o : r)
      if (o >= 0 && !graph_.node(o).varying) o = -1;
    return r;
  }

  std::int32_t uniform_register(int id) {
    if (registers_.size() <= static_cast<std::size_t>(id))
      registers_.resize(static_cast<std::size_t>(graph_.size()), -1);
    std::int32_t& reg = registers_[static_cast<std::size_t>(id)];
    if (reg >= 0) return reg;
    const Graph::Node& n = graph_.node(id);
    UniformInstr u{n.op};
    if (n.op == Op::kConst) {
      u.value = n.value;
    } else if (n.op == Op::kParam) {
      u.a = n.a;
    } else {
      u.a = uniform_register(n.a);  // already registered: operands come first
      u.b = n.b >= 0 ? uniform_register(n.b) : 0;
    }
    tape_.uniforms.push_back(u);
    reg = static_cast<std::int32_t>(tape_.uniforms.size()) - 1;
    return reg;
  }

  Instr instruction(const Graph::Node& n, std::int32_t dst, const std::vector<std::int32_t>& slot) {
    if (is_unary(n.op)) return {unary_code(n.op), dst, slot[static_cast<std::size_t>(n.a)], 0};
    const bool va = graph_.node(n.a).varying;
    const bool vb = graph_.node(n.b).varying;
    const std::int32_t sa = va ? slot[static_cast<std::size_t>(n.a)] : uniform_register(n.a);
    const std::int32_t sb = vb ? slot[static_cast<std::size_t>(n.b)] : uniform_register(n.b);
    // In the *U codes the slot comes first and the uniform second.
    auto pick = [&](Code both, Code slot_first, Code uniform_first) -> Instr {
      if (va && vb) return {both, dst, sa, sb};
      if (va) return {slot_first, dst, sa, sb};
      return {uniform_first, dst, sb, sa};
    };
    switch (n.op) {
      case Op::kAdd:
        return pick(Code::kAdd, Code::kAddU, Code::kAddU);
      case Op::kSub:
        return pick(Code::kSub, Code::kSubVU, Code::kSubUV);
      case Op::kMul:
        return pick(Code::kMul, Code::kMulU, Code::kMulU);
      case Op::kDiv:
        return pick(Code::kDiv, Code::kDivVU, Code::kDivUV);
      case Op::kPow:
        ZS_ASSERT(va && !vb);  // Graph::power rewrites varying exponents
        return {Code::kPowU, dst, sa, sb};
      default:
        break;
    }
    ZS_ASSERT(false);
  }

  /// Node `id` is a sum into which the product fused_[id] is folded.
  Instr fused_instruction(int id, std::int32_t dst, const std::vector<std::int32_t>& slot) {
    const Graph::Node& n = graph_.node(id);
    const int m = fused_[static_cast<std::size_t>(id)];
    const Graph::Node& product = graph_.node(m);
    const int other = n.a == m ? n.b : n.a;
    const bool both = graph_.node(product.a).varying && graph_.node(product.b).varying;
    const int varying = graph_.node(product.a).varying ? product.a : product.b;
    const int uniform = varying == product.a ? product.b : product.a;
    Code code = Code::kMulAdd;
    if (n.op == Op::kSub) code = n.a == m ? Code::kMulSub : Code::kSubMul;
    Instr in{code, dst, slot[static_cast<std::size_t>(product.a)],
             slot[static_cast<std::size_t>(product.b)], slot[static_cast<std::size_t>(other)]};
    if (!both) {
      // The *MulU codes: a slot times a uniform register.
      in.code = code == Code::kMulAdd   ? Code::kMulUAdd
                : code == Code::kMulSub ? Code::kMulUSub
                                        : Code::kSubMulU;
      in.a = slot[static_cast<std::size_t>(varying)];
      in.b = uniform_register(uniform);
    }
    return in;
  }

  const Graph& graph_;
  Tape& tape_;
  std::vector<int> fused_;  ///< per node of the program being emitted: its fused product
  std::vector<std::int32_t> registers_;  ///< graph node → uniform register, -1 if none
};

std::shared_ptr<const Tape> compile(const ProgramAst& program, std::string_view source) {
  auto tape = std::make_shared<Tape>();
  tape->source = std::string(source);
  tape->parameters = program.parameters;
  for (std::size_t k = 0; k < program.parameters.size(); ++k)
    tape->parameter_indices.emplace(program.parameters[k], static_cast<int>(k));
  // Substituted definitions read better than the source unless they blow it up.
  tape->expression = print_expression(program, 3 * source.size() + 80);
  if (tape->expression.empty()) {
    const std::size_t first = source.find_first_not_of(" \t\r\n");
    const std::size_t last = source.find_last_not_of(" \t\r\n");
    tape->expression = std::string(source.substr(first, last - first + 1));
  }

  Graph graph;
  const int f = Builder(program, graph).run();
  const int fx = graph.derivative(f, graph.coordinate(0));
  const int fy = graph.derivative(f, graph.coordinate(1));
  const int fz = graph.derivative(f, graph.coordinate(2));
  std::vector<int> full = {f,
                           fx,
                           fy,
                           fz,
                           graph.derivative(fx, graph.coordinate(0)),
                           graph.derivative(fx, graph.coordinate(1)),
                           graph.derivative(fx, graph.coordinate(2)),
                           graph.derivative(fy, graph.coordinate(1)),
                           graph.derivative(fy, graph.coordinate(2)),
                           graph.derivative(fz, graph.coordinate(2))};
  for (const int dq : graph.parameter_derivatives(f, static_cast<int>(program.parameters.size())))
    full.push_back(dq);

  Emitter emitter(graph, *tape);
  const int value_root[] = {f};
  tape->value = emitter.emit(value_root);
  tape->gradient = emitter.emit(std::span<const int>(full).first(4));
  tape->full = emitter.emit(full);
  const std::int64_t degree = graph.node(f).degree;
  tape->degree = static_cast<int>(std::min<std::int64_t>(degree, INT_MAX));
  return tape;
}

}  // namespace
}  // namespace detail

ParseResult parse_field(std::string_view source) {
  ParseResult result;
  result.source = std::string(source);
  const detail::ProgramAst program = detail::parse_program(result.source, result.diagnostics);
  if (result.diagnostics.empty()) result.field = Field(detail::compile(program, result.source));
  return result;
}

Field compile_field(std::string_view source) {
  ParseResult result = parse_field(source);
  if (!result.ok()) {
    const Diagnostic& first = result.diagnostics.front();
    throw ParseError(first.message, first.line, first.column, result.format());
  }
  return std::move(*result.field);
}

}  // namespace zeroset
