#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include "syntax_detail.h"
#include "zeroset/expr/parse.h"

namespace zeroset {

std::string Diagnostic::format(std::string_view source) const {
  std::string out = fmt::format("line {}, column {}: {}", line, column, message);
  // Find the line the diagnostic is on; a diagnostic past the end shows no source.
  std::size_t begin = 0;
  for (int l = 1; l < line && begin != std::string_view::npos; ++l) {
    begin = source.find('\n', begin);
    if (begin != std::string_view::npos) ++begin;
  }
  if (begin != std::string_view::npos && begin <= source.size()) {
    std::string_view text = source.substr(begin);
    text = text.substr(0, std::min(text.find('\n'), text.size()));
    if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
    // The caret line copies tabs from the source line so that the caret stays aligned.
    std::string pad;
    int chars = 0;
    for (std::size_t i = 0; i < text.size() && chars < column - 1; ++i) {
      if ((static_cast<unsigned char>(text[i]) & 0xC0U) == 0x80U) continue;
      pad += text[i] == '\t' ? '\t' : ' ';
      ++chars;
    }
    pad.append(static_cast<std::size_t>(std::max(0, column - 1 - chars)), ' ');
    out += fmt::format("\n  {}\n  {}^{}", text, pad,
                       std::string(static_cast<std::size_t>(std::max(0, length - 1)), '~'));
  }
  if (!hint.empty()) out += "\n  hint: " + hint;
  return out;
}

std::string ParseResult::format() const {
  std::string out;
  for (const Diagnostic& d : diagnostics) {
    if (!out.empty()) out += '\n';
    out += d.format(source);
  }
  return out;
}

namespace detail {
namespace {

constexpr std::array<std::string_view, 7> kFunctionNames = {"sqrt", "exp", "log", "sin",
                                                            "cos",  "tan", "abs"};
constexpr std::size_t kMaxDiagnostics = 20;

std::optional<Function> find_function(std::string_view name) {
  for (std::size_t i = 0; i < kFunctionNames.size(); ++i)
    if (kFunctionNames[i] == name) return static_cast<Function>(i);
  return std::nullopt;
}

int coordinate_index(std::string_view name) {
  if (name == "x") return 0;
  if (name == "y") return 1;
  if (name == "z") return 2;
  return -1;
}

bool is_constant_name(std::string_view name) { return name == "pi" || name == "e"; }

bool is_operator(TokenKind k) {
  return k == TokenKind::kPlus || k == TokenKind::kMinus || k == TokenKind::kStar ||
         k == TokenKind::kSlash || k == TokenKind::kCaret;
}

bool is_separator(TokenKind k) {
  return k == TokenKind::kSemicolon || k == TokenKind::kNewline || k == TokenKind::kEnd;
}

bool starts_operand(TokenKind k) {
  return k == TokenKind::kNumber || k == TokenKind::kIdentifier || k == TokenKind::kLParen;
}

std::string describe(const Token& t) {
  switch (t.kind) {
    case TokenKind::kNewline:
      return "the end of the line";
    case TokenKind::kEnd:
      return "the end of the input";
    default:
      return fmt::format("'{}'", t.text);
  }
}

/// A newline ends a definition only where a line could end: not inside parentheses, not after
/// an operator (the expression continues), not before a token that cannot start a line.
std::vector<Token> drop_continuation_newlines(const std::vector<Token>& tokens) {
  std::vector<Token> out;
  out.reserve(tokens.size());
  int depth = 0;
  for (std::size_t i = 0; i < tokens.size(); ++i) {
    const Token& t = tokens[i];
    if (t.kind == TokenKind::kNewline) {
      if (depth > 0 || out.empty()) continue;
      const TokenKind prev = out.back().kind;
      if (is_operator(prev) || prev == TokenKind::kLParen || prev == TokenKind::kComma ||
          prev == TokenKind::kEquals || prev == TokenKind::kSemicolon ||
          prev == TokenKind::kNewline)
        continue;
      std::size_t j = i + 1;
      while (tokens[j].kind == TokenKind::kNewline) ++j;  // kEnd terminates the scan
      const TokenKind next = tokens[j].kind;
      if (next == TokenKind::kStar || next == TokenKind::kSlash || next == TokenKind::kCaret ||
          next == TokenKind::kRParen || next == TokenKind::kEnd)
        continue;
    } else if (t.kind == TokenKind::kLParen) {
      ++depth;
    } else if (t.kind == TokenKind::kRParen) {
      depth = std::max(0, depth - 1);
    } else if (t.kind == TokenKind::kSemicolon) {
      depth = 0;
    }
    out.push_back(t);
  }
  return out;
}

/// Thrown inside the parser to abandon the current segment after its diagnostic is recorded.
struct SegmentFailed {};

class Parser {
 public:
  Parser(std::string_view source, std::vector<Diagnostic>& diagnostics)
      : tokens_(drop_continuation_newlines(lex(source))), diagnostics_(diagnostics) {}

