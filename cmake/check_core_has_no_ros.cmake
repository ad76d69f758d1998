# Fails when a file of the ROS-independent core includes a ROS header.
# Usage: cmake -DROOT=<repository> -P check_core_has_no_ros.cmake
file(GLOB_RECURSE core_files
  "${ROOT}/include/kneed_walker/core/*" "${ROOT}/src/core/*.cpp" "${ROOT}/src/core/*.h")
set(ros_include_pattern
  "#[ \t]*include[ \t]*[<\"](ros|nodelet|pluginlib|tf2|tf2_ros|tf2_eigen|tf2_geometry_msgs|cv_bridge|image_transport|image_geometry|rosbag|sensor_msgs|geometry_msgs|std_msgs|visualization_msgs|diagnostic_updater|diagnostic_msgs|kneed_walker/ros|kneed_walker/[A-Z][A-Za-z]*\\.h)[/>\"]")
set(offenders "")
list(LENGTH core_files n_files)
foreach(f IN LISTS core_files)
  file(STRINGS "${f}" hits REGEX "${ros_include_pattern}")
  if(hits)
    list(APPEND offenders "${f}: ${hits}")
  endif()
endforeach()
if(n_files EQUAL 0)
  message(FATAL_ERROR "no core files found under ${ROOT}: the check would pass vacuously")
endif()
if(offenders)
  string(REPLACE ";" "\n  " offenders "${offenders}")
  message(FATAL_ERROR "ROS headers in the ROS-independent core:\n  ${offenders}")
endif()
message(STATUS "${n_files} core files include no ROS header")
