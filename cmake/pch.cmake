# The project's precompiled headers (none with CMake before 3.16 or a compiler
# launcher, see below).
#
# One precompiled header for the gtest programs: the external headers nearly
# all of them include (gtest, Eigen, OpenCV, the standard library), parsed
# once per build instead of once per test file (docs/BENCHMARKS.md, "Test
# suite time").
#   semexp_test_pch_owner(<compile options> LIBS <libraries>): the target that
#     builds it, compiled as the test programs are (their options and the
#     libraries' include directories and definitions).
#   semexp_test_pch(target): a test program reuses it. GCC takes it only where
#     the program's flags match; a test that adds definitions of its own
#     (test_core_detector) is fine as long as none appears in these headers.
# Nothing changes with CMake before 3.16 (no precompiled headers) or with a
# compiler launcher such as ccache, which caches no file built against a
# precompiled header unless told to be sloppy about it, and makes repeat
# builds fast anyway.
function(semexp_test_pch_owner)
  cmake_parse_arguments(ARG "" "" "LIBS" ${ARGN})
  if(CMAKE_VERSION VERSION_LESS 3.16 OR CMAKE_CXX_COMPILER_LAUNCHER)
    return()
  endif()
  set(src "${CMAKE_CURRENT_BINARY_DIR}/semexp_test_pch.cpp")
  file(WRITE "${src}" "// builds the gtest programs' precompiled header (cmake/pch.cmake)\n")
  add_library(semexp_test_pch OBJECT "${src}")
  target_compile_options(semexp_test_pch PRIVATE ${ARG_UNPARSED_ARGUMENTS})
  target_link_libraries(semexp_test_pch PRIVATE ${ARG_LIBS})
  target_precompile_headers(semexp_test_pch PRIVATE
    <gtest/gtest.h> <Eigen/Core> <Eigen/Geometry> <opencv2/core.hpp> <opencv2/imgproc.hpp>
    <algorithm> <cmath> <map> <memory> <string> <vector>)
endfunction()

function(semexp_test_pch target)
  if(TARGET semexp_test_pch)
    target_precompile_headers(${target} REUSE_FROM semexp_test_pch)
  endif()
endfunction()

#   semexp_core_pch(target): the core library's own precompiled header (Eigen,
#     OpenCV core and the standard library, which nearly every core source
#     includes), about 1-2 s less compile CPU per source with the sanitizers'
#     flags (tsdf.cpp 19.2 -> 17.0 s, object_masks.cpp 4.8 -> 3.0 s). Same
#     conditions as above. It adds no include a core source does not already
#     make through its headers, and no ROS header.
function(semexp_core_pch target)
  if(CMAKE_VERSION VERSION_LESS 3.16 OR CMAKE_CXX_COMPILER_LAUNCHER)
    return()
  endif()
  target_precompile_headers(${target} PRIVATE
    <Eigen/Core> <Eigen/Geometry> <opencv2/core.hpp>
    <algorithm> <cmath> <cstdint> <memory> <stdexcept> <string> <unordered_map> <vector>)
endfunction()
