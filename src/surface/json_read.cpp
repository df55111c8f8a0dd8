#include "zeroset/surface/json_read.h"

#include "zeroset/io/atomic_file.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "zeroset/error.h"

namespace zeroset::json_read {

using nlohmann::json;

void fail(const std::string& origin, const std::string& where, const std::string& what) {
  throw BadInput(fmt::format("{}: {}: {}", origin, where, what));
}

double number(const json& j, const std::string& origin, const std::string& where) {
  if (!j.is_number()) fail(origin, where, "expected a number");
  const double v = j.get<double>();
  if (!std::isfinite(v)) fail(origin, where, "expected a finite number");
  return v;
}

double number_in(const json& j, const std::string& origin, const std::string& where, double lo,
                 double hi) {
  const double v = number(j, origin, where);
  if (v < lo || v > hi) fail(origin, where, fmt::format("must lie in [{:g}, {:g}]", lo, hi));
  return v;
}

std::uint64_t whole(const json& j, const std::string& origin, const std::string& where, double lo,
                    double hi) {
  const double v = j.is_number() ? j.get<double>() : std::nan("");
  if (!(v >= lo && v <= hi && v == std::floor(v)))
    fail(origin, where, fmt::format("expected a whole number from {:.0f} to {:.0f}", lo, hi));
  return static_cast<std::uint64_t>(v);
}

bool boolean(const json& j, const std::string& origin, const std::string& where) {
  if (!j.is_boolean()) fail(origin, where, "expected true or false");
  return j.get<bool>();
}

std::string string(const json& j, const std::string& origin, const std::string& where) {
  if (!j.is_string()) fail(origin, where, "expected a string");
  return j.get<std::string>();
}

double setting_number(const json& j, const std::string& key) {
  // Only the type: a value that is not finite (a flag's "nan"; JSON text has none) is the
  // validator's, which says the range it must lie in.
  if (!j.is_number()) throw SettingError(key, j.dump(), "expected a number");
  return j.get<double>();
}

std::uint64_t setting_whole(const json& j, const std::string& key, double lo, double hi) {
  const double v = j.is_number() ? j.get<double>() : std::nan("");
  if (!(v >= lo && v <= hi && v == std::floor(v)))
    throw SettingError(key, j.dump(),
                       fmt::format("expected a whole number from {:.0f} to {:.0f}", lo, hi));
  return static_cast<std::uint64_t>(v);
}

bool setting_boolean(const json& j, const std::string& key) {
  if (!j.is_boolean()) throw SettingError(key, j.dump(), "expected true or false");
  return j.get<bool>();
}

std::string setting_string(const json& j, const std::string& key) {
  if (!j.is_string()) throw SettingError(key, j.dump(), "expected a string");
  return j.get<std::string>();
}

Vec3 vec3(const json& j, const std::string& origin, const std::string& where) {
  if (!j.is_array() || j.size() != 3) fail(origin, where, "expected [x, y, z]");
  return {number(j[0], origin, where + "/0"), number(j[1], origin, where + "/1"),
          number(j[2], origin, where + "/2")};
}

json from_vec3(const Vec3& v) { return {v.x(), v.y(), v.z()}; }

void known_keys(const json& object, std::span<const char* const> known, const std::string& origin,
                const std::string& where) {
  for (auto it = object.begin(); it != object.end(); ++it) {
    const std::string& key = it.key();  // not a structured binding: lambdas capture it
    if (std::find_if(known.begin(), known.end(), [&](const char* k) { return key == k; }) !=
        known.end())
      continue;
    std::string list;
    for (const char* k : known) list += (list.empty() ? "" : ", ") + std::string(k);
    fail(origin, where + "/" + pointer_token(key), "unknown key (known: " + list + ")");
  }
}

std::string pointer_token(std::string_view key) {
  std::string out;
  for (char c : key) {
    if (c == '~')
      out += "~0";
    else if (c == '/')
      out += "~1";
    else
      out += c;
  }
  return out;
}

namespace {

// Builds the document itself (nlohmann's SAX interface), so that every limit is checked where
// the parser stands, with the JSON pointer of that place, before anything deeper is built: a
// document nested 10⁵ deep is refused at level kMaxDepth + 1, never recursed into.
class LimitedBuilder final : public json::json_sax_t {
 public:
  explicit LimitedBuilder(const std::string& origin) : origin_(origin) {}
  json take() { return std::move(root_); }