  ProgramAst run() {
    struct Segment {
      std::size_t begin, end;  // tokens [begin, end); tokens_[end] is its separator
    };
    std::vector<Segment> segments;
    std::size_t begin = 0;
    for (std::size_t i = 0; i < tokens_.size(); ++i) {
      if (!is_separator(tokens_[i].kind)) continue;
      if (i > begin) segments.push_back({begin, i});
      begin = i + 1;
    }
    if (segments.empty()) {
      diagnostics_.push_back(
          {1, 1, 1, "empty input: expected an expression", "for example: x^2 + y^2 + z^2 - 1"});
      return std::move(program_);
    }
    for (std::size_t s = 0; s < segments.size() && diagnostics_.size() < kMaxDiagnostics; ++s) {
      pos_ = segments[s].begin;
      end_ = segments[s].end;
      const bool last = s + 1 == segments.size();
      defining_ = {};
      try {
        const bool defines = tokens_[pos_].kind == TokenKind::kIdentifier &&
                             tokens_[pos_ + 1].kind == TokenKind::kEquals;
        if (!last) {
          if (!defines)
            fail(tokens_[pos_], "expected a definition 'name = expression' on this line",
                 "only the last line is the surface's expression; if it continues on the next "
                 "line, end this line with an operator");
          definition();
        } else if (defines && tokens_[end_].kind == TokenKind::kSemicolon &&
                   !is_reserved(tokens_[pos_].text)) {
          fail(tokens_[pos_],
               fmt::format("the definition of '{}' is not followed by the surface's expression",
                           tokens_[pos_].text),
               "end with the expression that uses the definitions, e.g. 'p = 1 - z; p^2 - x'");
        } else {
          final_expression();
        }
      } catch (const SegmentFailed&) {
        // The diagnostic is recorded; go on with the next segment to report more problems.
      }
    }
    return std::move(program_);
  }

 private:
  const Token& peek() const { return tokens_[std::min(pos_, end_)]; }
  const Token& take() {
    const Token& t = peek();
    if (pos_ < end_) ++pos_;
    return t;
  }
  bool at(TokenKind k) const { return peek().kind == k; }

  [[noreturn]] void fail(const Token& t, std::string message, std::string hint = {}) {
    diagnostics_.push_back(
        {t.line, t.column, std::max(1, t.length), std::move(message), std::move(hint)});
    throw SegmentFailed{};
  }

  int add(AstNode node) {
    program_.nodes.push_back(std::move(node));
    return static_cast<int>(program_.nodes.size()) - 1;
  }

  static bool is_reserved(std::string_view name) {
    return coordinate_index(name) >= 0 || is_constant_name(name) || find_function(name);
  }

  void definition() {
    const Token name = take();
    const std::string_view n = name.text;
    if (coordinate_index(n) >= 0)
      fail(name, fmt::format("cannot define '{}': x, y and z are the coordinates", n),
           "choose another name");
    if (is_constant_name(n))
      fail(name, fmt::format("cannot redefine the constant '{}'", n), "choose another name");
    if (find_function(n))
      fail(name, fmt::format("cannot define '{}': it is a function", n), "choose another name");
    if (const auto it = locals_.find(n); it != locals_.end())
      fail(name,
           fmt::format("'{}' is already defined on line {}", n,
                       program_.definitions[static_cast<std::size_t>(it->second)].line),
           "choose another name");
    if (const auto it = parameter_uses_.find(n); it != parameter_uses_.end())
      fail(it->second, fmt::format("'{}' is used before its definition on line {}", n, name.line),
           fmt::format("move the definition of '{}' above its first use", n));
    take();  // '='
    defining_ = n;
    // Registered even if the body fails, so later lines do not report it again as unknown.
    locals_.emplace(n, static_cast<int>(program_.definitions.size()));
    program_.definitions.push_back({n, -1, name.line});
    depth_ = 0;
    const int root = sum();
    defining_ = {};
    if (at(TokenKind::kEquals))
      fail(peek(), "a definition has only one '='", "write one definition per line");
    expect_segment_end();
    program_.definitions.back().root = root;
  }

