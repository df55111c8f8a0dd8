#pragma once
/// Writing output files so that an error never leaves a partial file (docs/architecture.md,
/// "Errors").
#include <functional>
#include <ostream>
#include <string>

namespace zeroset {

/// Writes `path` through `write` into a temporary file beside it, then renames it into place.
/// If `write` throws, the temporary file is removed and the exception propagates; `path` is
/// untouched. Throws IoError when the directory is not writable.
void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write);

/// Checks early (before long work) that `path` can be created: its directory exists and is
/// writable, and `path` is not a directory. Throws IoError otherwise.
void check_writable(const std::string& path);

/// Lower-case extension of `path` without the dot ("" when none).
std::string file_extension(const std::string& path);

/// Reads a whole file; throws IoError with the reason.
std::string read_text_file(const std::string& path);

}  // namespace zeroset
