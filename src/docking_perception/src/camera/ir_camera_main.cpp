// Standalone ir_camera: runs IrCameraNodelet in this process.
#include "nodelet_main.h"

int main(int argc, char** argv) {
  return docking_perception::runNodeletStandalone(argc, argv, "ir_camera", "docking_perception/IrCameraNodelet");
}
