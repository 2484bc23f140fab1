# Debian's ROS1 bag packages, found directly (their CMake configs pull in ament/catkin machinery
# that does not configure outside a ROS workspace), as the INTERFACE target freeinit_ros1_deps, and
# the compression libraries of the bag guard (FREEINIT_LIB_BZ2, FREEINIT_LIB_LZ4). Included by
# ros1/CMakeLists.txt and by the fuzzing build (fuzz/CMakeLists.txt).
set(_ros_hint "install them (apt-get install librosbag-dev libsensor-msgs-dev) or configure with -DFREEINIT_WITH_ROSBAG=OFF")
find_path(FREEINIT_ROSBAG_INCLUDE rosbag/view.h)
find_path(FREEINIT_SENSOR_MSGS_INCLUDE sensor_msgs/PointCloud2.h)
# rosbag/bag.h includes pluginlib and its dependencies, which Debian ships one folder deeper.
set(_ros_include_dirs)
foreach(pair "pluginlib:class_loader.hpp" "class_loader:class_loader.hpp" "rcutils:allocator.h"
             "rcpputils:env.hpp" "ament_index_cpp:get_resource.hpp")
  string(REPLACE ":" ";" parts ${pair})
  list(GET parts 0 pkg)
  list(GET parts 1 header)
  find_path(FREEINIT_ROS_${pkg}_INCLUDE ${pkg}/${header} PATH_SUFFIXES ${pkg})
  list(APPEND _ros_include_dirs ${FREEINIT_ROS_${pkg}_INCLUDE})
endforeach()
foreach(dir FREEINIT_ROSBAG_INCLUDE FREEINIT_SENSOR_MSGS_INCLUDE FREEINIT_ROS_pluginlib_INCLUDE
            FREEINIT_ROS_class_loader_INCLUDE FREEINIT_ROS_rcutils_INCLUDE
            FREEINIT_ROS_rcpputils_INCLUDE FREEINIT_ROS_ament_index_cpp_INCLUDE)
  if(NOT ${dir})
    message(FATAL_ERROR "FREEINIT_WITH_ROSBAG: ${dir} not found: ${_ros_hint}")
  endif()
endforeach()
set(_ros_libs)
foreach(lib rosbag_storage roscpp_serialization rostime cpp_common console_bridge)
  find_library(FREEINIT_ROS_LIB_${lib} ${lib})
  if(NOT FREEINIT_ROS_LIB_${lib})
    message(FATAL_ERROR "FREEINIT_WITH_ROSBAG: library ${lib} not found: ${_ros_hint}")
  endif()
  list(APPEND _ros_libs ${FREEINIT_ROS_LIB_${lib}})
endforeach()
message(STATUS "ROS1 bag import: rosbag_storage ${FREEINIT_ROS_LIB_rosbag_storage}")

# The ROS headers and libraries, for freeinit_rosbag and for tests that write bags by hand.
add_library(freeinit_ros1_deps INTERFACE)
target_include_directories(freeinit_ros1_deps SYSTEM INTERFACE ${FREEINIT_ROSBAG_INCLUDE}
                                                             ${FREEINIT_SENSOR_MSGS_INCLUDE}
                                                             ${_ros_include_dirs})
target_link_libraries(freeinit_ros1_deps INTERFACE ${_ros_libs})

# The bag guard decompresses chunks itself (bz2, lz4), both libraries librosbag depends on.
find_library(FREEINIT_LIB_BZ2 bz2)
find_library(FREEINIT_LIB_LZ4 lz4)
find_path(FREEINIT_LZ4_INCLUDE lz4.h)
if(NOT FREEINIT_LIB_BZ2 OR NOT FREEINIT_LIB_LZ4 OR NOT FREEINIT_LZ4_INCLUDE)
  message(FATAL_ERROR "FREEINIT_WITH_ROSBAG: libbz2 or liblz4 not found (libbz2-dev liblz4-dev, "
                      "dependencies of librosbag-dev)")
endif()
