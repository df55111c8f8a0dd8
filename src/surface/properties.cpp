#include <fmt/core.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "properties_detail.h"
#include "zeroset/error.h"

namespace zeroset::detail {
namespace {

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\f'; }

void append_utf8(std::string& out, std::uint32_t cp) {
  if (cp < 0x80) {
    out += static_cast<char>(cp);
  } else if (cp < 0x800) {
    out += static_cast<char>(0xC0 | (cp >> 6));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  } else if (cp < 0x10000) {
    out += static_cast<char>(0xE0 | (cp >> 12));
    out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  } else {
    out += static_cast<char>(0xF0 | (cp >> 18));
    out += static_cast<char>(0x80 | ((cp >> 12) & 0x3F));
    out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  }
}

// A logical line: natural lines joined where a line ends in an odd number of backslashes.
struct LogicalLine {
  std::string text;
  int line = 1;
};

// Unescapes part of a logical line (a key or a value).
std::string unescape(std::string_view s, const std::string& origin, int line) {
  std::string out;
  std::uint32_t pending_high = 0;  // a UTF-16 high surrogate waiting for its low half
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] != '\\' || i + 1 >= s.size()) {
      out += s[i];
      continue;
    }
    const char c = s[++i];
    if (c != 'u') {
      out += c == 't' ? '\t' : c == 'n' ? '\n' : c == 'r' ? '\r' : c == 'f' ? '\f' : c;
      continue;
    }
    std::uint32_t unit = 0;
    for (int k = 0; k < 4; ++k) {
      const size_t j = i + 1 + static_cast<size_t>(k);
      const char h = j < s.size() ? s[j] : '\0';
      int digit = -1;
      if (h >= '0' && h <= '9') digit = h - '0';
      if (h >= 'a' && h <= 'f') digit = h - 'a' + 10;
      if (h >= 'A' && h <= 'F') digit = h - 'A' + 10;
      if (digit < 0)
        throw BadInput(
            fmt::format("{}:{}: malformed \\uXXXX escape '\\u{}' (four hex digits "
                        "expected)",
                        origin, line, s.substr(i + 1, 4)));
      unit = unit * 16 + static_cast<std::uint32_t>(digit);
    }
    i += 4;
    if (unit >= 0xD800 && unit < 0xDC00) {
      pending_high = unit;
      continue;
    }
    if (unit >= 0xDC00 && unit < 0xE000 && pending_high) {
      append_utf8(out, 0x10000 + ((pending_high - 0xD800) << 10) + (unit - 0xDC00));
    } else {
      append_utf8(out, unit);
    }
    pending_high = 0;
  }
  return out;
}

}  // namespace

std::map<std::string, PropertyValue> parse_properties(std::string_view text,
                                                      const std::string& origin) {
  // Natural lines, each with its number.
  std::vector<std::pair<std::string_view, int>> natural;
  {
    size_t start = 0;
    int number = 1;
    for (size_t i = 0; i <= text.size(); ++i) {
      if (i == text.size() || text[i] == '\n' || text[i] == '\r') {
        natural.push_back({text.substr(start, i - start), number++});
        if (i < text.size() && text[i] == '\r' && i + 1 < text.size() && text[i + 1] == '\n') ++i;
        start = i + 1;
      }
    }
  }
  std::map<std::string, PropertyValue> out;
  for (size_t n = 0; n < natural.size(); ++n) {
    std::string_view first = natural[n].first;
    size_t b = 0;
    while (b < first.size() && is_blank(first[b])) ++b;
    if (b == first.size() || first[b] == '#' || first[b] == '!') continue;  // blank or comment
    LogicalLine logical{std::string(first.substr(b)), natural[n].second};
    auto continues = [](const std::string& s) {
      size_t k = 0;
      while (k < s.size() && s[s.size() - 1 - k] == '\\') ++k;
      return k % 2 == 1;
    };
    while (continues(logical.text)) {
      logical.text.pop_back();
      if (++n >= natural.size()) break;  // a continuation at the end of the file: nothing more
      std::string_view next = natural[n].first;
      size_t k = 0;
      while (k < next.size() && is_blank(next[k])) ++k;
      logical.text += next.substr(k);
    }
    const std::string& s = logical.text;
    // The key runs to the first unescaped '=', ':' or blank.
    size_t k = 0;
    while (k < s.size()) {
      if (s[k] == '\\') {
        k += 2;
        continue;
      }
      if (s[k] == '=' || s[k] == ':' || is_blank(s[k])) break;
      ++k;
    }
    k = std::min(k, s.size());
    const size_t key_end = k;
    while (k < s.size() && is_blank(s[k])) ++k;
    if (k < s.size() && (s[k] == '=' || s[k] == ':')) ++k;
    while (k < s.size() && is_blank(s[k])) ++k;
    const std::string key = unescape(std::string_view(s).substr(0, key_end), origin, logical.line);
    out[key] = {unescape(std::string_view(s).substr(k), origin, logical.line), logical.line};
  }
  return out;
}

std::string escape_property(std::string_view text, bool key) {
  std::string out;
  for (size_t i = 0; i < text.size(); ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c == '\\') {
      out += "\\\\";
    } else if (c == '\n') {
      out += "\\n";
    } else if (c == '\r') {
      out += "\\r";
    } else if (c == '\t') {
      out += "\\t";
    } else if (c == '\f') {
      out += "\\f";
    } else if (c == ' ' && (key || i == 0)) {
      out += "\\ ";
    } else if (key && (c == '=' || c == ':' || c == '#' || c == '!')) {
      out += '\\';
      out += static_cast<char>(c);
    } else if (c >= 0x20 && c < 0x7F) {
      out += static_cast<char>(c);
    } else {
      // A UTF-8 sequence (or a stray byte, kept as its Latin-1 character) as \uXXXX units.
      std::uint32_t cp = c;
      int more = c >= 0xF0 ? 3 : c >= 0xE0 ? 2 : c >= 0xC0 ? 1 : 0;
      if (more && i + static_cast<size_t>(more) < text.size()) {
        cp = c & (0x3F >> more);
        for (int m = 0; m < more; ++m)
          cp = (cp << 6) | (static_cast<unsigned char>(text[++i]) & 0x3F);
      }
      auto unit = [&](std::uint32_t u) { out += fmt::format("\\u{:04X}", u); };
      if (cp >= 0x10000) {
        unit(0xD800 + ((cp - 0x10000) >> 10));
        unit(0xDC00 + ((cp - 0x10000) & 0x3FF));
      } else {
        unit(cp);
      }
    }
  }
  return out;
}

}  // namespace zeroset::detail
