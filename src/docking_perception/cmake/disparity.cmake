# disparity_detector: the far-range target detector on the stereo disparity image (issue 4).
# Included by the package CMakeLists.txt after catkin_package().

# ROS-free core: the paper's detector made robust (no ros:: here; gtests need no roscore).
add_library(docking_perception_disparity_core
  src/disparity/face_appearance.cpp
  src/disparity/footprint_fit.cpp
  src/disparity/stages.cpp
  src/disparity/disparity_detector.cpp
  src/disparity/target_track_gate.cpp
  src/disparity/tracking_window.cpp
  src/disparity/window_rectifier.cpp
)
target_include_directories(docking_perception_disparity_core SYSTEM PUBLIC ${YAML_CPP_INCLUDE_DIR})
# Its settings are declared in settings/disparity_detector.yaml and settings/far_stereo_rectify.yaml (generated
# structs; docking_settings checks them).
target_link_libraries(docking_perception_disparity_core ${OpenCV_LIBRARIES} ${YAML_CPP_LIBRARIES}
  ${docking_settings_LIBRARIES})
add_dependencies(docking_perception_disparity_core ${PROJECT_NAME}_settings_headers)

# Test and benchmark support: a synthetic rectified stereo pair with known geometry, the matcher settings
# read from config/stereo_image_proc.yaml (the ones the launch file uses), and the shipped settings.
add_library(docking_perception_disparity_synthetic STATIC
  test/disparity/synthetic_stereo.cpp
)
target_link_libraries(docking_perception_disparity_synthetic docking_perception_disparity_core ${OpenCV_LIBRARIES})

set(DISPARITY_CONFIG_DIR ${PROJECT_SOURCE_DIR}/../../config)

# Nodelet: thin ROS wrapper (parameters, dynamic_reconfigure, diagnostics, message conversion).
# The library name is the one nodelet_plugins.xml declares.
add_library(docking_perception_disparity_nodelet
  src/disparity/disparity_detector_nodelet.cpp
  src/disparity/far_stereo_rectify_nodelet.cpp
)
add_dependencies(docking_perception_disparity_nodelet ${PROJECT_NAME}_gencfg ${catkin_EXPORTED_TARGETS})
target_link_libraries(docking_perception_disparity_nodelet
  docking_perception_disparity_core docking_perception_duty_core docking_perception_mono_core ${catkin_LIBRARIES}
  ${OpenCV_LIBRARIES})

# Standalone node: loads the nodelet in-process (pluginlib finds it through nodelet_plugins.xml).
add_executable(disparity_detector src/disparity/disparity_detector_node.cpp)
target_link_libraries(disparity_detector ${catkin_LIBRARIES})
add_dependencies(disparity_detector docking_perception_disparity_nodelet)

install(TARGETS docking_perception_disparity_nodelet disparity_detector
  ARCHIVE DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})

# Benchmark (a program that prints figures, never a test): rectify + disparity + detection.
add_executable(bench_disparity src/disparity/bench_disparity.cpp)
target_link_libraries(bench_disparity
  docking_perception_disparity_core docking_perception_disparity_synthetic docking_perception_mono_core
  ${OpenCV_LIBRARIES})
target_include_directories(bench_disparity PRIVATE test/disparity)
target_compile_definitions(bench_disparity PRIVATE
  DISPARITY_CONFIG_DIR="${DISPARITY_CONFIG_DIR}")

install(TARGETS docking_perception_disparity_core
  ARCHIVE DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION})
install(TARGETS bench_disparity RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
install(DIRECTORY include/${PROJECT_NAME}/disparity/
  DESTINATION ${CATKIN_PACKAGE_INCLUDE_DESTINATION}/disparity)

if(CATKIN_ENABLE_TESTING)
  # The detector on synthetic disparity images with known answers; the appearance check on drawn faces.
  catkin_add_gtest(test_disparity_detector test/disparity/test_disparity_detector.cpp
    test/disparity/test_target_confirmation.cpp test/disparity/test_face_appearance.cpp)
  if(TARGET test_disparity_detector)
    target_link_libraries(test_disparity_detector docking_perception_disparity_core
      docking_perception_disparity_synthetic gtest_main)
    target_compile_definitions(test_disparity_detector PRIVATE
      DISPARITY_CONFIG_DIR="${DISPARITY_CONFIG_DIR}")
  endif()

  # The whole far-range pipeline on rendered stereo pairs: matcher with the launch file's settings,
  # then the detector.
  catkin_add_gtest(test_disparity_pipeline test/disparity/test_disparity_pipeline.cpp
    test/disparity/test_window_rectifier.cpp test/disparity/test_footprint_fit.cpp
    test/disparity/test_tracking_window.cpp)
  if(TARGET test_disparity_pipeline)
    target_link_libraries(test_disparity_pipeline
      docking_perception_disparity_core docking_perception_disparity_synthetic ${OpenCV_LIBRARIES}
      gtest_main)
    target_compile_definitions(test_disparity_pipeline PRIVATE
      DISPARITY_CONFIG_DIR="${DISPARITY_CONFIG_DIR}")
  endif()

  # The node end to end on synthetic DisparityImage messages (needs a roscore: rostest).
  add_rostest_gtest(test_disparity_detector_node test/disparity/disparity_detector_node.test
    test/disparity/test_disparity_detector_node.cpp)
  if(TARGET test_disparity_detector_node)
    target_link_libraries(test_disparity_detector_node ${catkin_LIBRARIES})
    add_dependencies(test_disparity_detector_node disparity_detector docking_perception_disparity_nodelet
      ${catkin_EXPORTED_TARGETS})
  endif()

  # Issue 15: far_stereo_rectify alone on pairs of the check's making: bad ones dropped with a reason.
  add_rostest(test/disparity/far_stereo_rectify_bad_input.test
    DEPENDENCIES docking_perception_disparity_nodelet)
  # Issue 15: near the target the stage rests; it wakes when the arbiter stops (~1-2 min wall).
  add_rostest(test/disparity/disparity_pause.test
    DEPENDENCIES perception_host arbiter docking_perception_disparity_nodelet)
  # Issue 15: at 1.5 m block matching at the keep-alive rate; full rate when the arbiter stops (~1-2 min).
  add_rostest(test/disparity/disparity_keepalive.test
    DEPENDENCIES perception_host arbiter docking_perception_image_guard_nodelet)

  # Issue 11: a box of the mockup's size and shape, the target out of view: refused by its appearance (~1 min).
  add_rostest(test/disparity/disparity_decoy.test
    DEPENDENCIES perception_host arbiter docking_perception_disparity_nodelet)
  # Against the simulator's truth at 3 m (needs docking_sim, omni_base and the camera frames node).
  add_rostest_gtest(test_disparity_sim test/disparity/disparity_sim_still_3m.test
    test/disparity/test_disparity_sim.cpp)
  if(TARGET test_disparity_sim)
    target_link_libraries(test_disparity_sim ${catkin_LIBRARIES})
    add_dependencies(test_disparity_sim disparity_detector docking_perception_disparity_nodelet
      ${catkin_EXPORTED_TARGETS})
  endif()
  # The tracking window (the default) while the chaser turns at 4 m: windows follow the target.
  add_rostest(test/disparity/far_window_motion_4m.test DEPENDENCIES test_disparity_sim)
endif()
