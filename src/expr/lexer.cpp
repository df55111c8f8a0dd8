#include <cstddef>
#include <string_view>
#include <vector>

#include "syntax_detail.h"

namespace zeroset::detail {
namespace {

bool is_digit(char c) { return c >= '0' && c <= '9'; }
bool is_identifier_start(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_';
}
bool is_identifier_char(char c) { return is_identifier_start(c) || is_digit(c); }
bool is_continuation_byte(char c) { return (static_cast<unsigned char>(c) & 0xC0U) == 0x80U; }

/// Byte length of the UTF-8 sequence starting with `lead`, so that a bad character is reported
/// whole. Invalid lead bytes count as one byte.
std::size_t utf8_length(char lead) {
  const auto b = static_cast<unsigned char>(lead);
  if (b >= 0xF0U && b < 0xF8U) return 4;
  if (b >= 0xE0U) return b < 0xF0U ? 3 : 1;
  if (b >= 0xC0U) return 2;
  return 1;
}

class Lexer {
 public:
  explicit Lexer(std::string_view source) : src_(source) {}

  std::vector<Token> run() {
    std::vector<Token> tokens;
    while (true) {
      skip_blanks_and_comments();
      if (pos_ >= src_.size()) break;
      tokens.push_back(next());
    }
    // End sits right after the last token, so "missing operand" and "missing ')'" point at
    // the end of the text instead of a line of trailing blanks.
    Token end{TokenKind::kEnd, {}, 1, 1, 1};
    if (!tokens.empty()) {
      const Token& last = tokens.back();
      end.line = last.line;
      end.column = last.kind == TokenKind::kNewline ? last.column : last.column + last.length;
    }
    tokens.push_back(end);
    return tokens;
  }

 private:
  void skip_blanks_and_comments() {
    while (pos_ < src_.size()) {
      const char c = src_[pos_];
      if (c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v') {
        ++pos_;
      } else if (c == '#') {
        while (pos_ < src_.size() && src_[pos_] != '\n') ++pos_;
      } else {
        break;
      }
    }
  }

  Token make(TokenKind kind, std::size_t begin, std::size_t end) {
    const std::string_view text = src_.substr(begin, end - begin);
    Token t{kind, text, line_, column_of(begin), count_characters(text)};
    pos_ = end;
    return t;
  }

  // Offsets only grow, so counting from the previous token keeps long lines linear.
  int column_of(std::size_t offset) {
    column_ += count_characters(src_.substr(counted_to_, offset - counted_to_));
    counted_to_ = offset;
    return column_;
  }

  Token next() {
    const std::size_t begin = pos_;
    const char c = src_[pos_];
    if (c == '\n') {
      Token t = make(TokenKind::kNewline, begin, begin + 1);
      ++line_;
      counted_to_ = pos_;
      column_ = 1;
      return t;
    }
    if (is_digit(c) || c == '.') return number(begin);
    if (is_identifier_start(c)) {
      std::size_t end = begin;
      while (end < src_.size() && is_identifier_char(src_[end])) ++end;
      return make(TokenKind::kIdentifier, begin, end);
    }
    switch (c) {
      case '+':
        return make(TokenKind::kPlus, begin, begin + 1);
      case '-':
        return make(TokenKind::kMinus, begin, begin + 1);
      case '*':
        if (begin + 1 < src_.size() && src_[begin + 1] == '*')
          return make(TokenKind::kCaret, begin, begin + 2);
        return make(TokenKind::kStar, begin, begin + 1);
      case '/':
        return make(TokenKind::kSlash, begin, begin + 1);
      case '^':
        return make(TokenKind::kCaret, begin, begin + 1);
      case '(':
        return make(TokenKind::kLParen, begin, begin + 1);
      case ')':
        return make(TokenKind::kRParen, begin, begin + 1);
      case ',':
        return make(TokenKind::kComma, begin, begin + 1);
      case '=':
        return make(TokenKind::kEquals, begin, begin + 1);
      case ';':
        return make(TokenKind::kSemicolon, begin, begin + 1);
      default:
        break;
    }
    std::size_t end = begin + utf8_length(c);
    if (end > src_.size()) end = src_.size();
    for (std::size_t i = begin + 1; i < end; ++i) {
      if (!is_continuation_byte(src_[i])) {
        end = begin + 1;
        break;
      }
    }
    return make(TokenKind::kBadCharacter, begin, end);
  }

  /// Digits and dots are taken greedily, so "1..2" and "1.2.3" become one malformed number
  /// rather than a confusing sequence of valid ones. An exponent is only taken when digits
  /// follow: "2e" is the number 2 followed by the constant e.
  Token number(std::size_t begin) {
    std::size_t end = begin;
    int dots = 0;
    int digits = 0;
    while (end < src_.size() && (is_digit(src_[end]) || src_[end] == '.')) {
      (src_[end] == '.' ? dots : digits) += 1;
      ++end;
    }
    if (end < src_.size() && (src_[end] == 'e' || src_[end] == 'E')) {
      std::size_t exp = end + 1;
      if (exp < src_.size() && (src_[exp] == '+' || src_[exp] == '-')) ++exp;
      if (exp < src_.size() && is_digit(src_[exp])) {
        end = exp;
        while (end < src_.size() && is_digit(src_[end])) ++end;
        // "1e5.3" is as malformed as "1..2".
        while (end < src_.size() && (is_digit(src_[end]) || src_[end] == '.')) {
          dots = 2;
          ++end;
        }
      }
    }
    const bool ok = dots <= 1 && digits > 0;
    return make(ok ? TokenKind::kNumber : TokenKind::kBadNumber, begin, end);
  }

  std::string_view src_;
  std::size_t pos_ = 0;
  std::size_t counted_to_ = 0;  ///< offset where column_ was counted
  int column_ = 1;
  int line_ = 1;
};

}  // namespace

int count_characters(std::string_view text) {
  int n = 0;
  for (char c : text) n += is_continuation_byte(c) ? 0 : 1;
  return n;
}

std::vector<Token> lex(std::string_view source) { return Lexer(source).run(); }

}  // namespace zeroset::detail
