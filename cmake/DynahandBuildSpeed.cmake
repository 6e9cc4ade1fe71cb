# How the library and the command compile quickly from scratch (README's demo builds the
# command cold in under two minutes on 2 cores; docs/performance.md, "Build time").
#
# dynahand_unity_build(target): the target's sources are compiled as a few combined "unity"
# files (CMake UNITY_BUILD, at most DYNAHAND_UNITY_BATCH_SIZE sources each). Most of a
# file's compile time here is not its own code but the Eigen, nlohmann/json, OpenCV and
# CLI11 templates it parses and instantiates; a unity file pays for them once. Results are
# the same bit for bit (no fast-math, -ffp-contract=off). Consequence for the code: names
# in anonymous namespaces must be unique within a module (share a helper through an
# internal header instead of copying it). -DDYNAHAND_UNITY_BUILD=OFF compiles file by file
# (quicker rebuilds after editing one file of a large module).
#
# dynahand_cold_code(target): code whose speed does not matter (file formats, the command's
# options, reports, the viewer's server) is compiled with -O1 in Release builds instead of
# -O3, about a third less compile time for those files. The hot code (physics, cloud,
# track, model, synth, playground) keeps the build type's flags. At -O1 GCC 12 reports
# -Wnull-dereference false positives inside libstdc++ (std::string moved by a growing
# vector, from CLI11); the warning stays on for this code in the other builds (ci-asan: -O2).
option(DYNAHAND_UNITY_BUILD "Compile the libraries and the command as combined unity files" ON)
set(DYNAHAND_UNITY_BATCH_SIZE 16 CACHE STRING "Source files per unity file (16: one per module today)")

function(dynahand_unity_build target)
  if(DYNAHAND_UNITY_BUILD)
    set_target_properties(${target} PROPERTIES UNITY_BUILD ON
                          UNITY_BUILD_BATCH_SIZE ${DYNAHAND_UNITY_BATCH_SIZE})
  endif()
endfunction()

function(dynahand_cold_code target)
  target_compile_options(${target} PRIVATE "$<$<CONFIG:Release>:-O1;-Wno-null-dereference>")
endfunction()
