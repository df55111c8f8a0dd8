#include "zeroset/surface/json_read.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>

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

std::uint64_t whole(const json& j, const std::string& origin, const std::string& where,
                    double lo, double hi) {
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

Vec3 vec3(const json& j, const std::string& origin, const std::string& where) {
  if (!j.is_array() || j.size() != 3) fail(origin, where, "expected [x, y, z]");
  return {number(j[0], origin, where + "/0"), number(j[1], origin, where + "/1"),
          number(j[2], origin, where + "/2")};
}

void known_keys(const json& object, std::initializer_list<const char*> known,
                const std::string& origin, const std::string& where) {
  for (const auto& [key, value] : object.items()) {
    if (std::find_if(known.begin(), known.end(), [&](const char* k) { return key == k; }) !=
        known.end())
      continue;
    std::string list;
    for (const char* k : known) list += (list.empty() ? "" : ", ") + std::string(k);
    fail(origin, where + "/" + key, "unknown key (known: " + list + ")");
  }
}

}  // namespace zeroset::json_read
