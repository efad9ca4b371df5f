# target_print: a user's own target face (issue 11). Included after mono_pose.cmake and compare.cmake.
#   docking_perception_target_print  ROS-free core: compose a print with the five dots on white rings,
#                                    check a print's texture and contrast with mono_pose's matcher
#   make_target_print, check_target_print   thin CLIs (rosrun docking_perception ...)
#   test_target_print                gtests (procedural prints; the shipped config/target.yaml)
add_library(docking_perception_target_print src/target_print/target_print.cpp)
target_link_libraries(docking_perception_target_print docking_perception_mono_core ${OpenCV_LIBRARIES})

add_executable(make_target_print src/target_print/make_target_print_main.cpp)
target_link_libraries(make_target_print docking_perception_target_print)
# The mono_pose settings from config/mono_pose_visible.yaml without ROS (docking_settings::shippedSettings).
add_executable(check_target_print src/target_print/check_target_print_main.cpp)
target_link_libraries(check_target_print docking_perception_target_print)
install(TARGETS docking_perception_target_print make_target_print check_target_print
  ARCHIVE DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})

if(CATKIN_ENABLE_TESTING)
  catkin_add_gtest(test_target_print test/target_print/test_target_print.cpp)
  if(TARGET test_target_print)
    target_link_libraries(test_target_print docking_perception_target_print gtest_main)
    target_compile_definitions(test_target_print PRIVATE
      TARGET_PRINT_CONFIG_DIR="${PROJECT_SOURCE_DIR}/../../config")
  endif()
endif()
