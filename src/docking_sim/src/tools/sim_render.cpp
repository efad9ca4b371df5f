// Renders the simulator's three cameras without ROS: saves frames as PNG, or benchmarks the renderer.
//
//   sim_render --config DIR --scenario NAME [--time S] [--out PREFIX]     save PREFIX_{stereo_left,...}.png
//   sim_render --config DIR --scenario NAME --bench N                      CPU ms per frame, per camera
//
// DIR is the workspace's config folder (sim.yaml, target.yaml, robot.yaml, omni_base.yaml, scenarios/).
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>

#include <ctime>
#include <iostream>
#include <string>

#include "docking_sim/config_error.h"
#include "docking_sim/simulation.h"

namespace {

double cpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

int usage() {
  std::cerr << "usage: sim_render --config DIR --scenario NAME [--time S] [--out PREFIX] [--bench N]\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::string config_dir, scenario = "default", out = "frame";
  double time_s = 0.0;
  int bench = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (i + 1 >= argc) return usage();
    const std::string value = argv[++i];
    if (arg == "--config") config_dir = value;
    else if (arg == "--scenario") scenario = value;
    else if (arg == "--time") time_s = std::stod(value);
    else if (arg == "--out") out = value;
    else if (arg == "--bench") bench = std::stoi(value);
    else return usage();
  }
  if (config_dir.empty()) return usage();
  docking_sim::SimulationFiles files;
  files.sim_config = config_dir + "/sim.yaml";
  files.scenario = config_dir + "/scenarios/" + scenario + ".yaml";
  files.target_config = config_dir + "/target.yaml";
  files.robot_config = config_dir + "/robot.yaml";
  files.omni_base_config = config_dir + "/omni_base.yaml";
  // One core, as the node runs: OpenCV's worker threads would only add hand-over cost here.
  cv::setNumThreads(1);
  try {
    docking_sim::Simulation sim(files);
    while (sim.time() < time_s - 1e-9) sim.advance(std::min(0.005, time_s - sim.time()));
    const char* names[3] = {"stereo_left", "stereo_right", "ir"};
    if (bench > 0) {
      std::cout << "scenario " << scenario << ", " << bench << " frames per camera, 640x480\n";
      double total = 0.0;
      for (int cam = 0; cam < 3; ++cam) {
        sim.render(cam);  // warm-up: first-touch allocations
        docking_sim::RenderTiming stages;
        const double start = cpuSeconds();
        for (int k = 0; k < bench; ++k) {
          sim.advance(1.0 / 30.0);
          sim.render(cam);
          const auto& t = sim.renderer(cam).lastTiming();
          stages.rasterize_ms += t.rasterize_ms / bench;
          stages.distort_ms += t.distort_ms / bench;
          stages.effects_ms += t.effects_ms / bench;
        }
        const double ms = 1e3 * (cpuSeconds() - start) / bench;
        total += ms;
        std::cout << "  " << names[cam] << ": " << ms << " ms CPU per frame (rasterize " << stages.rasterize_ms
                  << ", distortion " << stages.distort_ms << ", blur/glare/vignette/noise " << stages.effects_ms
                  << ")\n";
      }
      std::cout << "  mean over cameras: " << total / 3 << " ms CPU per frame\n";
      return 0;
    }
    for (int cam = 0; cam < 3; ++cam) {
      const std::string path = out + "_" + names[cam] + ".png";
      cv::imwrite(path, sim.render(cam));
      std::cout << "wrote " << path << "\n";
    }
  } catch (const docking_sim::ConfigError& e) {
    std::cerr << "configuration error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
