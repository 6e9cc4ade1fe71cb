# dynahand_precompile(target DEPS...): precompiled headers for the heavy third-party headers
# a target uses (Eigen always; nlohmann/json, fmt, spdlog, CLI11, GoogleTest, Google
# Benchmark and OpenCV core when the target links them). Each target builds its own PCH once,
# then every source file of the target starts from it. Project headers are never precompiled.
# Off by default: measured on a cold -O3 build of the command it costs more than it saves
# (code generation, not parsing, dominates; docs/performance.md, "Build time").
#
# With ccache as compiler launcher, ccache needs sloppiness pch_defines,time_macros to cache
# files built with a PCH (otherwise it passes them through uncached), and GCC needs
# -fpch-preprocess; both are set here when DYNAHAND_PCH is on.
option(DYNAHAND_PCH "Precompile third-party headers per target" OFF)

if(DYNAHAND_PCH AND CMAKE_CXX_COMPILER_LAUNCHER MATCHES "ccache" AND
   NOT CMAKE_CXX_COMPILER_LAUNCHER MATCHES "CCACHE_SLOPPINESS")
  set(CMAKE_CXX_COMPILER_LAUNCHER
      env CCACHE_SLOPPINESS=pch_defines,time_macros,include_file_mtime,include_file_ctime
      ${CMAKE_CXX_COMPILER_LAUNCHER})
endif()

function(dynahand_precompile target)
  if(NOT DYNAHAND_PCH)
    return()
  endif()
  set(headers <algorithm> <array> <cmath> <functional> <memory> <optional> <string> <vector>
              <Eigen/Core> <Eigen/Geometry>)
  foreach(dep IN LISTS ARGN)
    if(dep STREQUAL "nlohmann_json::nlohmann_json")
      list(APPEND headers <nlohmann/json.hpp>)
    elseif(dep STREQUAL "fmt::fmt")
      list(APPEND headers <fmt/format.h>)
    elseif(dep STREQUAL "spdlog::spdlog")
      list(APPEND headers <spdlog/spdlog.h>)
    elseif(dep STREQUAL "CLI11::CLI11")
      list(APPEND headers <CLI/CLI.hpp>)
    elseif(dep MATCHES "^GTest::")
      list(APPEND headers <gtest/gtest.h>)
    elseif(dep MATCHES "^benchmark::")
      list(APPEND headers <benchmark/benchmark.h>)
    elseif(dep STREQUAL "DynahandOpenCV::OpenCV")
      list(APPEND headers <opencv2/core.hpp>)
    endif()
  endforeach()
  list(REMOVE_DUPLICATES headers)
  target_precompile_headers(${target} PRIVATE ${headers})
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_LAUNCHER MATCHES "ccache")
    target_compile_options(${target} PRIVATE -fpch-preprocess)
  endif()
endfunction()
