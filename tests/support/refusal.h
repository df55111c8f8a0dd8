#pragma once
// The message a call is refused with, for tests of error messages.
#include <string>

#include "zeroset/error.h"

namespace zeroset::test {

/// The message of the BadInput that `f` throws ("" when it throws none).
template <typename F>
std::string refusal(F&& f) {
  try {
    f();
  } catch (const BadInput& e) {
    return e.what();
  }
  return "";
}

}  // namespace zeroset::test
