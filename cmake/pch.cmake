# The project's precompiled headers (none with CMake before 3.16 or a compiler
# launcher, see below).
#
# Decided once, here: no precompiled headers before CMake 3.16 (no
# target_precompile_headers) or with a compiler launcher such as ccache, which
# caches no file built against a precompiled header unless told to be sloppy
# about it, and makes repeat builds fast anyway.
if(CMAKE_VERSION VERSION_LESS 3.16 OR CMAKE_CXX_COMPILER_LAUNCHER)
  set(SEMEXP_PCH OFF)
else()
  set(SEMEXP_PCH ON)
endif()
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
function(semexp_test_pch_owner)
  cmake_parse_arguments(ARG "" "" "LIBS" ${ARGN})
  if(NOT SEMEXP_PCH)
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

#   semexp_core_pch(target): the core library's own precompiled header
#     (Eigen, OpenCV core and the standard library: the external headers most
#     core sources include through the project's headers; some sources
#     include none of them), about 1-2 s less compile CPU per source with the
#     sanitizers' flags (tsdf.cpp 19.2 -> 17.0 s, object_masks.cpp 4.8 ->
#     3.0 s). No ROS header: the core stays ROS-free.
#   semexp_ros_pch(target): the same for semexp_ros (roscpp, the messages,
#     tf2, Eigen, OpenCV), whose sources spent about 6 s of their 8-14 s of
#     compile CPU parsing them.
# A precompiled header makes its headers visible to every source of the
# target, so a missing #include can go unnoticed here: configure once with
# -DCMAKE_DISABLE_PRECOMPILE_HEADERS=ON to check that every source compiles
# on its own.
function(semexp_pch target)  # target_precompile_headers(target PRIVATE <headers>) where it applies
  if(NOT SEMEXP_PCH)
    return()
  endif()
  target_precompile_headers(${target} PRIVATE ${ARGN})
endfunction()

function(semexp_core_pch target)
  semexp_pch(${target} <Eigen/Core> <Eigen/Geometry> <opencv2/core.hpp>
    <algorithm> <cmath> <cstdint> <memory> <stdexcept> <string> <unordered_map> <vector>)
endfunction()

function(semexp_ros_pch target)
  semexp_pch(${target} <ros/ros.h> <sensor_msgs/CameraInfo.h> <sensor_msgs/Image.h> <sensor_msgs/PointCloud2.h>
    <visualization_msgs/MarkerArray.h> <tf2_ros/buffer.h> <Eigen/Core> <Eigen/Geometry> <opencv2/core.hpp>
    <algorithm> <cmath> <map> <memory> <string> <vector>)
endfunction()