  void final_expression() {
    depth_ = 0;
    int root = sum();
    if (at(TokenKind::kEquals)) {
      take();
      const int rhs = sum();
      if (at(TokenKind::kEquals))
        fail(peek(), "an equation has only one '='", "write the surface as 'lhs = rhs'");
      AstNode diff{AstKind::kSum};
      diff.children = {root, rhs};
      diff.signs = "+-";
      root = add(std::move(diff));
    }
    expect_segment_end();
    program_.root = root;
  }

  void expect_segment_end() {
    if (!is_separator(peek().kind)) unexpected(peek(), nullptr);
  }

  /// Reports the token `t` found where an operator, a separator or (when `open` is given)
  /// the ')' closing `open` was expected.
  [[noreturn]] void unexpected(const Token& t, const Token* open) {
    if (t.kind == TokenKind::kBadNumber || t.kind == TokenKind::kBadCharacter) lexical_error(t);
    if (starts_operand(t.kind)) {
      const Token& prev = tokens_[pos_ - 1];
      std::string hint = "implicit multiplication is not supported: write '*' for a product";
      if (prev.kind == TokenKind::kNumber && t.kind == TokenKind::kIdentifier)
        hint = fmt::format("did you mean {}*{}?", prev.text, t.text);
      else if (prev.kind == TokenKind::kIdentifier && t.kind == TokenKind::kLParen)
        hint = fmt::format("did you mean {}*(...)?", prev.text);
      fail(t, "expected an operator", hint);
    }
    if (open != nullptr) {
      const std::string where = open->line == t.line
                                    ? fmt::format("column {}", open->column)
                                    : fmt::format("line {}, column {}", open->line, open->column);
      fail(t, fmt::format("missing ')' to close '(' at {}", where));
    }
    switch (t.kind) {
      case TokenKind::kRParen:
        fail(t, "unmatched ')'", "remove it, or add the '(' it closes");
      case TokenKind::kComma:
        fail(t, "unexpected ','", "',' only separates the arguments of a function");
      default:
        fail(t, fmt::format("unexpected {}", describe(t)));
    }
  }

  [[noreturn]] void lexical_error(const Token& t) {
    if (t.kind == TokenKind::kBadNumber)
      fail(t, fmt::format("malformed number '{}'", t.text), "numbers look like 2, 1.5, .5 or 2e-3");
    const auto byte = static_cast<unsigned char>(t.text[0]);
    if (t.text.size() == 1 && (byte < 0x20U || byte >= 0x7FU))
      fail(t, fmt::format("unexpected byte 0x{:02X}", static_cast<unsigned>(byte)));
    std::string hint;
    if (t.text == "×" || t.text == "·" || t.text == "⋅") hint = "write '*' for a product";
    if (t.text == "−" || t.text == "–") hint = "write '-' for a minus sign";
    if (t.text == "²" || t.text == "³") hint = "write powers with '^', e.g. x^2";
    if (t.text == "[" || t.text == "{") hint = "group with '(' and ')'";
    fail(t, fmt::format("unexpected character '{}'", t.text), hint);
  }

  // sum := product { ('+' | '-') product }
  int sum() {
    const int first = product();
    if (!at(TokenKind::kPlus) && !at(TokenKind::kMinus)) return first;
    AstNode node{AstKind::kSum};
    node.children.push_back(first);
    node.signs.push_back('+');
    while (at(TokenKind::kPlus) || at(TokenKind::kMinus)) {
      node.signs += take().kind == TokenKind::kPlus ? '+' : '-';
      node.children.push_back(product());
    }
    return add(std::move(node));
  }

  // product := unary { ('*' | '/') unary }
  int product() {
    const int first = unary();
    if (!at(TokenKind::kStar) && !at(TokenKind::kSlash)) return first;
    AstNode node{AstKind::kProduct};
    node.children.push_back(first);
    node.signs.push_back('*');
    while (at(TokenKind::kStar) || at(TokenKind::kSlash)) {
      node.signs += take().kind == TokenKind::kStar ? '*' : '/';
      node.children.push_back(unary());
    }
    return add(std::move(node));
  }

