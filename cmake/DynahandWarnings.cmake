# dynahand_set_warnings(target): the project's warning set; errors when DYNAHAND_WERROR.
# -ffp-contract=off keeps results bit-identical between builds that would fuse
# multiply-adds differently (determinism tests compare hashes of float state).
# -Wno-restrict: GCC 12 reports false positives inside libstdc++ string concatenation
# (GCC bug 105329); the warning is not useful until that is fixed.
function(dynahand_set_warnings target)
  target_compile_options(${target} PRIVATE
    -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wold-style-cast -Wcast-align
    -Wunused -Woverloaded-virtual -Wnull-dereference -Wdouble-promotion -Wformat=2
    -Wimplicit-fallthrough -ffp-contract=off)
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
    target_compile_options(${target} PRIVATE -Wno-restrict)
  endif()
  if(DYNAHAND_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()
