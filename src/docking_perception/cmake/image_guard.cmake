# image_guard: each camera's image_raw checked before image_proc sees it (issue 12, item 1).
# Included by ../CMakeLists.txt after catkin_package().

# ROS-free core: what an image must satisfy (encoding, sizes, step, data size, frame, stamp).
docking_settings_generate(settings/image_guard.yaml)
add_library(${PROJECT_NAME}_image_guard_core src/image_guard/image_check.cpp src/image_guard/rate_cap.cpp)
target_link_libraries(${PROJECT_NAME}_image_guard_core ${docking_settings_LIBRARIES})
add_dependencies(${PROJECT_NAME}_image_guard_core ${PROJECT_NAME}_settings_image_guard)

# Nodelet (nodelet_plugins.xml): image_raw (any image_transport) -> image_checked, drops with diagnostics.
add_library(${PROJECT_NAME}_image_guard_nodelet src/image_guard/image_guard_nodelet.cpp)
target_link_libraries(${PROJECT_NAME}_image_guard_nodelet ${PROJECT_NAME}_image_guard_core docking_perception_duty_core
                      ${catkin_LIBRARIES})
add_dependencies(${PROJECT_NAME}_image_guard_nodelet ${catkin_EXPORTED_TARGETS})

install(TARGETS ${PROJECT_NAME}_image_guard_core ${PROJECT_NAME}_image_guard_nodelet
  ARCHIVE DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION})

if(CATKIN_ENABLE_TESTING)
  catkin_add_gtest(test_image_guard_core test/image_guard/test_image_check.cpp test/image_guard/test_rate_cap.cpp)
  if(TARGET test_image_guard_core)
    # Debian's catkin links GTest::gtest only; the tests use gtest's own main().
    target_link_libraries(test_image_guard_core ${PROJECT_NAME}_image_guard_core GTest::gtest_main)
  endif()
endif()

if(CATKIN_ENABLE_TESTING)
  # Issue 12 end to end: malformed images and estimates beside the simulator's real ones; nothing may
  # die, valid estimates keep flowing, the diagnostics name the publisher (~3 min wall).
  add_rostest(test/fault/bad_inputs.test
    DEPENDENCIES ${PROJECT_NAME}_image_guard_nodelet arbiter docking_perception_mono_pose_nodelet
                 docking_perception_disparity_nodelet)
endif()
