# duty: when a stage that the current state does not use may do less (issue 15), from the arbiter's fused
# estimate. Used by the disparity_detector and mono_pose nodelets. Included by ../CMakeLists.txt after
# catkin_package(), before the components that link it.
add_library(docking_perception_duty_core src/duty/fused_range_condition.cpp)

install(TARGETS docking_perception_duty_core
  ARCHIVE DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION})

if(CATKIN_ENABLE_TESTING)
  catkin_add_gtest(test_fused_range_condition test/duty/test_fused_range_condition.cpp)
  if(TARGET test_fused_range_condition)
    target_link_libraries(test_fused_range_condition docking_perception_duty_core gtest_main)
  endif()
endif()
