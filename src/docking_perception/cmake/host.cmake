# perception_host: perception.launch's nodelets in one process (issue 15: memory and CPU of the
# per-nodelet loader processes). Included by ../CMakeLists.txt after catkin_package().

# Core: the ~nodelets list (parsing and checks; XmlRpc values, no master).
add_library(${PROJECT_NAME}_host_core src/host/nodelet_list.cpp)
target_link_libraries(${PROJECT_NAME}_host_core ${catkin_LIBRARIES})

add_executable(perception_host src/host/perception_host.cpp)
target_link_libraries(perception_host ${PROJECT_NAME}_host_core ${catkin_LIBRARIES} ${OpenCV_LIBRARIES})

install(TARGETS ${PROJECT_NAME}_host_core perception_host
  ARCHIVE DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  LIBRARY DESTINATION ${CATKIN_PACKAGE_LIB_DESTINATION}
  RUNTIME DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})

if(CATKIN_ENABLE_TESTING)
  catkin_add_gtest(test_nodelet_list test/host/test_nodelet_list.cpp)
  if(TARGET test_nodelet_list)
    target_link_libraries(test_nodelet_list ${PROJECT_NAME}_host_core GTest::gtest_main)
  endif()
endif()
