# arbiter: chooses among the disparity, visible-mono and IR-mono estimates (see README.md, "arbiter").
# Included by ../CMakeLists.txt after catkin_package().

# ROS-free core: the choice (range regime with hysteresis, quality, staleness, order, consistency
# across sources).
add_library(${PROJECT_NAME}_arbiter_core
  src/arbiter/consistency.cpp
  src/arbiter/frame_change.cpp
  src/arbiter/source_arbiter.cpp
)
# The stamp checks and clock-jump detection shared with the planner (docking_msgs/estimate_check.h).
target_link_libraries(${PROJECT_NAME}_arbiter_core ${docking_msgs_LIBRARIES} ${docking_settings_LIBRARIES})
add_dependencies(${PROJECT_NAME}_arbiter_core ${PROJECT_NAME}_settings_headers)

# Node: tf2 into one output frame, publishes the FUSED estimate, pose, twist, tf, status, diagnostics.
add_executable(arbiter src/arbiter/arbiter_node.cpp)
target_link_libraries(arbiter ${PROJECT_NAME}_arbiter_core ${catkin_LIBRARIES})
add_dependencies(arbiter ${catkin_EXPORTED_TARGETS})
# cfg/Arbiter.cfg (live tuning): the generated ArbiterConfig.h must exist before the node compiles.
if(TARGET ${PROJECT_NAME}_gencfg)
  add_dependencies(arbiter ${PROJECT_NAME}_gencfg)
endif()

install(TARGETS arbiter ${PROJECT_NAME}_arbiter_core
  ARCHIVE DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})

if(CATKIN_ENABLE_TESTING)
  catkin_add_gtest(test_arbiter_core
    test/arbiter/test_consistency.cpp
    test/arbiter/test_frame_change.cpp
    test/arbiter/test_source_arbiter.cpp)
  if(TARGET test_arbiter_core)
    # Debian's catkin links GTest::gtest only; the tests use gtest's own main().
    target_link_libraries(test_arbiter_core ${PROJECT_NAME}_arbiter_core GTest::gtest_main)
    target_compile_definitions(test_arbiter_core PRIVATE WORKSPACE_CONFIG_DIR="${CMAKE_CURRENT_SOURCE_DIR}/../../config")
  endif()

  # The node on synthetic estimates from two cameras (needs a roscore: rostest).
  add_rostest_gtest(test_arbiter_node test/arbiter/arbiter_node.test test/arbiter/test_arbiter_node.cpp)
  if(TARGET test_arbiter_node)
    target_link_libraries(test_arbiter_node ${catkin_LIBRARIES})
    add_dependencies(test_arbiter_node arbiter ${catkin_EXPORTED_TARGETS})
  endif()
endif()
