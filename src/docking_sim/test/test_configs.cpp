// Loaders: the shipped files load; bad files are rejected with the file and the field named.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "docking_sim/config_error.h"
#include "docking_sim/configs.h"
#include "docking_sim/scenario.h"
#include "docking_sim/simulation.h"
#include "test_helpers.h"

using docking_sim::ConfigError;
using docking_sim_test::configDir;
using docking_sim_test::files;
using docking_sim_test::writeTempFile;

namespace {

/// Runs f, expects a ConfigError, returns it.
template <typename F>
ConfigError expectConfigError(F f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e;
  }
  ADD_FAILURE() << "no ConfigError thrown";
  return ConfigError("", "", "");
}

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << "test setup: '" << from << "' not in the file";
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

}  // namespace

TEST(Configs, ShippedScenariosAndConfigsLoad) {
  for (const char* name : {"default", "still_3m", "rotating_1m", "dark", "glare", "translating_2m"}) {
    EXPECT_NO_THROW(docking_sim::Simulation(files(configDir() + "/scenarios/" + name + ".yaml"))) << name;
  }
  const auto s = docking_sim::loadScenario(configDir() + "/scenarios/default.yaml");
  EXPECT_NEAR(s.target_motion.yaw_rate_rad_s, 3.0 * M_PI / 180.0, 1e-12);
  EXPECT_EQ(s.lighting, "nominal");
}

TEST(Configs, DefaultScenarioPortIsFourMetresAwayAndFortyDegreesOff) {
  docking_sim::Simulation sim(files(configDir() + "/scenarios/default.yaml"));
  const Eigen::Isometry3d port = sim.worldTPort();
  const Eigen::Vector3d chaser = sim.worldTChaser().translation();
  // Angles on the floor plane (the port is 0.25 m above base_link).
  Eigen::Vector3d to_chaser = chaser - port.translation();
  to_chaser.z() = 0.0;
  to_chaser.normalize();
  EXPECT_NEAR(std::hypot(port.translation().x() - chaser.x(), port.translation().y() - chaser.y()), 4.0, 1e-3);
  const Eigen::Vector3d port_axis = port.linear().col(0);
  EXPECT_NEAR(std::acos(port_axis.dot(to_chaser)) * 180.0 / M_PI, 40.0, 0.1);
}

TEST(Configs, ScenarioMissingFieldIsNamed) {
  const std::string text = readFile(configDir() + "/scenarios/still_3m.yaml");
  const auto path = writeTempFile("missing", replaced(text, "seed: 2", "# no seed"));
  const ConfigError e = expectConfigError([&] { docking_sim::loadScenario(path); });
  EXPECT_EQ(e.file(), path);
  EXPECT_EQ(e.field(), "scenario.seed");
  EXPECT_NE(std::string(e.what()).find("scenario.seed"), std::string::npos);
  EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
}

TEST(Configs, ScenarioBadValuesAreNamed) {
  const std::string text = readFile(configDir() + "/scenarios/rotating_1m.yaml");
  {
    const auto path = writeTempFile("notnum", replaced(text, "x_m: 1.15", "x_m: one"));
    EXPECT_EQ(expectConfigError([&] { docking_sim::loadScenario(path); }).field(), "scenario.target.x_m");
  }
  {
    const auto path = writeTempFile("nan", replaced(text, "yaw_rate_deg_s: 5.0", "yaw_rate_deg_s: .nan"));
    const auto e = expectConfigError([&] { docking_sim::loadScenario(path); });
    EXPECT_EQ(e.field(), "scenario.target.motion.yaw_rate_deg_s");
    EXPECT_NE(std::string(e.what()).find("finite"), std::string::npos);
  }
  {
    const auto path = writeTempFile("vel", replaced(text, "velocity_m_s: [0.0, 0.0]", "velocity_m_s: [0.0]"));
    EXPECT_EQ(expectConfigError([&] { docking_sim::loadScenario(path); }).field(),
              "scenario.target.motion.velocity_m_s");
  }
  {
    const auto path = writeTempFile("yaml", "scenario: [unclosed");
    const auto e = expectConfigError([&] { docking_sim::loadScenario(path); });
    EXPECT_EQ(e.file(), path);
    EXPECT_NE(std::string(e.what()).find("YAML"), std::string::npos);
  }
  {
    const auto e = expectConfigError([&] { docking_sim::loadScenario("/nonexistent/scenario.yaml"); });
    EXPECT_EQ(e.file(), "/nonexistent/scenario.yaml");
  }
}

TEST(Configs, ScenarioThatDoesNotFitTheWorldIsNamed) {
  const std::string text = readFile(configDir() + "/scenarios/still_3m.yaml");
  {
    const auto path = writeTempFile("lighting", replaced(text, "lighting: nominal", "lighting: disco"));
    const auto e = expectConfigError([&] { docking_sim::Simulation sim(files(path)); });
    EXPECT_EQ(e.field(), "scenario.lighting");
    EXPECT_NE(std::string(e.what()).find("disco"), std::string::npos);
  }
  {
    const auto path = writeTempFile("outside", replaced(text, "x_m: 3.15", "x_m: 30.0"));
    EXPECT_EQ(expectConfigError([&] { docking_sim::Simulation sim(files(path)); }).field(), "scenario.target");
  }
  {
    const auto path = writeTempFile("overlap", replaced(text, "x_m: 3.15", "x_m: 0.2"));
    EXPECT_EQ(expectConfigError([&] { docking_sim::Simulation sim(files(path)); }).field(), "scenario.target");
  }
}

TEST(Configs, BadSimTargetAndCameraFilesAreNamed) {
  {
    const std::string text = readFile(configDir() + "/sim.yaml");
    const auto path = writeTempFile("sim", replaced(text, "material: metal", "material: cheese"));
    const auto e = expectConfigError([&] { docking_sim::loadSimSettings(path); });
    EXPECT_EQ(e.file(), path);
    EXPECT_NE(e.field().find("room.clutter["), std::string::npos);
    EXPECT_NE(e.field().find("material"), std::string::npos);
  }
  {
    const std::string text = readFile(configDir() + "/target.yaml");
    const auto path = writeTempFile("target", replaced(text, "width_m: 0.30", "width_m: -0.30"));
    EXPECT_EQ(expectConfigError([&] { docking_sim::loadTargetModel(path); }).field(), "target.face.width_m");
  }
  {
    // A target whose texture is missing: the simulator stops naming target.yaml's field.
    std::string text = readFile(configDir() + "/target.yaml");
    text = replaced(text, "texture: textures/target_face.png", "texture: " + configDir() + "/textures/nope.png");
    const auto target = writeTempFile("target_tex", text);
    auto f = files(configDir() + "/scenarios/still_3m.yaml");
    f.target_config = target;
    const auto e = expectConfigError([&] { docking_sim::Simulation sim(f); });
    EXPECT_EQ(e.file(), target);
    EXPECT_EQ(e.field(), "target.face.texture");
  }
  {
    const std::string text = readFile(configDir() + "/cameras/ir.yaml");
    const auto path = writeTempFile("camera", replaced(text, "distortion_model: plumb_bob", "distortion_model: fisheye"));
    EXPECT_EQ(expectConfigError([&] { docking_sim::loadCameraCalibration(path); }).field(), "distortion_model");
  }
}
