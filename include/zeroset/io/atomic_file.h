#pragma once
/// Writing output files so that an error never leaves a partial file (docs/architecture.md,
/// "Errors"); zeroset/io/output_transaction.h groups the outputs of one command.
#include <cstddef>
#include <functional>
#include <limits>
#include <ostream>
#include <string>
#include <string_view>

namespace zeroset {

/// Writes `path` through `write`. Inside an OutputTransaction (the active one of this thread)
/// the file is staged into it and appears at its commit; otherwise it is a transaction of its
/// own: written into a temp file beside the target and renamed into place. If `write` throws,
/// the temp file is removed and the exception propagates; `path` is untouched. Throws IoError
/// when `path` cannot be created (checked first), WriteError when writing or the rename fails.
void write_file_atomically(const std::string& path,
                           const std::function<void(std::ostream&)>& write);

/// Checks early (before long work) that `path` can be written: its directory (that of the
/// file a symbolic link at `path` leads to) exists and is writable, and `path` is not a
/// directory; an existing device or FIFO must be writable itself. Throws IoError otherwise.
void check_writable(const std::string& path);

/// Lower-case extension of `path` without the dot ("" when none).
std::string file_extension(const std::string& path);

/// Reads a whole file; throws IoError with the reason. A file longer than `max_bytes` is
/// refused (BadInput "PATH: larger than WHAT may be (N MiB)") one piece past the limit, so
/// /dev/zero or a huge file costs no more than the limit.
std::string read_text_file(const std::string& path,
                           std::size_t max_bytes = std::numeric_limits<std::size_t>::max(),
                           std::string_view what = "a file");

}  // namespace zeroset
