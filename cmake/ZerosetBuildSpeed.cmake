# Build speed (docs/contributing.md, "How CI is built").

# Unity builds: each target is compiled as a few large files instead of one per source, so the
# headers they share (Eigen, nlohmann-json, GoogleTest, CLI11, fmt) are parsed and instantiated
# once per batch. The libraries in src/ are batched by 4 files, so a change there recompiles
# four files (under 25 s for src/mesh); the test programs, the command line, the viewer and the
# Python module by 8. zeroset_unity_build(BATCH) is called at the top of those directories;
# ZEROSET_UNITY_BUILD=OFF builds every file alone (e.g. to check that each includes what it
# uses, or that no two files of a library define the same name in an anonymous namespace).
option(ZEROSET_UNITY_BUILD "Compile the libraries, tests, apps and Python module as unity builds"
       ON)
macro(zeroset_unity_build batch)
  set(CMAKE_UNITY_BUILD ${ZEROSET_UNITY_BUILD})
  set(CMAKE_UNITY_BUILD_BATCH_SIZE ${batch})
endmacro()

# ccache when it is installed (never required): a rebuild of unchanged files is a cache hit.
option(ZEROSET_CCACHE "Compile through ccache when it is installed" ON)
if(ZEROSET_CCACHE AND NOT CMAKE_CXX_COMPILER_LAUNCHER)
  find_program(ZEROSET_CCACHE_PROGRAM ccache)
  if(ZEROSET_CCACHE_PROGRAM)
    set(CMAKE_CXX_COMPILER_LAUNCHER ${ZEROSET_CCACHE_PROGRAM})
    message(STATUS "zeroset: compiling through ${ZEROSET_CCACHE_PROGRAM}")
  endif()
endif()
