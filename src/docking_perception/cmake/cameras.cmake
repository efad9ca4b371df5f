# Cameras: stereo_camera and ir_camera (nodelets + standalone executables),
# their ROS-free core library and tests. Included by CMakeLists.txt after catkin_package().
# Targets: ${PROJECT_NAME}_camera_core, ${PROJECT_NAME}_camera_nodelets (nodelet_plugins.xml),
# stereo_camera, ir_camera. The camera frames come from the robot model (docking_description).

# ROS-free logic: source parsing, the capture rig, frame formats, calibration checks.
add_library(${PROJECT_NAME}_camera_core
  src/camera/calibration_check.cpp
  src/camera/capture_rig.cpp
  src/camera/frame_format.cpp
  src/camera/source_spec.cpp
)
target_link_libraries(${PROJECT_NAME}_camera_core ${OpenCV_LIBRARIES} yaml-cpp)

docking_settings_generate(settings/camera_capture.yaml settings/stereo_camera.yaml settings/ir_camera.yaml)
add_library(${PROJECT_NAME}_camera_nodelets src/camera/capture_nodelet.cpp)
target_link_libraries(${PROJECT_NAME}_camera_nodelets ${PROJECT_NAME}_camera_core ${catkin_LIBRARIES})
add_dependencies(${PROJECT_NAME}_camera_nodelets ${catkin_EXPORTED_TARGETS} ${PROJECT_NAME}_settings_stereo_camera
                 ${PROJECT_NAME}_settings_ir_camera ${PROJECT_NAME}_settings_camera_capture)

add_executable(stereo_camera src/camera/stereo_camera_main.cpp)
target_link_libraries(stereo_camera ${catkin_LIBRARIES})
add_executable(ir_camera src/camera/ir_camera_main.cpp)
target_link_libraries(ir_camera ${catkin_LIBRARIES})

install(TARGETS ${PROJECT_NAME}_camera_core ${PROJECT_NAME}_camera_nodelets
  ARCHIVE DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION})
install(TARGETS ir_camera stereo_camera
  RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})
install(DIRECTORY include/${PROJECT_NAME}/camera/ DESTINATION ${CATKIN_PACKAGE_INCLUDE_DESTINATION}/camera)

if(CATKIN_ENABLE_TESTING)
  # Core unit tests: no roscore.
  catkin_add_gtest(${PROJECT_NAME}_camera_core_test
    test/camera/gtest_main.cpp
    test/camera/test_calibration_check.cpp
    test/camera/test_capture_rig.cpp
    test/camera/test_frame_format.cpp
    test/camera/test_source_spec.cpp
  )
  if(TARGET ${PROJECT_NAME}_camera_core_test)
    target_link_libraries(${PROJECT_NAME}_camera_core_test ${PROJECT_NAME}_camera_core)
    target_compile_definitions(${PROJECT_NAME}_camera_core_test PRIVATE
      DOCKING_CONFIG_DIR="${PROJECT_SOURCE_DIR}/../../config")
  endif()

  # Node tests (rostest): one executable, one .test file per scenario.
  catkin_add_executable_with_gtest(camera_nodes_rostest test/camera/camera_nodes_rostest.cpp EXCLUDE_FROM_ALL)
  if(TARGET camera_nodes_rostest)
    target_link_libraries(camera_nodes_rostest ${catkin_LIBRARIES} yaml-cpp)
    add_dependencies(camera_nodes_rostest ${catkin_EXPORTED_TARGETS})
    foreach(camera_test camera_frames camera_failures camera_sequence)
      add_rostest(test/camera/${camera_test}.test
        DEPENDENCIES camera_nodes_rostest ir_camera stereo_camera
                     ${PROJECT_NAME}_camera_nodelets)
    endforeach()
  endif()
  # Issue 12: a rate_hz that is not a number or out of range stops the camera naming the parameter.
  add_rostest(test/camera/bad_rate.test DEPENDENCIES ir_camera ${PROJECT_NAME}_camera_nodelets)
endif()
