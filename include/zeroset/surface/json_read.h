#pragma once
/// Reading the entries of a scene file's JSON (the scene itself, and the "render", "floaters"
/// and viewer objects): each function checks one entry and throws BadInput
/// "ORIGIN: /json/pointer: what is wrong" (e.g. "scene.json: /floaters/seed: expected a whole
/// number from 0 to 9007199254740992"), so every reader reports a bad entry the same way.
#include <cstdint>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <string>

#include "zeroset/types.h"

namespace zeroset::json_read {

/// Throws BadInput "origin: where: what".
[[noreturn]] void fail(const std::string& origin, const std::string& where,
                       const std::string& what);

/// A finite number.
double number(const nlohmann::json& j, const std::string& origin, const std::string& where);
/// A finite number in [lo, hi].
double number_in(const nlohmann::json& j, const std::string& origin, const std::string& where,
                 double lo, double hi);
/// A whole number in [lo, hi] (hi ≤ 2^53, where doubles still hold every whole number).
std::uint64_t whole(const nlohmann::json& j, const std::string& origin, const std::string& where,
                    double lo, double hi);
bool boolean(const nlohmann::json& j, const std::string& origin, const std::string& where);
std::string string(const nlohmann::json& j, const std::string& origin, const std::string& where);
/// [x, y, z], finite.
Vec3 vec3(const nlohmann::json& j, const std::string& origin, const std::string& where);

/// Every key of `object` must be among `known`: a misspelt key would otherwise be ignored.
void known_keys(const nlohmann::json& object, std::initializer_list<const char*> known,
                const std::string& origin, const std::string& where);

}  // namespace zeroset::json_read