  // unary := ('-' | '+') unary | power. Every level of nesting passes through here, so this
  // is where the depth is limited (the parser recurses, and so do the later passes).
  int unary() {
    if (++depth_ > kMaxNesting)
      fail(peek(),
           fmt::format("the expression is nested too deeply (more than {} levels)", kMaxNesting),
           "use definitions to split it");
    int result = 0;
    if (at(TokenKind::kMinus)) {
      take();
      AstNode node{AstKind::kNeg};
      node.children.push_back(unary());
      result = add(std::move(node));
    } else if (at(TokenKind::kPlus)) {
      take();
      result = unary();
    } else {
      result = power();
    }
    --depth_;
    return result;
  }

  // power := primary [ '^' unary ]   (right-associative; -x^2 is -(x^2), x^-2 is allowed)
  int power() {
    const int base = primary();
    if (!at(TokenKind::kCaret)) return base;
    take();
    AstNode node{AstKind::kPower};
    node.children = {base, unary()};
    return add(std::move(node));
  }

  int primary() {
    const Token& t = peek();
    switch (t.kind) {
      case TokenKind::kNumber:
        return number(take());
      case TokenKind::kIdentifier:
        return identifier(take());
      case TokenKind::kLParen: {
        const Token& open = take();
        if (at(TokenKind::kRParen)) fail(open, "expected an expression inside '()'");
        const int inner = sum();
        if (!at(TokenKind::kRParen)) unexpected(peek(), &open);
        take();
        return inner;
      }
      case TokenKind::kBadNumber:
      case TokenKind::kBadCharacter:
        lexical_error(t);
      default:
        missing_operand(t);
    }
  }

  [[noreturn]] void missing_operand(const Token& t) {
    const bool at_start = pos_ == 0 || is_separator(tokens_[pos_ - 1].kind);
    if (at_start) fail(t, fmt::format("expected an expression, found {}", describe(t)));
    const Token& prev = tokens_[pos_ - 1];
    const std::string found =
        is_separator(t.kind) ? std::string() : fmt::format(", found {}", describe(t));
    if (is_operator(prev.kind))
      fail(prev, fmt::format("expected an operand after '{}'{}", prev.text, found));
    fail(prev, fmt::format("expected an expression after '{}'{}", prev.text, found));
  }

  int number(const Token& t) {
    AstNode node{AstKind::kNumber};
    node.text = t.text;
    const char* first = t.text.data();
    const char* last = first + t.text.size();
    const auto [ptr, ec] = std::from_chars(first, last, node.value);
    if (ec == std::errc::result_out_of_range)
      fail(t, fmt::format("the number '{}' is out of the range of double precision", t.text));
    if (ec != std::errc() || ptr != last)
      fail(t, fmt::format("malformed number '{}'", t.text), "numbers look like 2, 1.5, .5 or 2e-3");
    return add(std::move(node));
  }

  int identifier(const Token& t) {
    const std::string_view name = t.text;
    if (const auto f = find_function(name)) return call(t, *f);
    const bool is_local = locals_.count(name) != 0;
    if (at(TokenKind::kLParen) && !is_local && coordinate_index(name) < 0 &&
        !is_constant_name(name))
      fail(t, fmt::format("unknown function '{}'", name),
           fmt::format("the functions are sqrt, exp, log, sin, cos, tan and abs; for a product "
                       "write {}*(...)",
                       name));
    AstNode node{AstKind::kParameter};
    node.text = name;
    if (const int axis = coordinate_index(name); axis >= 0) {
      node.kind = AstKind::kCoordinate;
      node.index = axis;
    } else if (is_constant_name(name)) {
      node.kind = AstKind::kConstant;
      node.value = name == "pi" ? 3.14159265358979323846 : 2.71828182845904523536;
    } else if (name == defining_) {
      fail(t, fmt::format("'{}' is used in its own definition", name),
           "a definition can only use coordinates, parameters and earlier definitions");
    } else if (is_local) {
      node.kind = AstKind::kLocal;
      node.index = locals_.at(name);
    } else {
      parameter_uses_.emplace(name, t);
      // By a hash, not a search of the list: an equation with many parameters stays linear.
      const auto [it, is_new] =
          parameter_indices_.emplace(name, static_cast<int>(program_.parameters.size()));
      if (is_new) program_.parameters.emplace_back(name);
      node.index = it->second;
    }
    return add(std::move(node));
  }

