# Fails if any file of the ROS-free core includes a ROS header.
# Usage: cmake -DCORE_DIRS="dir1;dir2" -P check_core_ros_free.cmake
# Also included at configure time by CMakeLists.txt.
set(_ros_include_regex "#[ \t]*include[ \t]*[<\"](ros|tf2_ros|tf2_msgs|tf2_eigen|tf2_geometry_msgs|cv_bridge|image_transport|message_filters|sensor_msgs|nav_msgs|geometry_msgs|std_msgs|std_srvs|visualization_msgs|pcl_conversions|rosbag|semantic_exploration/ros)/")
set(_offenders "")
foreach(_dir ${CORE_DIRS})
  file(GLOB_RECURSE _files "${_dir}/*.h" "${_dir}/*.hpp" "${_dir}/*.c" "${_dir}/*.cpp" "${_dir}/*.cc")
  foreach(_f ${_files})
    file(STRINGS "${_f}" _hits REGEX "${_ros_include_regex}")
    if(_hits)
      list(APPEND _offenders "${_f}: ${_hits}")
    endif()
  endforeach()
endforeach()
if(_offenders)
  string(REPLACE ";" "\n  " _msg "${_offenders}")
  message(FATAL_ERROR "semexp_core must stay ROS-free, but these files include ROS headers:\n  ${_msg}")
endif()
