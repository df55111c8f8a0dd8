# Warnings and sanitizers as an interface target: linked PRIVATE by every zeroset target,
# never set globally.
add_library(zeroset_warnings INTERFACE)
target_compile_options(zeroset_warnings INTERFACE -Wall -Wextra -Wpedantic -Wno-unused-parameter)
if(ZEROSET_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  add_link_options(-fsanitize=address,undefined)
endif()
