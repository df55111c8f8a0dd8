#pragma once
/// Parsing the surface language (docs/architecture.md, "From text to output") into a compiled
/// `Field`.
///
/// Grammar (informal):
///   program    := { definition (';' | newline) } expression [ '=' expression ]
///   definition := identifier '=' expression          (a local name, usable afterwards)
///   expression := numbers, x y z, + - * / ^ ** (right-associative), unary minus, ( ),
///                 pi, e, sqrt exp log sin cos tan abs (...)
/// An equation `a = b` means a - b. Every other free identifier is a parameter.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "zeroset/expr/field.h"

namespace zeroset {

/// One problem found in the source text.
struct Diagnostic {
  int line = 1;         ///< 1-based line
  int column = 1;       ///< 1-based column (characters)
  int length = 1;       ///< how many characters the caret line underlines
  std::string message;  ///< what is wrong, e.g. "expected an operand after '+'"
  std::string hint;     ///< what to try, may be empty

  /// "line L, column C: message\n  <source line>\n  <caret line>\n  hint: ..." .
  std::string format(std::string_view source) const;
};

/// The outcome of parsing typed input: a field, or diagnostics. Never throws for bad text.
struct ParseResult {
  std::string source;
  std::vector<Diagnostic> diagnostics;
  std::optional<Field> field;

  bool ok() const { return field.has_value() && diagnostics.empty(); }
  /// All diagnostics formatted against the source, one after the other.
  std::string format() const;
};

/// Parses and compiles `source`. Parameters get no values here (see Field::set_parameter).
ParseResult parse_field(std::string_view source);

/// As parse_field, but throws ParseError (with line, column and caret) on bad input.
Field compile_field(std::string_view source);

}  // namespace zeroset
