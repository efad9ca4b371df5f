# Stress harness of the monocular pose (issue 11): docking_sim's renderer + blur, clutter, glare,
# occlusion and IR reflections, scored against the truth with the covariance (src/compare/mono_stress.*).
#   docking_perception_mono_stress  the harness (ROS-free library; also the gtests' fixture)
#   stress_mono                     the tables per condition over a seed range
#   test_mono_stress                gtests on a few fixed seeds
# Needs docking_sim's core library in the same build (catkin_make with docking_sim); skipped otherwise.
if(TARGET docking_sim_core)
  add_library(docking_perception_mono_stress STATIC src/compare/mono_stress.cpp)
  target_include_directories(docking_perception_mono_stress PUBLIC src/compare ${docking_sim_SOURCE_DIR}/include
    ${omni_base_SOURCE_DIR}/include)
  target_link_libraries(docking_perception_mono_stress docking_sim_core docking_perception_mono_core ${OpenCV_LIBRARIES})
  add_executable(stress_mono src/compare/stress_mono.cpp)
  target_link_libraries(stress_mono docking_perception_mono_stress docking_perception_compare)
  install(TARGETS stress_mono RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
  if(CATKIN_ENABLE_TESTING AND EXISTS ${CMAKE_CURRENT_SOURCE_DIR}/test/mono/test_mono_stress.cpp)
    catkin_add_gtest(test_mono_stress test/mono/test_mono_stress.cpp test/mono/test_face_alignment.cpp)
    if(TARGET test_mono_stress)
      target_compile_definitions(test_mono_stress PRIVATE CONFIG_DIR="${CMAKE_CURRENT_SOURCE_DIR}/../../config")
      target_link_libraries(test_mono_stress docking_perception_mono_stress docking_perception_compare gtest_main)
    endif()
  endif()
else()
  message(STATUS "docking_perception: docking_sim_core not in this build, stress_mono and test_mono_stress skipped")
endif()
