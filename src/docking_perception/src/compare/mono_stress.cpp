#include "mono_stress.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>

#include "docking_perception/mono/motion_kernel.h"
#include "docking_sim/renderer.h"
#include "docking_sim/scene.h"

namespace docking_perception {
namespace stress {
namespace {

constexpr int kWidth = 640;
constexpr int kHeight = 480;
constexpr double kFocalPx = 550.0;
constexpr double kFaceMarginPx = 8.0;
constexpr double kConfidentWrongRangeFraction = 0.05;
constexpr double kConfidentWrongDeg = 10.0;

double uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

docking_sim::CameraCalibration pinholeCalibration() {
  docking_sim::CameraCalibration cal;
  cal.name = "stress";
  cal.width = kWidth;
  cal.height = kHeight;
  cal.K = cv::Matx33d(kFocalPx, 0, 319.5, 0, kFocalPx, 239.5, 0, 0, 1);
  cal.D = {0, 0, 0, 0, 0};
  cal.P = cv::Matx34d(kFocalPx, 0, 319.5, 0, 0, kFocalPx, 239.5, 0, 0, 0, 1, 0);
  return cal;
}

// A flat surface spanning three points given in the camera frame (the harness renders with the camera
// at the world origin).
docking_sim::Surface surfaceFrom(const Eigen::Vector3d& origin, const Eigen::Vector3d& u_end,
                                 const Eigen::Vector3d& v_end) {
  docking_sim::Surface s;
  s.origin = origin;
  s.edge_u = u_end - origin;
  s.edge_v = v_end - origin;
  return s;
}

void addGaussianBlob(cv::Mat* image, const cv::Point2d& centre, double sigma, double peak) {
  const int r = static_cast<int>(std::ceil(3.5 * sigma));
  for (int y = std::max(0, static_cast<int>(centre.y) - r); y <= std::min(image->rows - 1, static_cast<int>(centre.y) + r); ++y) {
    float* row = image->ptr<float>(y);
    for (int x = std::max(0, static_cast<int>(centre.x) - r); x <= std::min(image->cols - 1, static_cast<int>(centre.x) + r); ++x) {
      const double d2 = (x - centre.x) * (x - centre.x) + (y - centre.y) * (y - centre.y);
      row[x] += static_cast<float>(peak * std::exp(-0.5 * d2 / (sigma * sigma)));
    }
  }
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

cv::Mat makeBusyTexture(uint64_t seed, int size) {
  cv::RNG rng(seed);
  cv::Mat t(size, size, CV_8UC3, cv::Scalar::all(rng.uniform(60, 200)));
  for (int i = 0; i < size / 2; ++i) {
    const cv::Scalar colour = cv::Scalar::all(rng.uniform(0, 256));
    const cv::Point a(rng.uniform(0, size), rng.uniform(0, size));
    switch (rng.uniform(0, 4)) {
      case 0:
        cv::rectangle(t, a, a + cv::Point(rng.uniform(4, size / 6), rng.uniform(4, size / 6)), colour, cv::FILLED);
        break;
      case 1:
        cv::circle(t, a, rng.uniform(3, size / 16), colour, cv::FILLED);
        break;
      case 2:
        cv::line(t, a, a + cv::Point(rng.uniform(-size / 4, size / 4), rng.uniform(-size / 4, size / 4)), colour,
                 rng.uniform(1, 4));
        break;
      default:
        cv::putText(t, std::to_string(rng.uniform(100, 99999)), a, cv::FONT_HERSHEY_SIMPLEX, rng.uniform(0.4, 1.5),
                    colour, rng.uniform(1, 3));
    }
  }
  return t;
}

struct StressRenderer::Impl {
  std::shared_ptr<docking_sim::Texture> face;
  std::vector<std::shared_ptr<docking_sim::Texture>> busy;
  std::shared_ptr<docking_sim::Texture> plain;
};

StressRenderer::StressRenderer(const mono::TargetModel& model) : impl_(new Impl), model_(model) {
  camera_.fx = camera_.fy = kFocalPx;
  camera_.cx = 319.5;
  camera_.cy = 239.5;
  camera_.width = kWidth;
  camera_.height = kHeight;
  if (model.hasTexture()) {
    // The renderer's texture sizes: powers of two are not required without repeat.
    cv::Mat bgr;
    cv::cvtColor(model.textureGray(), bgr, cv::COLOR_GRAY2BGR);
    impl_->face = docking_sim::makeTexture(bgr, false);
  }
  for (uint64_t i = 0; i < 4; ++i) impl_->busy.push_back(docking_sim::makeTexture(makeBusyTexture(77 + i), true));
  // The tidy room: a smooth, low-contrast wall (few corners).
  cv::Mat plain(256, 256, CV_8UC3);
  cv::RNG rng(5);
  rng.fill(plain, cv::RNG::UNIFORM, 150, 170);
  cv::GaussianBlur(plain, plain, cv::Size(0, 0), 12.0);
  impl_->plain = docking_sim::makeTexture(plain, true);
}

StressRenderer::~StressRenderer() = default;

TrialPose StressRenderer::drawPose(const StressCondition& condition, uint64_t seed) const {
  std::mt19937_64 rng(seed * 7919 + 17);
  const std::vector<Eigen::Vector3d> corners = model_.faceCorners();
  for (int attempt = 0;; ++attempt) {
    const double range = uniform(rng, condition.min_range_m, condition.max_range_m);
    const double yaw = uniform(rng, -35.0, 35.0) * M_PI / 180.0;
    const double pitch = uniform(rng, -10.0, 10.0) * M_PI / 180.0;
    const double roll = uniform(rng, -condition.max_roll_deg, condition.max_roll_deg) * M_PI / 180.0;
    // Off-axis: a direction up to the image border (halved on later attempts until the face fits).
    const double shrink = std::pow(0.8, attempt);
    const double nx = uniform(rng, -1.0, 1.0) * shrink * 0.5 * kWidth / kFocalPx;
    const double ny = uniform(rng, -1.0, 1.0) * shrink * 0.5 * kHeight / kFocalPx;
    TrialPose pose;
    pose.translation = Eigen::Vector3d(nx, ny, 1.0).normalized() * range;
    // Face looking at the camera (target x towards -camera z), then turned.
    Eigen::Matrix3d facing;
    facing.col(0) = Eigen::Vector3d(0, 0, -1);  // target x (face normal) -> towards the camera
    facing.col(1) = Eigen::Vector3d(1, 0, 0);   // target y (viewer's right) -> image right
    facing.col(2) = Eigen::Vector3d(0, -1, 0);  // target z (up) -> image up
    pose.rotation = facing * Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
                    Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()).toRotationMatrix() *
                    Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()).toRotationMatrix();
    bool inside = true;
    for (const Eigen::Vector3d& c : corners) {
      const Eigen::Vector2d p = camera_.project(pose.rotation * c + pose.translation);
      inside = inside && p.x() > kFaceMarginPx && p.x() < kWidth - kFaceMarginPx && p.y() > kFaceMarginPx &&
               p.y() < kHeight - kFaceMarginPx;
    }
    if (inside || attempt > 40) return pose;
  }
}

namespace {

using TexturePtr = std::shared_ptr<docking_sim::Texture>;

Eigen::Vector3d toCamera(const TrialPose& pose, const Eigen::Vector3d& p) {
  return Eigen::Vector3d(pose.rotation * p + pose.translation);
}

// The face, on a body slightly larger than it (a mockup's front plate); textured in the visible band
// (when the model has a texture), a dark square in the IR.
void addTargetFace(const mono::TargetModel& model, const TexturePtr& face_texture, bool infrared,
                   const TrialPose& pose, docking_sim::Scene* scene) {
  const double w = model.faceWidth();
  const double h = model.faceHeight();
  docking_sim::Surface plate =
      surfaceFrom(toCamera(pose, {-0.002, -0.6 * w, 0.62 * h}), toCamera(pose, {-0.002, 0.6 * w, 0.62 * h}),
                  toCamera(pose, {-0.002, -0.6 * w, -0.62 * h}));
  plate.color = cv::Vec3b(150, 150, 155);
  scene->addSurface(plate);
  if (!infrared && face_texture) {
    const cv::Size ts = model.textureGray().size();
    docking_sim::Surface face = surfaceFrom(
        toCamera(pose, model.texturePixelToPoint({-0.5f, -0.5f})),
        toCamera(pose, model.texturePixelToPoint({static_cast<float>(ts.width) - 0.5f, -0.5f})),
        toCamera(pose, model.texturePixelToPoint({-0.5f, static_cast<float>(ts.height) - 0.5f})));
    face.texture = face_texture;
    face.bilinear = true;  // as docking_sim draws the target's face (Surface::bilinear)
    face.color = cv::Vec3b(255, 255, 255);
    scene->addSurface(face);
  } else {
    docking_sim::Surface face = surfaceFrom(toCamera(pose, {0, -0.5 * w, 0.5 * h}),
                                            toCamera(pose, {0, 0.5 * w, 0.5 * h}),
                                            toCamera(pose, {0, -0.5 * w, -0.5 * h}));
    face.color = cv::Vec3b(60, 60, 60);
    scene->addSurface(face);
  }
}

// Background: a wall 0.4-1.5 m behind the target, and with clutter busy boards beside the target at
// about its depth (the hard case: the same apparent scale as the face).
void addBackground(const StressCondition& condition, const TrialPose& pose, uint64_t scene_seed,
                   const std::vector<TexturePtr>& busy, const TexturePtr& plain, std::mt19937_64& scene_rng,
                   docking_sim::Scene* scene) {
  const double wall_z = pose.translation.z() + uniform(scene_rng, 0.4, 1.5);
  docking_sim::Surface wall = surfaceFrom({-6, -6, wall_z}, {6, -6, wall_z}, {-6, 6, wall_z});
  wall.texture = condition.clutter ? busy[scene_seed % busy.size()] : plain;
  wall.repeat_u = wall.repeat_v = condition.clutter ? 12.0 : 6.0;
  wall.color = cv::Vec3b(255, 255, 255);
  scene->addSurface(wall);
  if (!condition.clutter) return;
  for (int i = 0; i < 6; ++i) {
    // Boards beside the target and a little behind it (never over the face: the card condition does that).
    const double side = (i % 2 == 0) ? -1.0 : 1.0;
    const double size = uniform(scene_rng, 0.15, 0.4);
    const double x = pose.translation.x() + side * (0.2 + 0.5 * size + uniform(scene_rng, 0.0, 0.3));
    const double y = pose.translation.y() + uniform(scene_rng, -0.4, 0.4);
    const double z = pose.translation.z() + uniform(scene_rng, 0.08, 0.4);
    docking_sim::Surface board = surfaceFrom({x - size / 2, y - size / 2, z}, {x + size / 2, y - size / 2, z},
                                             {x - size / 2, y + size / 2, z});
    board.texture = busy[(scene_seed + static_cast<uint64_t>(i) + 1) % busy.size()];
    board.repeat_u = board.repeat_v = uniform(scene_rng, 0.5, 1.5);
    board.color = cv::Vec3b(255, 255, 255);
    scene->addSurface(board);
  }
}

void addLeds(const mono::TargetModel& model, const TrialPose& pose, docking_sim::Scene* scene) {
  for (const Eigen::Vector3d& m : model.markers()) {
    docking_sim::Led led;
    led.centre = toCamera(pose, m);
    led.normal = pose.rotation.col(0);
    led.radius_m = model.ledRadius();
    scene->addLed(led);
  }
}

// The scene through docking_sim's renderer (no noise, no distortion; the harness adds its own), as
// grey levels in CV_32F.
cv::Mat renderGray(const StressCondition& condition, uint64_t frame_seed, docking_sim::Scene* scene) {
  docking_sim::LightingScenario light;
  light.visible.noise_sigma = 0.0;
  light.ir.noise_sigma = 0.0;
  light.ir.illumination = 0.12;  // the dark scenario's IR: the LEDs, little else
  light.led_intensity = 1.0;
  docking_sim::CameraEffects visible_effects;
  visible_effects.blur_sigma_px = 0.6;
  visible_effects.vignetting = 0.0;
  docking_sim::CameraEffects ir_effects;
  ir_effects.blur_sigma_px = 0.8;
  ir_effects.vignetting = 0.0;
  ir_effects.led_radiance = 10.0;  // config/sim.yaml
  scene->setLighting(light, Eigen::Vector3d(0.3, 0.4, 1.0), 0.45, visible_effects, ir_effects);
  scene->update(Eigen::Isometry3d::Identity());
  docking_sim::RenderOptions options;
  options.distortion = false;
  docking_sim::CameraRenderer renderer(pinholeCalibration(),
                                       condition.infrared ? docking_sim::Band::kInfrared : docking_sim::Band::kVisible,
                                       condition.infrared ? ir_effects : visible_effects, light, frame_seed, options);
  const cv::Mat& rendered = renderer.render(*scene, Eigen::Isometry3d::Identity());
  cv::Mat gray;
  if (rendered.channels() == 3) {
    cv::cvtColor(rendered, gray, cv::COLOR_BGR2GRAY);
  } else {
    gray = rendered.clone();
  }
  cv::Mat image;
  gray.convertTo(image, CV_32F);
  return image;
}

// A card over 25-45 % of the face from a random side: the half plane beyond a line across the face,
// only near the face (a hand-held card, not a wall).
void occludeWithCard(const mono::CameraIntrinsics& camera, const TrialPose& pose, const std::vector<cv::Point>& outline,
                     double face_px, std::mt19937_64& rng, cv::Mat* image) {
  const double angle = uniform(rng, 0, 2 * M_PI);
  const Eigen::Vector2d dir(std::cos(angle), std::sin(angle));
  const Eigen::Vector2d centre = camera.project(pose.translation);
  const double offset = uniform(rng, 0.1, 0.3) * face_px;  // the card edge this far from the centre
  const Eigen::Vector2d edge_point = centre + dir * offset;
  const Eigen::Vector2d along(-dir.y(), dir.x());
  const double big = 2000.0;
  std::vector<cv::Point> card;
  const std::vector<Eigen::Vector2d> card_corners = {edge_point + along * big, edge_point + along * big + dir * big,
                                                     edge_point - along * big + dir * big, edge_point - along * big};
  for (const Eigen::Vector2d& q : card_corners) {
    card.emplace_back(static_cast<int>(q.x()), static_cast<int>(q.y()));
  }
  cv::Mat mask = cv::Mat::zeros(image->size(), CV_8U);
  cv::fillConvexPoly(mask, card, cv::Scalar(255));
  cv::Mat near = cv::Mat::zeros(image->size(), CV_8U);
  cv::Rect box = cv::boundingRect(outline);
  box.x -= box.width / 3;
  box.y -= box.height / 3;
  box.width += 2 * box.width / 3;
  box.height += 2 * box.height / 3;
  cv::rectangle(near, box, cv::Scalar(255), cv::FILLED);
  cv::bitwise_and(mask, near, mask);
  image->setTo(cv::Scalar(uniform(rng, 60, 200)), mask);
}

// IR: one LED covered, and/or a reflection of it on a nearby surface (a bright spot 1.5-3 spot radii
// away, merging with it).
void degradeLed(const StressCondition& condition, const mono::TargetModel& model, const mono::CameraIntrinsics& camera,
                const TrialPose& pose, std::mt19937_64& rng, cv::Mat* image) {
  const double range = pose.translation.norm();
  const int which = static_cast<int>(uniform(rng, 0, 4.999));
  const Eigen::Vector3d led = toCamera(pose, model.markers()[static_cast<size_t>(which)]);
  const Eigen::Vector2d p = camera.project(led);
  const double led_px = std::max(1.0, kFocalPx * model.ledRadius() / range);
  if (condition.occlusion) {
    cv::circle(*image, cv::Point(static_cast<int>(p.x()), static_cast<int>(p.y())),
               static_cast<int>(std::ceil(4 * led_px + 4)), cv::Scalar(15), cv::FILLED);
  }
  if (condition.reflection) {
    const double angle = uniform(rng, 0, 2 * M_PI);
    const double distance = uniform(rng, 1.5, 3.0) * (led_px + 1.2);
    addGaussianBlob(image, {p.x() + distance * std::cos(angle), p.y() + distance * std::sin(angle)},
                    uniform(rng, 0.8, 1.5) * (led_px + 0.8), uniform(rng, 300, 700));
  }
}

// Scene-side degradations (before the optics blur them): a glint, an occluding card, LED troubles.
void addSceneDegradations(const StressCondition& condition, const mono::TargetModel& model,
                          const mono::CameraIntrinsics& camera, const TrialPose& pose, std::mt19937_64& rng,
                          cv::Mat* image) {
  std::vector<cv::Point> outline;
  for (const Eigen::Vector3d& c : model.faceCorners()) {
    const Eigen::Vector2d p = camera.project(toCamera(pose, c));
    outline.emplace_back(static_cast<int>(std::lround(p.x())), static_cast<int>(std::lround(p.y())));
  }
  const double w = model.faceWidth();
  const double face_px = kFocalPx * w / pose.translation.norm();
  if (condition.specular) {
    // A glint somewhere on the face: saturated core, 1/8..1/4 of the face wide.
    const double s = uniform(rng, -0.35, 0.35);
    const double t = uniform(rng, -0.35, 0.35);
    const Eigen::Vector2d p = camera.project(toCamera(pose, {0, s * w, t * model.faceHeight()}));
    addGaussianBlob(image, {p.x(), p.y()}, uniform(rng, 0.06, 0.12) * face_px, uniform(rng, 400, 900));
  }
  if (condition.occlusion && !condition.infrared) occludeWithCard(camera, pose, outline, face_px, rng, image);
  if (condition.infrared && (condition.occlusion || condition.reflection)) {
    degradeLed(condition, model, camera, pose, rng, image);
  }
}

// Optics: defocus, then motion during the exposure.
void applyOptics(const StressCondition& condition, std::mt19937_64& rng, cv::Mat* image) {
  if (condition.defocus_sigma_px > 0.0) cv::GaussianBlur(*image, *image, cv::Size(0, 0), condition.defocus_sigma_px);
  if (condition.motion_length_px > 1.0) {
    // One draw whatever the spread, so that the other conditions' images stay the same.
    const double draw = uniform(rng, 0, M_PI);
    const double angle = condition.motion_max_angle_deg >= 90.0 ? draw
                                                                : (draw - 0.5 * M_PI) * condition.motion_max_angle_deg / 90.0;
    cv::filter2D(*image, *image, -1, mono::linearMotionKernel(condition.motion_length_px, angle), cv::Point(-1, -1), 0,
                 cv::BORDER_REFLECT);
  }
}

// Sensor: clip (saturated highlights stay flat), noise; quantised by the caller.
void applySensor(const StressCondition& condition, uint64_t frame_seed, cv::Mat* image) {
  cv::min(*image, 255.0, *image);
  if (condition.noise_sigma > 0.0) {
    cv::Mat noise(image->size(), CV_32F);
    cv::RNG noise_rng(frame_seed * 31 + 7);
    noise_rng.fill(noise, cv::RNG::NORMAL, 0.0, condition.noise_sigma);
    *image += noise;
  }
}

}  // namespace

StressFrame StressRenderer::render(const StressCondition& condition, const TrialPose& pose, uint64_t scene_seed,
                                   uint64_t frame_seed) const {
  std::mt19937_64 scene_rng(scene_seed * 104729 + 3);
  std::mt19937_64 rng(frame_seed * 15485863 + 11);
  docking_sim::Scene scene;
  addTargetFace(model_, impl_->face, condition.infrared, pose, &scene);
  addBackground(condition, pose, scene_seed, impl_->busy, impl_->plain, scene_rng, &scene);
  if (condition.infrared) addLeds(model_, pose, &scene);
  cv::Mat image = renderGray(condition, frame_seed, &scene);
  addSceneDegradations(condition, model_, camera_, pose, rng, &image);
  applyOptics(condition, rng, &image);
  applySensor(condition, frame_seed, &image);
  StressFrame frame;
  image.convertTo(frame.gray, CV_8U);
  frame.truth = pose;
  return frame;
}

cv::Rect noisyFaceBox(const mono::TargetModel& model, const mono::CameraIntrinsics& camera, const TrialPose& pose,
                      uint64_t seed) {
  std::mt19937_64 rng(seed * 2654435761u + 5);
  std::vector<cv::Point> outline;
  for (const Eigen::Vector3d& c : model.faceCorners()) {
    const Eigen::Vector2d p = camera.project(pose.rotation * c + pose.translation);
    outline.emplace_back(static_cast<int>(p.x()), static_cast<int>(p.y()));
  }
  const cv::Rect box = cv::boundingRect(outline);
  const int dx = static_cast<int>(uniform(rng, -0.15, 0.15) * box.width);
  const int dy = static_cast<int>(uniform(rng, -0.15, 0.15) * box.height);
  return cv::Rect(box.x + dx - box.width * 3 / 20, box.y + dy - box.height * 3 / 20, box.width * 13 / 10,
                  box.height * 13 / 10);
}

std::vector<StressCondition> standardConditions() {
  auto visible = [](const std::string& name) {
    StressCondition c;
    c.name = name;
    return c;
  };
  std::vector<StressCondition> out;
  out.push_back(visible("clean"));
  { auto c = visible("defocus1"); c.defocus_sigma_px = 1.0; out.push_back(c); }
  { auto c = visible("defocus2"); c.defocus_sigma_px = 2.0; out.push_back(c); }
  { auto c = visible("motion5"); c.motion_length_px = 5.0; out.push_back(c); }
  { auto c = visible("motion9"); c.motion_length_px = 9.0; out.push_back(c); }
  { auto c = visible("noise8_defocus1"); c.noise_sigma = 8.0; c.defocus_sigma_px = 1.0; out.push_back(c); }
  { auto c = visible("clutter"); c.clutter = true; out.push_back(c); }
  { auto c = visible("clutter_defocus1"); c.clutter = true; c.defocus_sigma_px = 1.0; out.push_back(c); }
  { auto c = visible("clutter_defocus2"); c.clutter = true; c.defocus_sigma_px = 2.0; out.push_back(c); }
  { auto c = visible("clutter_motion7"); c.clutter = true; c.motion_length_px = 7.0; out.push_back(c); }
  { auto c = visible("clutter_motion9_noise8"); c.clutter = true; c.motion_length_px = 9.0; c.noise_sigma = 8.0; out.push_back(c); }
  { auto c = visible("clutter_defocus2_noise8"); c.clutter = true; c.defocus_sigma_px = 2.0; c.noise_sigma = 8.0; out.push_back(c); }
  { auto c = visible("clutter_defocus1_hint"); c.clutter = true; c.defocus_sigma_px = 1.0; c.region_hint = true; out.push_back(c); }
  { auto c = visible("clutter_motion9_noise8_hint"); c.clutter = true; c.motion_length_px = 9.0; c.noise_sigma = 8.0;
    c.region_hint = true; out.push_back(c); }
  { auto c = visible("clutter_defocus2_noise8_hint"); c.clutter = true; c.defocus_sigma_px = 2.0; c.noise_sigma = 8.0;
    c.region_hint = true; out.push_back(c); }
  { auto c = visible("motion9_far_rows_hint"); c.motion_length_px = 9.0; c.motion_max_angle_deg = 10.0;
    c.min_range_m = 1.6; c.region_hint = true; out.push_back(c); }
  { auto c = visible("specular"); c.specular = true; out.push_back(c); }
  { auto c = visible("specular_far"); c.specular = true; c.min_range_m = 1.6; out.push_back(c); }
  { auto c = visible("occlusion"); c.occlusion = true; out.push_back(c); }
  { auto c = visible("clutter_specular_occlusion_defocus1"); c.clutter = true; c.specular = true; c.occlusion = true;
    c.defocus_sigma_px = 1.0; out.push_back(c); }
  // Any in-plane rotation (a tilted mount, a print glued at an angle, orbit), sharp and under each blur: the
  // cold column of these is the single image with no prior.
  { auto c = visible("roll_any"); c.max_roll_deg = 180.0; out.push_back(c); }
  { auto c = visible("roll_any_defocus2"); c.max_roll_deg = 180.0; c.defocus_sigma_px = 2.0; out.push_back(c); }
  { auto c = visible("roll_any_motion9"); c.max_roll_deg = 180.0; c.motion_length_px = 9.0; out.push_back(c); }
  { auto c = visible("roll_any_noise8"); c.max_roll_deg = 180.0; c.noise_sigma = 8.0; out.push_back(c); }
  { auto c = visible("roll_any_defocus2_motion9_noise8"); c.max_roll_deg = 180.0; c.defocus_sigma_px = 2.0;
    c.motion_length_px = 9.0; c.noise_sigma = 8.0; out.push_back(c); }
  auto ir = [](const std::string& name) {
    StressCondition c;
    c.name = name;
    c.infrared = true;
    c.noise_sigma = 3.0;
    return c;
  };
  out.push_back(ir("ir_clean"));
  { auto c = ir("ir_defocus2"); c.defocus_sigma_px = 2.0; out.push_back(c); }
  { auto c = ir("ir_motion9_noise8"); c.motion_length_px = 9.0; c.noise_sigma = 8.0; out.push_back(c); }
  { auto c = ir("ir_reflection"); c.reflection = true; out.push_back(c); }
  { auto c = ir("ir_reflection_far"); c.reflection = true; c.min_range_m = 1.6; out.push_back(c); }
  { auto c = ir("ir_occlusion"); c.occlusion = true; out.push_back(c); }
  { auto c = ir("ir_roll_any"); c.max_roll_deg = 180.0; out.push_back(c); }
  return out;
}

EstimateScore scoreEstimate(const mono::MonoPoseResult& result, const TrialPose& truth) {
  EstimateScore score;
  score.valid = result.valid;
  score.reason = result.reject_reason;
  score.cpu_ms = result.processing_time_ms;
  score.range_m = truth.translation.norm();
  if (!result.valid) return score;
  const Eigen::Vector3d dp = result.pose.translation - truth.translation;
  const Eigen::Vector3d dr = mono::rotationLog(result.pose.rotation * truth.rotation.transpose());
  score.position_error_pct = 100.0 * dp.norm() / score.range_m;
  score.orientation_error_deg = dr.norm() * 180.0 / M_PI;
  for (int i = 0; i < 6; ++i) {
    const double e = i < 3 ? dp[i] : dr[i - 3];
    const double variance = result.pose.covariance(i, i);
    score.normalized[i] = variance > 0.0 ? e / std::sqrt(variance) : 1e9;
  }
  // A withheld orientation (MonoPoseResult::orientation_valid) is not a claim: as in make eval, it
  // counts neither for the orientation error nor for its coverage.
  score.orientation_claimed = result.orientation_valid;
  score.confident_wrong = score.position_error_pct > 100.0 * kConfidentWrongRangeFraction ||
                          (score.orientation_claimed && score.orientation_error_deg > kConfidentWrongDeg);
  return score;
}

ConditionSummary summarize(const std::string& name, const std::vector<EstimateScore>& scores,
                           const std::vector<bool>& cold) {
  ConditionSummary s;
  s.name = name;
  std::vector<double> position;
  std::vector<double> orientation;
  std::vector<double> cpu;
  int within[6] = {0, 0, 0, 0, 0, 0};
  int claimed = 0;  // valid estimates that claim their orientation
  for (size_t i = 0; i < scores.size(); ++i) {
    const EstimateScore& e = scores[i];
    ++s.frames;
    cpu.push_back(e.cpu_ms);
    if (i < cold.size() && cold[i]) {
      ++s.cold_frames;
      s.cold_valid += e.valid ? 1 : 0;
    }
    if (!e.valid) {
      ++s.reasons[mono::toString(e.reason)];
      continue;
    }
    ++s.valid;
    position.push_back(e.position_error_pct);
    for (int a = 0; a < 3; ++a) within[a] += std::abs(e.normalized[a]) <= 3.0 ? 1 : 0;
    if (e.orientation_claimed) {
      ++claimed;
      orientation.push_back(e.orientation_error_deg);
      for (int a = 3; a < 6; ++a) within[a] += std::abs(e.normalized[a]) <= 3.0 ? 1 : 0;
    }
    s.confident_wrong += e.confident_wrong ? 1 : 0;
  }
  s.median_position_pct = median(position);
  s.median_orientation_deg = median(orientation);
  s.cpu_ms_median = median(cpu);
  for (int a = 0; a < 6; ++a) {
    const int count = a < 3 ? s.valid : claimed;
    s.coverage[a] = count > 0 ? static_cast<double>(within[a]) / count : 1.0;
  }
  s.orientation_withheld = s.valid - claimed;
  return s;
}

ConditionSummary runCondition(const StressRenderer& renderer, const StressCondition& condition,
                              const mono::MonoPoseParams& params, uint64_t first_seed, int trials,
                              int frames_per_trial, std::vector<EstimateScore>* scores_out) {
  std::vector<EstimateScore> scores;
  std::vector<bool> cold;
  mono::MonoPoseEstimator estimator(renderer.model(), renderer.camera(), params);
  for (int t = 0; t < trials; ++t) {
    const uint64_t seed = first_seed + static_cast<uint64_t>(t);
    const TrialPose pose = renderer.drawPose(condition, seed);
    estimator.reset();
    for (int f = 0; f < frames_per_trial; ++f) {
      const StressFrame frame = renderer.render(condition, pose, seed, seed * 16 + static_cast<uint64_t>(f));
      if (condition.region_hint) {
        estimator.setRegionHint(noisyFaceBox(renderer.model(), renderer.camera(), pose, seed * 16 + f), f / 30.0);
      }
      const mono::MonoPoseResult result = estimator.process(frame.gray, f / 30.0);
      scores.push_back(scoreEstimate(result, frame.truth));
      cold.push_back(f == 0);
    }
  }
  if (scores_out) *scores_out = scores;
  return summarize(condition.name, scores, cold);
}

}  // namespace stress
}  // namespace docking_perception
