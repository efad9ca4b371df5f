# mono_pose: near-range monocular pose of the known target (issue 5).
#   docking_perception_mono_core  ROS-free core (OpenCV, Eigen, yaml-cpp): target model, BRISK face
#                                 matching, LED pattern, paper 5-point solver, planar PnP, velocities
#   test_mono_core                gtests of the core (no roscore)
#   bench_mono                    timing of detection + pose (stages mono_full, mono_tracking)

set(MONO_CORE_SOURCES
  src/mono/pose_types.cpp
  src/mono/target_model.cpp
  src/mono/collinear_five_point_solver.cpp
  src/mono/planar_pnp_solver.cpp
  src/mono/led_pattern_detector.cpp
  src/mono/feature_matcher.cpp
  src/mono/motion_kernel.cpp
  src/mono/upright_descriptor.cpp
  src/mono/dark_dot_locator.cpp
  src/mono/velocity_estimators.cpp
  src/mono/mono_pose_estimator.cpp
  src/mono/debug_drawing.cpp
  src/mono/apriltag_pose.cpp
  src/mono/inner_pattern_detector.cpp
  src/mono/reject_reason.cpp
  src/mono/stages.cpp
  src/mono/pose_consistency.cpp
  src/mono/face_search.cpp
  src/mono/face_alignment.cpp)

# AprilTag 3 (Debian's libapriltag-dev, pkg-config `apriltag`): the inner pattern and the comparison tools.
find_package(PkgConfig REQUIRED)
pkg_check_modules(APRILTAG REQUIRED apriltag)

add_library(docking_perception_mono_core ${MONO_CORE_SOURCES})
target_include_directories(docking_perception_mono_core SYSTEM PUBLIC ${YAML_CPP_INCLUDE_DIR} ${APRILTAG_INCLUDE_DIRS})
# The settings (settings/mono_pose.yaml): the generated structs, validated and loaded by docking_settings.
target_link_libraries(docking_perception_mono_core ${OpenCV_LIBRARIES} ${YAML_CPP_LIBRARIES} ${APRILTAG_LIBRARIES}
  ${docking_settings_LIBRARIES})
add_dependencies(docking_perception_mono_core ${PROJECT_NAME}_settings_headers)

# Synthetic targets and views, shared by the tests and the benchmark.
add_library(docking_perception_mono_synthetic STATIC test/mono/synthetic_scene.cpp)
target_link_libraries(docking_perception_mono_synthetic docking_perception_mono_core)

add_executable(bench_mono test/mono/bench_mono.cpp)
target_link_libraries(bench_mono docking_perception_mono_synthetic docking_perception_mono_core)
install(TARGETS bench_mono RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})

if(CATKIN_ENABLE_TESTING)
  catkin_add_gtest(test_mono_core
    test/mono/test_main.cpp
    test/mono/test_target_model.cpp
    test/mono/test_feature_matcher.cpp
    test/mono/test_upright_descriptor.cpp
    test/mono/test_five_point_solver.cpp
    test/mono/test_planar_pnp_solver.cpp
    test/mono/test_velocity_estimators.cpp
    test/mono/test_led_pattern_detector.cpp
    test/mono/test_dark_dot_finder.cpp
    test/mono/test_mono_pose_estimator.cpp
    test/mono/test_inner_pattern.cpp)
  if(TARGET test_mono_core)
    target_compile_definitions(test_mono_core PRIVATE CONFIG_DIR="${CMAKE_CURRENT_SOURCE_DIR}/../../config")
    target_link_libraries(test_mono_core docking_perception_mono_synthetic docking_perception_mono_core)
  endif()
endif()

# The ROS shell: nodelet (docking_perception/MonoPoseNodelet) and the same in its own process.
# (MONO_CORE_ONLY: a scratch build of the core and its tests without catkin.)
if(NOT MONO_CORE_ONLY)
add_library(docking_perception_mono_pose_nodelet src/mono/mono_pose_nodelet.cpp)
target_link_libraries(docking_perception_mono_pose_nodelet docking_perception_mono_core docking_perception_duty_core
  ${PROJECT_NAME}_image_guard_core ${catkin_LIBRARIES})
add_dependencies(docking_perception_mono_pose_nodelet ${catkin_EXPORTED_TARGETS})
if(TARGET ${PROJECT_NAME}_gencfg)
  add_dependencies(docking_perception_mono_pose_nodelet ${PROJECT_NAME}_gencfg)
endif()

add_executable(mono_pose src/mono/mono_pose_node.cpp)
target_link_libraries(mono_pose ${catkin_LIBRARIES})

install(TARGETS docking_perception_mono_core docking_perception_mono_pose_nodelet mono_pose
  ARCHIVE DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
endif()

# The inner pattern on the simulator's own renders (docking_sim_core, a test dependency), 0.08-0.4 m.
if(CATKIN_ENABLE_TESTING)
  find_package(docking_sim QUIET)
  if(docking_sim_FOUND)
    catkin_add_gtest(test_inner_pattern_sim test/mono/test_inner_pattern_sim.cpp)
    if(TARGET test_inner_pattern_sim)
      target_compile_definitions(test_inner_pattern_sim PRIVATE CONFIG_DIR="${CMAKE_CURRENT_SOURCE_DIR}/../../config")
      target_include_directories(test_inner_pattern_sim SYSTEM PRIVATE ${docking_sim_INCLUDE_DIRS})
      target_link_libraries(test_inner_pattern_sim docking_perception_mono_core ${docking_sim_LIBRARIES} gtest_main)
    endif()
  else()
    message(WARNING "docking_sim not found: test_inner_pattern_sim is not built")
  endif()
endif()

# Against the simulator's truth (rostest; needs docking_sim, omni_base and docking_description):
# the visible instance at 1 m, and the IR instance in the dark while the visible one reports invalid.
if(CATKIN_ENABLE_TESTING AND NOT MONO_CORE_ONLY)
  add_rostest_gtest(test_mono_sim test/mono/mono_sim_near_1m.test test/mono/test_mono_sim.cpp)
  if(TARGET test_mono_sim)
    target_link_libraries(test_mono_sim ${catkin_LIBRARIES})
    add_dependencies(test_mono_sim docking_perception_mono_pose_nodelet ${catkin_EXPORTED_TARGETS})
  endif()
  add_rostest(test/mono/mono_sim_dark_1m.test DEPENDENCIES test_mono_sim docking_perception_mono_pose_nodelet)
endif()
