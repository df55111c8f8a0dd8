#pragma once
// Tokens, the syntax tree and the parser of the surface language. Private to the expr module.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "zeroset/expr/parse.h"

namespace zeroset::detail {

enum class TokenKind : std::uint8_t {
  kNumber,
  kIdentifier,
  kPlus,
  kMinus,
  kStar,
  kSlash,
  kCaret,  ///< '^' or '**'
  kLParen,
  kRParen,
  kComma,
  kEquals,
  kSemicolon,
  kNewline,
  kEnd,
  kBadNumber,     ///< a malformed number such as 1..2
  kBadCharacter,  ///< a character the language does not use
};

/// A token with its place in the source: 1-based line and column in characters (UTF-8 code
/// points), length in characters.
struct Token {
  TokenKind kind;
  std::string_view text;
  int line = 1;
  int column = 1;
  int length = 1;
};

/// Splits the source into tokens; skips blanks and `#` comments; always ends with kEnd, which
/// sits just after the last character that is not blank. Never fails: bad characters become
/// kBadCharacter and kBadNumber tokens for the parser to report.
std::vector<Token> lex(std::string_view source);

/// Number of characters (UTF-8 code points) in a byte string.
int count_characters(std::string_view text);

/// The seven functions of the language.
enum class Function : std::uint8_t { kSqrt, kExp, kLog, kSin, kCos, kTan, kAbs };

enum class AstKind : std::uint8_t {
  kNumber,      ///< value, text = lexeme
  kCoordinate,  ///< index 0, 1, 2 for x, y, z
  kConstant,    ///< value, text = "pi" or "e"
  kParameter,   ///< index into Program::parameters
  kLocal,       ///< index into Program::definitions
  kNeg,         ///< children[0]
  kSum,         ///< children with signs[i] '+' or '-' (signs[0] is '+')
  kProduct,     ///< children with signs[i] '*' or '/' (signs[0] is '*')
  kPower,       ///< children[0] ^ children[1]
  kCall,        ///< function(children[0])
};

struct AstNode {
  explicit AstNode(AstKind k) : kind(k) {}
  AstKind kind;
  int index = 0;
  double value = 0;
  std::string_view text;
  std::vector<int> children;
  std::string signs;
};

/// A local definition `name = expression`.
struct Definition {
  std::string_view name;
  int root = -1;
  int line = 1;
};

/// The parsed program. Definitions only refer to earlier definitions, so compiling them in
/// order resolves every reference.
struct ProgramAst {
  std::vector<AstNode> nodes;
  std::vector<Definition> definitions;
  std::vector<std::string> parameters;  ///< in order of first appearance
  int root = -1;                        ///< the final expression (an equation is lhs - rhs)
};

/// The deepest nesting of parentheses, unary minus and powers the parser accepts.
inline constexpr int kMaxNesting = 256;

/// Parses a whole program. Problems are appended to `diagnostics` (then the returned tree is
/// incomplete and must not be compiled). Never throws for bad text.
ProgramAst parse_program(std::string_view source, std::vector<Diagnostic>& diagnostics);

/// The final expression with definitions substituted, or "" when that would be longer than
/// `max_length` characters (the caller then shows the source instead).
std::string print_expression(const ProgramAst& program, std::size_t max_length);

}  // namespace zeroset::detail
