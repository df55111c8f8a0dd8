#pragma once
/// Reading the entries of a scene file's JSON (the scene itself, and the "render", "floaters"
/// and viewer objects): each function checks one entry and throws BadInput
/// "ORIGIN: /json/pointer: what is wrong" (e.g. "scene.json: /floaters/seed: expected a whole
/// number from 0 to 9007199254740992"), so every reader reports a bad entry the same way.
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <string_view>

#include "zeroset/types.h"

namespace zeroset::json_read {

/// The deepest nesting of objects and arrays a scene file may have (the top object is level 1;
/// a keyframe's camera is at level 5). Deeper documents are refused while they are parsed,
/// before anything deeper is built.
inline constexpr int kMaxDepth = 16;
/// The largest scene file read (32 MiB: room for a million clip specs).
inline constexpr std::size_t kMaxBytes = std::size_t{32} << 20;

/// Parses a scene file's text. Throws BadInput "origin: /pointer: what" for a syntax error or a
/// number beyond double's range (with the byte position), nesting deeper than kMaxDepth, a key
/// repeated in one object, a NUL byte anywhere, or more than kMaxBytes.
nlohmann::json parse(std::string_view text, const std::string& origin);
/// The text of the file at `path`, refused (BadInput) when longer than kMaxBytes without
/// reading further; IoError when it cannot be read.
std::string read_file(const std::string& path);
/// `key` as one token of a JSON pointer ("~" becomes "~0", "/" becomes "~1").
std::string pointer_token(std::string_view key);

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

/// The entries of a settings object ("floaters", "mesh"), read for every entry point alike: as
/// number() (the type only: the settings' validators refuse values that are not finite, with
/// their range), whole(), boolean() and string() with the same words, but refused with a
/// SettingError naming `key`, so that each entry point names the setting its own way (a JSON
/// pointer in a scene file, a flag, a keyword).
double setting_number(const nlohmann::json& j, const std::string& key);
std::uint64_t setting_whole(const nlohmann::json& j, const std::string& key, double lo, double hi);
bool setting_boolean(const nlohmann::json& j, const std::string& key);
std::string setting_string(const nlohmann::json& j, const std::string& key);
/// The inverse of vec3: `v` as [x, y, z], as scene and statistics files write points.
nlohmann::json from_vec3(const Vec3& v);

/// Every key of `object` must be among `known`: a misspelt key would otherwise be ignored.
void known_keys(const nlohmann::json& object, std::span<const char* const> known,
                const std::string& origin, const std::string& where);
inline void known_keys(const nlohmann::json& object, std::initializer_list<const char*> known,
                       const std::string& origin, const std::string& where) {
  known_keys(object, std::span<const char* const>(known.begin(), known.size()), origin, where);
}

}  // namespace zeroset::json_read
