// The world as planar textured polygons: room, clutter, the target robot and its mockup (ROS-free).
#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "docking_sim/configs.h"

namespace docking_sim {

/// One pyramid level stored in 8x8 texel blocks, so that a scanline walking down a texture column
/// stays in cache as well as one walking along a row.
struct BlockedLevel {
  int width{0}, height{0}, blocks_x{0};
  /// blocked, 4 bytes per texel (b, g, r, 0): one aligned 32-bit load per texel, and the renderer
  /// shades all channels at once in one register.
  std::vector<uint32_t> bgrx;
  std::vector<uchar> gray;   ///< blocked, 1 byte per texel
  /// index(u, v) == u_offset[u] + v_offset[v]: the blocked index split into its column and row parts
  /// (they occupy disjoint bits), so the renderer's inner loop needs two table loads and an add.
  std::vector<uint32_t> u_offset, v_offset;
  /// Texel index of (u, v) in the blocked layout (multiply by the channel count).
  std::size_t index(int u, int v) const {
    return ((static_cast<std::size_t>(v >> 3) * blocks_x + static_cast<std::size_t>(u >> 3)) << 6) |
           static_cast<std::size_t>(((v & 7) << 3) | (u & 7));
  }
};

/// A texture with its mip pyramid, in colour (visible band) and grey (IR band).
struct Texture {
  std::vector<cv::Mat> bgr;    ///< level 0 = full size, CV_8UC3
  std::vector<cv::Mat> gray;   ///< CV_8UC1, same sizes
  std::vector<BlockedLevel> blocked;  ///< the same levels, blocked, for the renderer
  bool repeat{false};          ///< wraps (sizes are powers of two) instead of clamping
};

/// Builds a texture's pyramid. repeat requires power-of-two sizes (checked).
std::shared_ptr<Texture> makeTexture(const cv::Mat& bgr, bool repeat);

enum BandMask : unsigned { kVisibleBand = 1u, kInfraredBand = 2u, kBothBands = 3u };

/// A flat convex polygon. Points are origin + s * edge_u + t * edge_v with (s, t) on `outline`
/// (default: the unit square); the texture spans s, t in [0, 1] `repeat_u` / `repeat_v` times.
struct Surface {
  Eigen::Vector3d origin{Eigen::Vector3d::Zero()};
  Eigen::Vector3d edge_u{Eigen::Vector3d::UnitX()};
  Eigen::Vector3d edge_v{Eigen::Vector3d::UnitY()};
  std::vector<Eigen::Vector2d> outline{{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  std::shared_ptr<const Texture> texture;  ///< null: flat colour
  cv::Vec3b color{128, 128, 128};          ///< flat colour, or the tint of a grey texture
  double repeat_u{1.0}, repeat_v{1.0};
  double offset_u{0.0}, offset_v{0.0};     ///< texture coordinate at s = 0, t = 0 (in repeats)
  unsigned bands{kBothBands};
  bool emissive{false};          ///< lights itself: not shaded, not scaled by the room light
  double emission{1.0};          ///< brightness of an emissive surface relative to led_intensity
  bool moves_with_target{false}; ///< defined in the target robot's frame
  /// Texture sampled bilinearly, not from the nearest texel. A camera integrates light over each pixel;
  /// nearest texels of a mip level 0.7-1.4 px wide warp a fine print by a moire of sub-pixel shifts that
  /// beats with the pixel grid across the face (a still pose 0.5 deg off on sharp frames at 1.4 m,
  /// changing with every mm of range). Set on the target's surfaces, which the pose measures; the
  /// room keeps the cheaper nearest texel (+0.9 ms a camera frame when the face fills it at 0.4 m).
  bool bilinear{false};
  /// Lies on another surface (a sticker, a painted mark): drawn after all other surfaces, in `surfaces()`
  /// order, with area-coverage anti-aliasing (blended over what is there), winning depth ties with
  /// the surface under it by a relative 1/z bias, writing no depth. Flat colour only (no texture).
  bool decal{false};
  /// A glossy print (the target's face): the renderer adds a Blinn-Phong highlight of the key light
  /// (cameras.<band>.specular) where the mirror direction meets the camera.
  bool glossy{false};
  // Filled per frame by Scene::update: the brightness factor in each band.
  double gain_visible{1.0};
  double gain_ir{1.0};
};

/// An IR LED: a small emitting disc far brighter than the diffuse scene. Not a surface: the IR
/// renderer draws it after rasterisation as the lens-blurred spot of its disc, added before the
/// sensor clips (so a far LED is a saturated spot a few pixels wide, not a dim sub-pixel dot).
struct Led {
  Eigen::Vector3d centre{Eigen::Vector3d::Zero()};
  Eigen::Vector3d normal{Eigen::Vector3d::UnitX()};  ///< unit, out of the face it sits on
  double radius_m{0.005};
  bool moves_with_target{false};  ///< defined in the target robot's frame
  /// Filled per frame by Scene::update: radiance relative to the IR sensor's full scale
  /// (led_intensity * cameras.ir.led_radiance * ir exposure).
  double radiance_ir{1.0};
};

class Scene {
 public:
  /// Room and clutter from the settings, the target robot and mockup from the model. Loads the face
  /// texture (ConfigError naming target.yaml's face.texture if it cannot be read).
  Scene(const SimSettings& settings, const TargetModel& target, const LightingScenario& lighting, uint64_t seed);
  /// An empty scene for tests: add surfaces yourself.
  Scene() = default;

  void addSurface(const Surface& s) { local_.push_back(s); }
  void addLed(const Led& led) { leds_local_.push_back(led); }
  /// Places the target surfaces and LEDs at world_T_target_robot and recomputes the shading of every
  /// surface and the radiance of every LED.
  void update(const Eigen::Isometry3d& world_T_target_robot);
  const std::vector<Surface>& surfaces() const { return world_; }
  const std::vector<Led>& leds() const { return leds_world_; }
  /// Direction the key light travels (world, unit): Lambert shading and specular highlights.
  const Eigen::Vector3d& lightDirection() const { return light_direction_; }

  void setLighting(const LightingScenario& lighting, const Eigen::Vector3d& light_direction, double ambient,
                   const CameraEffects& visible, const CameraEffects& ir);

 private:
  void addBox(const Eigen::Isometry3d& pose, const Eigen::Vector3d& size, const std::shared_ptr<Texture>& tex,
              const cv::Vec3b& color, double texture_scale_m, bool moves_with_target, bool bottom);
  // The room (Scene's constructor, in this order: rng's draws depend on it).
  /// Floor (facing up) or ceiling pieces of `step` m at height z.
  void addTiles(const RoomConfig& room, double z, double step, const std::shared_ptr<Texture>& tex, bool facing_up);
  /// The four walls in 1 m pieces with skirting boards, and their decorations.
  void addWalls(const RoomConfig& room, const std::shared_ptr<Texture>& wall_tex, cv::RNG& rng);
  /// A door on the first wall (from corner a along dir), posters on every wall.
  void addWallDecorations(int wall, const Eigen::Vector2d& a, const Eigen::Vector2d& dir, double length,
                          cv::RNG& rng);
  void addCeilingLights(const RoomConfig& room);
  /// The boxes of room.clutter, textured by their material.
  void addClutter(const RoomConfig& room, cv::RNG& rng);
  // The target robot: face (and inner pattern), body, solar panels, LEDs, the base under it.
  void addTargetRobot(const TargetModel& target);
  /// Adds a surface given in the docking port's frame to the target robot (moves with it).
  void addInPortFrame(const TargetModel& target, Surface s);
  void addTargetFace(const TargetModel& target);
  void addTargetBody(const TargetModel& target);
  void addSolarPanels(const TargetModel& target);
  void addTargetLeds(const TargetModel& target);
  /// The robot base under the mockup, up to base_top (m).
  void addTargetBase(double base_top);

  std::vector<Surface> local_;   ///< static surfaces in world, target surfaces in the robot frame
  std::vector<Surface> world_;
  std::vector<Led> leds_local_;  ///< like local_
  std::vector<Led> leds_world_;
  LightingScenario lighting_;
  Eigen::Vector3d light_direction_{0.3, 0.2, -1.0};
  double ambient_{0.45};
  double visible_exposure_{1.0}, ir_exposure_{1.0};
  double led_radiance_{1.0};  ///< cameras.ir.led_radiance
};

}  // namespace docking_sim
