// Entry point of the camera gtest executables (catkin_add_gtest does not add gtest_main).
#include <gtest/gtest.h>

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