  int call(const Token& name, Function f) {
    if (!at(TokenKind::kLParen))
      fail(name, fmt::format("expected '(' after the function '{}'", name.text),
           fmt::format("write {}(x)", name.text));
    const Token& open = take();
    AstNode node{AstKind::kCall};
    node.index = static_cast<int>(f);
    node.text = name.text;
    if (!at(TokenKind::kRParen)) {
      node.children.push_back(sum());
      while (at(TokenKind::kComma)) {
        take();
        node.children.push_back(sum());
      }
    }
    if (!at(TokenKind::kRParen)) unexpected(peek(), &open);
    take();
    if (node.children.size() != 1)
      fail(name, fmt::format("'{}' takes 1 argument, but {} {} given", name.text,
                             node.children.size(), node.children.size() == 1 ? "was" : "were"));
    return add(std::move(node));
  }

  std::vector<Token> tokens_;
  std::vector<Diagnostic>& diagnostics_;
  ProgramAst program_;
  std::size_t pos_ = 0;
  std::size_t end_ = 0;
  int depth_ = 0;
  std::string_view defining_;  ///< name of the definition being parsed, to catch recursion
  std::unordered_map<std::string_view, int> locals_;
  std::unordered_map<std::string_view, Token> parameter_uses_;   ///< first use of each name
  std::unordered_map<std::string_view, int> parameter_indices_;  ///< in program_.parameters
};

/// Precedence levels for printing: a child with a lower level than its context needs ().
enum Level { kSumLevel = 1, kProductLevel = 2, kNegLevel = 3, kPowerLevel = 4, kAtomLevel = 5 };

class Printer {
 public:
  Printer(const ProgramAst& program, std::size_t max_length)
      : program_(program), max_length_(max_length) {}

  std::string run() {
    print(program_.root, 0);
    return overflow_ ? std::string() : std::move(out_);
  }

 private:
  /// Follows local references: a local prints as its definition.
  int resolve(int node) const {
    while (program_.nodes[static_cast<std::size_t>(node)].kind == AstKind::kLocal)
      node = program_
                 .definitions[static_cast<std::size_t>(
                     program_.nodes[static_cast<std::size_t>(node)].index)]
                 .root;
    return node;
  }

  static int level(const AstNode& n) {
    switch (n.kind) {
      case AstKind::kSum:
        return kSumLevel;
      case AstKind::kProduct:
        return kProductLevel;
      case AstKind::kNeg:
        return kNegLevel;
      case AstKind::kPower:
        return kPowerLevel;
      default:
        return kAtomLevel;
    }
  }

  void print(int index, int min_level) {
    // Substituting definitions can make the text grow exponentially and the nesting deep.
    if (overflow_ || out_.size() > max_length_ || depth_ > 4 * kMaxNesting) {
      overflow_ = true;
      return;
    }
    ++depth_;
    const AstNode& n = program_.nodes[static_cast<std::size_t>(resolve(index))];
    const bool parens = level(n) < min_level;
    if (parens) out_ += '(';
    switch (n.kind) {
      case AstKind::kNumber:
      case AstKind::kConstant:
      case AstKind::kParameter:
      case AstKind::kCoordinate:
      case AstKind::kLocal:
        out_ += n.text;
        break;
      case AstKind::kNeg:
        out_ += '-';
        print(n.children[0], kPowerLevel);
        break;
      case AstKind::kSum:
        for (std::size_t i = 0; i < n.children.size(); ++i) {
          if (i > 0) out_ += n.signs[i] == '+' ? " + " : " - ";
          print(n.children[i], i == 0 ? kSumLevel : kProductLevel);
        }
        break;
      case AstKind::kProduct:
        for (std::size_t i = 0; i < n.children.size(); ++i) {
          if (i > 0) out_ += n.signs[i];
          print(n.children[i], i == 0 ? kProductLevel : kNegLevel);
        }
        break;
      case AstKind::kPower:
        print(n.children[0], kAtomLevel);
        out_ += '^';
        print(n.children[1], kNegLevel);
        break;
      case AstKind::kCall:
        out_ += n.text;
        out_ += '(';
        print(n.children[0], 0);
        out_ += ')';
        break;
    }
    if (parens) out_ += ')';
    --depth_;
  }

  const ProgramAst& program_;
  std::size_t max_length_;
  std::string out_;
  int depth_ = 0;
  bool overflow_ = false;
};

}  // namespace

ProgramAst parse_program(std::string_view source, std::vector<Diagnostic>& diagnostics) {
  return Parser(source, diagnostics).run();
}

std::string print_expression(const ProgramAst& program, std::size_t max_length) {
  return Printer(program, max_length).run();
}

}  // namespace detail
}  // namespace zeroset
