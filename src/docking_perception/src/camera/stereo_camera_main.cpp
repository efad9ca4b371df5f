// Standalone stereo_camera: runs StereoCameraNodelet in this process (same parameters and topics as when
// it is loaded into a nodelet manager).
#include "nodelet_main.h"

int main(int argc, char** argv) {
  return docking_perception::runNodeletStandalone(argc, argv, "stereo_camera", "docking_perception/StereoCameraNodelet");
}
