#pragma once
// Java properties files (java.util.Properties.load): the syntax of SURFER's .jsurf files.
// Private to the surface module.
#include <map>
#include <string>
#include <string_view>

namespace zeroset::detail {

/// One entry: its unescaped value and the 1-based line its logical line starts on.
struct PropertyValue {
  std::string value;
  int line = 1;
};

/// Parses properties text: `key=value`, `key: value` or `key value` per logical line; lines
/// ending in an odd number of backslashes continue on the next line (its leading blanks
/// dropped); `#` and `!` start comment lines; \t \n \r \f \\ \uXXXX and \x (any other
/// character: itself) are escapes in keys and values; lines end in \n, \r\n or \r. A later
/// entry replaces an earlier one with the same key, as in Java. Throws BadInput
/// ("origin:LINE: ...") for a malformed \u escape.
std::map<std::string, PropertyValue> parse_properties(std::string_view text,
                                                      const std::string& origin);

/// Escapes `text` for a properties value (or, with `key`, a key): backslashes, leading blanks,
/// line breaks and characters outside printable ASCII (as \uXXXX), so that parse_properties
/// gives `text` back.
std::string escape_property(std::string_view text, bool key = false);

}  // namespace zeroset::detail
