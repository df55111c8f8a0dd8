# Warnings and sanitizers as an interface target: linked PRIVATE by every zeroset target,
# never set globally.
add_library(zeroset_warnings INTERFACE)
target_compile_options(zeroset_warnings INTERFACE -Wall -Wextra -Wpedantic -Wno-unused-parameter)
if(ZEROSET_BUILD_FUZZ AND NOT ZEROSET_SANITIZE)
  message(FATAL_ERROR "ZEROSET_BUILD_FUZZ needs ZEROSET_SANITIZE=ON (make fuzz sets both)")
endif()
if(ZEROSET_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  add_link_options(-fsanitize=address,undefined)
endif()
# The sanitizer build with the fuzz targets (clang, `make test-asan` and `make fuzz`): every
# library also gets libFuzzer's coverage counters, so the fuzzers link the libraries of the
# same build the sanitized tests run on; only the fuzz targets link the fuzzer's main.
if(ZEROSET_BUILD_FUZZ)
  add_compile_options(-fsanitize=fuzzer-no-link)
endif()

# Code generation for the processor that builds (AVX2, FMA, POPCNT where present): the hot
# loops (field evaluation, grid sampling, bit sets, ray casting, particle forces) vectorise much
# better. AVX-512 stays off: it gains little here and valgrind (callgrind, memcheck) cannot run
# it. Turn the option off to build binaries for other machines.
option(ZEROSET_NATIVE "Optimise for this machine's processor (-march=native)" ON)
add_library(zeroset_native INTERFACE)
if(ZEROSET_NATIVE)
  include(CheckCXXCompilerFlag)
  check_cxx_compiler_flag(-march=native ZEROSET_HAS_MARCH_NATIVE)
  check_cxx_compiler_flag(-mno-avx512f ZEROSET_HAS_MNO_AVX512F)
  if(ZEROSET_HAS_MARCH_NATIVE)
    target_compile_options(zeroset_native INTERFACE -march=native)
  endif()
  if(ZEROSET_HAS_MNO_AVX512F)
    target_compile_options(zeroset_native INTERFACE -mno-avx512f)
  endif()
endif()
