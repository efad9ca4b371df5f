# Evaluation (issue 5): our monocular pose beside AprilTag 3 on the same rendered frames.
#   docking_perception_compare  sequence reader, AprilTag wrapper (tag ->
#                               target), synthetic tag views, error statistics (ROS-free)
#   compare_mono                both solvers, both velocity methods and AprilTag on sim_render sequences
#   bench_apriltag              AprilTag detection + pose on one 640x480 frame (make bench, stage apriltag)
#   make_tag_texture            the tagged target's face texture from libapriltag's tag36h11 codes
#   pipeline_on_frames          perception.launch's image path (rectify, disparity + detector, both
#                               mono_pose instances) on raw camera frames (scripts/eval/transport_cost.py)
#   test_compare                gtests
# AprilTag 3 is Debian's libapriltag-dev (C library, pkg-config `apriltag`, found in cmake/mono_pose.cmake);
# the detector itself is the mono core's (mono/apriltag_pose.h).

add_library(docking_perception_compare STATIC
  src/compare/sequence_io.cpp
  src/compare/tag_pose.cpp
  src/compare/synthetic_tag_view.cpp
  src/compare/error_stats.cpp)
target_include_directories(docking_perception_compare SYSTEM PUBLIC ${APRILTAG_INCLUDE_DIRS} ${YAML_CPP_INCLUDE_DIR})
target_link_libraries(docking_perception_compare docking_perception_mono_core ${APRILTAG_LIBRARIES}
  ${OpenCV_LIBRARIES} ${YAML_CPP_LIBRARIES})

add_executable(compare_mono src/compare/compare_mono.cpp)
target_link_libraries(compare_mono docking_perception_compare)
add_executable(bench_apriltag src/compare/bench_apriltag.cpp)
target_link_libraries(bench_apriltag docking_perception_compare)
add_executable(make_tag_texture src/compare/make_tag_texture.cpp)
target_link_libraries(make_tag_texture docking_perception_compare)
# Needs the matcher and calibration readers of the disparity tests (cmake/disparity.cmake, included before).
add_executable(pipeline_on_frames src/compare/pipeline_on_frames.cpp)
target_include_directories(pipeline_on_frames PRIVATE test/disparity)
target_link_libraries(pipeline_on_frames docking_perception_compare docking_perception_disparity_synthetic
  docking_perception_disparity_core)
install(TARGETS compare_mono bench_apriltag make_tag_texture pipeline_on_frames RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})

if(CATKIN_ENABLE_TESTING)
  catkin_add_gtest(test_compare src/compare/test_compare.cpp)
  if(TARGET test_compare)
    target_compile_definitions(test_compare PRIVATE CONFIG_DIR="${CMAKE_CURRENT_SOURCE_DIR}/../../config")
    target_link_libraries(test_compare docking_perception_compare gtest_main)
  endif()
endif()