  bool null() override { return add(nullptr); }
  bool boolean(bool v) override { return add(v); }
  bool number_integer(number_integer_t v) override { return add(v); }
  bool number_unsigned(number_unsigned_t v) override { return add(v); }
  bool number_float(number_float_t v, const string_t&) override { return add(v); }
  bool string(string_t& v) override { return add(std::move(v)); }
  bool binary(binary_t& v) override { return add(json(std::move(v))); }
  bool start_object(std::size_t) override { return open(json::object()); }
  bool start_array(std::size_t) override { return open(json::array()); }
  bool end_object() override { return close(); }
  bool end_array() override { return close(); }
  bool key(string_t& k) override {
    // nlohmann keeps the last of repeated keys; a scene file saying two things is refused.
    if (stack_.back()->contains(k))
      fail(origin_, pointer() + "/" + pointer_token(k), "duplicate key");
    key_ = std::move(k);
    return true;
  }
  bool parse_error(std::size_t position, const std::string&,
                   const nlohmann::detail::exception& e) override {
    // A syntax error, or a number beyond double's range.
    throw BadInput(fmt::format("{}: not valid JSON (at byte {}): {}", origin_, position, e.what()));
  }

 private:
  // The pointer of the container being filled.
  std::string pointer() const {
    std::string p;
    for (const std::string& t : path_) p += "/" + t;
    return p;
  }
  // The token of the next value inside the container being filled.
  std::string next_token() const {
    const json& parent = *stack_.back();
    return parent.is_array() ? std::to_string(parent.size()) : pointer_token(key_);
  }
  json* place(json&& v) {
    if (stack_.empty()) {
      root_ = std::move(v);
      return &root_;
    }
    json& parent = *stack_.back();
    if (parent.is_array()) {
      parent.push_back(std::move(v));
      return &parent.back();
    }
    return &(parent[key_] = std::move(v));
  }
  bool add(json&& v) {
    place(std::move(v));
    return true;
  }
  bool open(json&& container) {
    const std::string token = stack_.empty() ? "" : next_token();
    if (stack_.size() >= static_cast<std::size_t>(kMaxDepth))
      fail(origin_, pointer() + "/" + token,
           fmt::format("nested deeper than {} levels (scene files need a few)", kMaxDepth));
    json* at = place(std::move(container));
    if (!stack_.empty()) path_.push_back(token);
    stack_.push_back(at);
    return true;
  }
  bool close() {
    stack_.pop_back();
    if (!path_.empty()) path_.pop_back();  // path_ has one token less than stack_
    return true;
  }

  const std::string& origin_;
  json root_;
  std::vector<json*> stack_;       // the open containers, outermost first
  std::vector<std::string> path_;  // tokens from the root to stack_.back()
  std::string key_;
};

}  // namespace

json parse(std::string_view text, const std::string& origin) {
  if (text.size() > kMaxBytes)
    fail(origin, "/",
         fmt::format("{} bytes is more than a scene file may hold ({} bytes)", text.size(),
                     kMaxBytes));
  // nlohmann's lexer takes a NUL byte for the end of the input and ignores what follows.
  if (const std::size_t nul = text.find('\0'); nul != std::string_view::npos)
    throw BadInput(fmt::format("{}: not valid JSON: a NUL byte at byte {}", origin, nul));
  LimitedBuilder builder(origin);
  json::sax_parse(text, &builder);
  return builder.take();
}

std::string read_file(const std::string& path) {
  return read_text_file(path, kMaxBytes, "a scene file");
}

}  // namespace zeroset::json_read
