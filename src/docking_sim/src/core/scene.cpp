#include "docking_sim/scene.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>

#include "docking_sim/config_error.h"
#include "inner_pattern_print.h"

namespace docking_sim {
namespace {

bool isPowerOfTwo(int n) { return n > 0 && (n & (n - 1)) == 0; }

// ---- Procedural textures: deterministic for the seed, so every run sees the same room. -----------

/// Smooth random field in [0, 1]: noise at a coarse grid, upsampled with cubic interpolation (wraps
/// when the result is tiled, because the coarse grid is drawn with a wrapped border).
cv::Mat smoothNoise(cv::RNG& rng, int size, int cells) {
  cv::Mat coarse(cells, cells, CV_32F);
  rng.fill(coarse, cv::RNG::UNIFORM, 0.0, 1.0);
  cv::Mat padded;
  cv::copyMakeBorder(coarse, padded, 2, 2, 2, 2, cv::BORDER_WRAP);
  const double scale = static_cast<double>(size) / cells;
  cv::Mat big;
  cv::resize(padded, big, cv::Size(), scale, scale, cv::INTER_CUBIC);
  const int off = static_cast<int>(std::round(2 * scale));
  return big(cv::Rect(off, off, size, size)).clone();
}

/// Grey detail map (mean about 1) tinted by a colour: the clutter materials.
cv::Mat tint(const cv::Mat& detail, const cv::Vec3b& color) {
  cv::Mat out(detail.size(), CV_8UC3);
  for (int y = 0; y < detail.rows; ++y) {
    for (int x = 0; x < detail.cols; ++x) {
      const float d = detail.at<float>(y, x);
      cv::Vec3b& p = out.at<cv::Vec3b>(y, x);
      for (int c = 0; c < 3; ++c) p[c] = cv::saturate_cast<uchar>(color[c] * d);
    }
  }
  return out;
}

// Detail maps per material: d starts at 1 everywhere; fine is unit Gaussian noise (drawn first, for
// every material, so the generator's sequence does not depend on the material).

/// Wood grain: stretched noise along u, rings from a wavy sine.
void woodDetail(cv::Mat& d, const cv::Mat& fine, cv::RNG& rng, int size) {
  cv::Mat stretched;
  cv::resize(smoothNoise(rng, size, 8), stretched, cv::Size(size, size));
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const double ring = std::sin((y + 18.0 * stretched.at<float>(y, x)) * 0.35);
      d.at<float>(y, x) = static_cast<float>(0.85 + 0.12 * ring + 0.03 * fine.at<float>(y, x));
    }
  }
}

void cardboardDetail(cv::Mat& d, const cv::Mat& fine, cv::RNG& rng, int size) {
  cv::Mat blotch = smoothNoise(rng, size, 6);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      d.at<float>(y, x) = static_cast<float>(0.9 + 0.1 * blotch.at<float>(y, x) + 0.04 * fine.at<float>(y, x));
    }
  }
  // Packing tape across the middle and a printed label.
  cv::rectangle(d, cv::Rect(0, size / 2 - size / 16, size, size / 8), cv::Scalar(1.15), -1);
  cv::rectangle(d, cv::Rect(size / 8, size / 8, size / 4, size / 6), cv::Scalar(1.35), -1);
  cv::putText(d, "FRAGILE", cv::Point(size / 2, size - size / 6), cv::FONT_HERSHEY_SIMPLEX, size / 300.0,
              cv::Scalar(0.25), 2, cv::LINE_AA);
  cv::line(d, cv::Point(size * 5 / 8, size / 8), cv::Point(size * 7 / 8, size * 3 / 8), cv::Scalar(0.3), 3);
}

/// Brushed metal: noise smeared along u.
void metalDetail(cv::Mat& d, const cv::Mat& fine, int size) {
  cv::Mat brushed;
  cv::blur(fine, brushed, cv::Size(31, 1), cv::Point(-1, -1), cv::BORDER_REFLECT_101);
  d = 1.0 + 0.25 * brushed;
  for (int k = 1; k < 4; ++k) {
    cv::line(d, cv::Point(0, k * size / 4), cv::Point(size, k * size / 4), cv::Scalar(0.55), 2);
  }
  cv::circle(d, cv::Point(size * 7 / 8, size / 8), size / 40, cv::Scalar(0.4), -1, cv::LINE_AA);
}

void fabricDetail(cv::Mat& d, const cv::Mat& fine, int size) {
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const double weave = ((x / 2 + y / 2) % 2) ? 0.06 : -0.06;
      d.at<float>(y, x) = static_cast<float>(0.95 + weave + 0.08 * fine.at<float>(y, x));
    }
  }
}

/// A busy print (packaging, a poster of shapes and text): many corners for a keypoint detector.
void busyDetail(cv::Mat& d, cv::RNG& rng, int size) {
  rng.fill(d, cv::RNG::UNIFORM, 0.55, 1.35);
  cv::blur(d, d, cv::Size(9, 9));
  for (int i = 0; i < 90; ++i) {
    const cv::Scalar shade(rng.uniform(0.15, 1.6));
    const cv::Point a(rng.uniform(0, size), rng.uniform(0, size));
    const int r = rng.uniform(size / 40, size / 8);
    switch (i % 4) {
      case 0: cv::rectangle(d, a, a + cv::Point(r, rng.uniform(size / 40, size / 8)), shade, -1); break;
      case 1: cv::circle(d, a, r / 2, shade, -1, cv::LINE_AA); break;
      case 2: {
        const cv::Point tri[3] = {a, a + cv::Point(r, r / 3), a + cv::Point(r / 4, r)};
        cv::fillConvexPoly(d, tri, 3, shade, cv::LINE_AA);
        break;
      }
      default: cv::putText(d, i % 8 == 3 ? "A7-X" : "K42", a, cv::FONT_HERSHEY_SIMPLEX, size / 400.0, shade, 2,
                           cv::LINE_AA);
    }
  }
}

/// Photo-like: noise over many scales (1/f-ish) with a few hard-edged objects.
void photoDetail(cv::Mat& d, const cv::Mat& fine, cv::RNG& rng, int size) {
  d = 0.35 * smoothNoise(rng, size, 4) + 0.3 * smoothNoise(rng, size, 16) + 0.25 * smoothNoise(rng, size, 64) +
      0.35 + 0.05 * fine;
  for (int i = 0; i < 25; ++i) {
    const cv::Point a(rng.uniform(0, size), rng.uniform(0, size));
    cv::rectangle(d, a, a + cv::Point(rng.uniform(8, size / 6), rng.uniform(8, size / 6)),
                  cv::Scalar(rng.uniform(0.2, 1.5)), -1);
  }
}

void plasticDetail(cv::Mat& d, const cv::Mat& fine, cv::RNG& rng, int size) {
  cv::Mat blotch = smoothNoise(rng, size, 4);
  d = 0.95 + 0.08 * blotch + 0.015 * fine;
  cv::rectangle(d, cv::Rect(size / 10, size / 10, size * 8 / 10, size * 8 / 10), cv::Scalar(0.7), 2);
}

cv::Mat materialDetail(const std::string& material, cv::RNG& rng, int size) {
  cv::Mat d(size, size, CV_32F, cv::Scalar(1.0));
  cv::Mat fine(size, size, CV_32F);
  rng.fill(fine, cv::RNG::NORMAL, 0.0, 1.0);
  if (material == "wood") woodDetail(d, fine, rng, size);
  else if (material == "cardboard") cardboardDetail(d, fine, rng, size);
  else if (material == "metal") metalDetail(d, fine, size);
  else if (material == "fabric") fabricDetail(d, fine, size);
  else if (material == "busy") busyDetail(d, rng, size);
  else if (material == "photo") photoDetail(d, fine, rng, size);
  else plasticDetail(d, fine, rng, size);
  return d;
}

cv::Mat floorTexture(cv::RNG& rng) {
  // 2 m x 2 m of vinyl tiles, 0.5 m each, with grout, per-tile shade, speckle and scuffs.
  const int size = 512, tiles = 4, tile_px = size / tiles;
  cv::Mat blotch = smoothNoise(rng, size, 16);
  cv::Mat speckle(size, size, CV_32F);
  rng.fill(speckle, cv::RNG::NORMAL, 0.0, 1.0);
  cv::Mat img(size, size, CV_8UC3);
  std::vector<double> tile_shade(tiles * tiles);
  for (auto& s : tile_shade) s = rng.uniform(0.88, 1.08);
  const cv::Vec3d base(150, 160, 168);  // light grey-beige
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const int tx = x / tile_px, ty = y / tile_px;
      const bool grout = (x % tile_px) < 2 || (y % tile_px) < 2;
      double f = grout ? 0.55 : tile_shade[static_cast<std::size_t>(ty * tiles + tx)] *
                                    (0.9 + 0.2 * blotch.at<float>(y, x)) + 0.05 * speckle.at<float>(y, x);
      cv::Vec3b& p = img.at<cv::Vec3b>(y, x);
      for (int c = 0; c < 3; ++c) p[c] = cv::saturate_cast<uchar>(base[c] * f);
    }
  }
  for (int i = 0; i < 40; ++i) {  // scuff marks
    cv::Point a(rng.uniform(0, size), rng.uniform(0, size));
    cv::Point b = a + cv::Point(rng.uniform(-30, 30), rng.uniform(-10, 10));
    cv::line(img, a, b, cv::Scalar(90, 95, 100), rng.uniform(1, 3), cv::LINE_AA);
  }
  return img;
}

cv::Mat wallTexture(cv::RNG& rng) {
  // 2 m x 2 m of painted plaster: soft blotches and fine speckle (enough texture for stereo).
  const int size = 512;
  cv::Mat blotch = smoothNoise(rng, size, 12);
  cv::Mat speckle(size, size, CV_32F);
  rng.fill(speckle, cv::RNG::NORMAL, 0.0, 1.0);
  cv::Mat img(size, size, CV_8UC3);
  const cv::Vec3d base(200, 212, 218);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const double f = 0.91 + 0.08 * blotch.at<float>(y, x) + 0.035 * speckle.at<float>(y, x);
      cv::Vec3b& p = img.at<cv::Vec3b>(y, x);
      for (int c = 0; c < 3; ++c) p[c] = cv::saturate_cast<uchar>(base[c] * f);
    }
  }
  return img;
}

cv::Mat ceilingTexture(cv::RNG& rng) {
  // 2 m x 2 m of 0.5 m acoustic tiles.
  const int size = 512;
  cv::Mat speckle(size, size, CV_32F);
  rng.fill(speckle, cv::RNG::NORMAL, 0.0, 1.0);
  cv::Mat img(size, size, CV_8UC3);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const bool grid = (x % 128) < 3 || (y % 128) < 3;
      const double f = grid ? 0.7 : 0.93 + 0.05 * speckle.at<float>(y, x);
      cv::Vec3b& p = img.at<cv::Vec3b>(y, x);
      for (int c = 0; c < 3; ++c) p[c] = cv::saturate_cast<uchar>(225 * f);
    }
  }
  return img;
}

cv::Mat posterTexture(cv::RNG& rng) {
  const int w = 256, h = 256;
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(235, 238, 240));
  for (int i = 0; i < 12; ++i) {
    const cv::Scalar col(rng.uniform(0, 255), rng.uniform(0, 255), rng.uniform(0, 255));
    const cv::Point a(rng.uniform(10, w - 60), rng.uniform(40, h - 60));
    if (i % 3 == 0) {
      cv::circle(img, a, rng.uniform(8, 30), col, -1, cv::LINE_AA);
    } else {
      cv::rectangle(img, a, a + cv::Point(rng.uniform(15, 60), rng.uniform(10, 50)), col, -1);
    }
  }
  cv::putText(img, "SAFETY FIRST", cv::Point(12, 28), cv::FONT_HERSHEY_SIMPLEX, 0.75, cv::Scalar(30, 30, 160), 2,
              cv::LINE_AA);
  cv::rectangle(img, cv::Rect(0, 0, w, h), cv::Scalar(40, 40, 40), 4);
  return img;
}

cv::Mat doorTexture() {
  cv::Mat img(512, 256, CV_8UC3, cv::Scalar(60, 90, 130));
  cv::rectangle(img, cv::Rect(20, 20, 216, 200), cv::Scalar(45, 70, 105), 4);
  cv::rectangle(img, cv::Rect(20, 260, 216, 230), cv::Scalar(45, 70, 105), 4);
  cv::circle(img, cv::Point(220, 250), 9, cv::Scalar(180, 180, 185), -1, cv::LINE_AA);
  cv::rectangle(img, cv::Rect(0, 0, 256, 512), cv::Scalar(200, 200, 200), 6);
  return img;
}

cv::Mat solarTexture() {
  // Dark blue cells with silver bus bars.
  cv::Mat img(128, 256, CV_8UC3, cv::Scalar(110, 40, 20));
  for (int x = 0; x < 256; x += 32) cv::line(img, cv::Point(x, 0), cv::Point(x, 127), cv::Scalar(170, 170, 170), 2);
  for (int y = 0; y < 128; y += 32) cv::line(img, cv::Point(0, y), cv::Point(255, y), cv::Scalar(170, 170, 170), 2);
  for (int y = 16; y < 128; y += 32) cv::line(img, cv::Point(0, y), cv::Point(255, y), cv::Scalar(140, 90, 70), 1);
  cv::rectangle(img, cv::Rect(0, 0, 256, 128), cv::Scalar(200, 200, 200), 3);
  return img;
}

/// The next mip level: half the size, texel centres at (j + 0.5) / size like every level's, so that
/// the renderer's one mapping (texel j of a level spans [j, j + 1) / size) holds at all levels. A
/// centred [1 2 1] / 4 low-pass (no shift), then an area average over each 2x2 block (for even sizes
/// [1 3 3 1] / 8 per axis, centred at 2j + 0.5 of the finer level). cv::pyrDown is not usable here:
/// its texel j is centred at 2j of the finer level, which shifts level L by (2^L - 1) / 2 texels of
/// level 0 towards +u, +v.
cv::Mat halveLevel(const cv::Mat& prev, bool repeat) {
  cv::Mat smooth;
  const cv::Mat kernel = (cv::Mat_<float>(1, 3) << 0.25f, 0.5f, 0.25f);
  if (repeat) {
    // The filters have no wrapping border: pad with a wrapped copy, filter, crop.
    cv::Mat padded, filtered;
    cv::copyMakeBorder(prev, padded, 1, 1, 1, 1, cv::BORDER_WRAP);
    cv::sepFilter2D(padded, filtered, -1, kernel, kernel, cv::Point(-1, -1), 0, cv::BORDER_REPLICATE);
    smooth = filtered(cv::Rect(1, 1, prev.cols, prev.rows));
  } else {
    cv::sepFilter2D(prev, smooth, -1, kernel, kernel, cv::Point(-1, -1), 0, cv::BORDER_REPLICATE);
  }
  // INTER_AREA maps output centres to input centres ((j + 0.5) * scale - 0.5), also for odd sizes.
  cv::Mat next;
  cv::resize(smooth, next, cv::Size(prev.cols / 2, prev.rows / 2), 0, 0, cv::INTER_AREA);
  return next;
}

/// Normal of a surface (not normalised away from zero: edges are never parallel).
Eigen::Vector3d normalOf(const Surface& s) { return s.edge_u.cross(s.edge_v).normalized(); }

}  // namespace

std::shared_ptr<Texture> makeTexture(const cv::Mat& bgr, bool repeat) {
  if (bgr.empty() || bgr.type() != CV_8UC3) throw std::invalid_argument("makeTexture needs a CV_8UC3 image");
  if (repeat && (!isPowerOfTwo(bgr.cols) || !isPowerOfTwo(bgr.rows))) {
    throw std::invalid_argument("a repeating texture needs power-of-two sizes");
  }
  auto tex = std::make_shared<Texture>();
  tex->repeat = repeat;
  tex->bgr.push_back(bgr.clone());
  while (tex->bgr.back().cols > 4 && tex->bgr.back().rows > 4) {
    tex->bgr.push_back(halveLevel(tex->bgr.back(), repeat));
  }
  for (const auto& level : tex->bgr) {
    cv::Mat g;
    cv::cvtColor(level, g, cv::COLOR_BGR2GRAY);
    tex->gray.push_back(g);
    BlockedLevel b;
    b.width = level.cols;
    b.height = level.rows;
    b.blocks_x = (level.cols + 7) / 8;
    const std::size_t texels = static_cast<std::size_t>(b.blocks_x) * ((level.rows + 7) / 8) * 64;
    b.bgrx.assign(texels, 0);
    for (int u = 0; u < level.cols; ++u) b.u_offset.push_back(static_cast<uint32_t>(b.index(u, 0)));
    for (int v = 0; v < level.rows; ++v) b.v_offset.push_back(static_cast<uint32_t>(b.index(0, v)));
    b.gray.assign(texels, 0);
    for (int v = 0; v < level.rows; ++v) {
      for (int u = 0; u < level.cols; ++u) {
        const std::size_t i = b.index(u, v);
        const cv::Vec3b& p = level.at<cv::Vec3b>(v, u);
        // Byte order in memory b, g, r, 0 (little-endian), the layout of a CV_8UC4 pixel.
        b.bgrx[i] = static_cast<uint32_t>(p[0]) | static_cast<uint32_t>(p[1]) << 8 | static_cast<uint32_t>(p[2]) << 16;
        b.gray[i] = g.at<uchar>(v, u);
      }
    }
    tex->blocked.push_back(std::move(b));
  }
  return tex;
}

void Scene::addBox(const Eigen::Isometry3d& pose, const Eigen::Vector3d& size, const std::shared_ptr<Texture>& tex,
                   const cv::Vec3b& color, double texture_scale_m, bool moves_with_target, bool bottom) {
  // pose: centre of the bottom face; the box spans +-size/2 in x, y and 0..size.z in z.
  const Eigen::Vector3d h(size.x() / 2, size.y() / 2, size.z());
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  auto add = [&](const Eigen::Vector3d& origin, const Eigen::Vector3d& eu, const Eigen::Vector3d& ev) {
    Surface s;
    s.origin = pose * origin;
    s.edge_u = pose.linear() * eu;
    s.edge_v = pose.linear() * ev;
    s.texture = tex;
    s.color = color;
    if (tex && tex->repeat && texture_scale_m > 0) {
      s.repeat_u = eu.norm() / texture_scale_m;
      s.repeat_v = ev.norm() / texture_scale_m;
    }
    s.moves_with_target = moves_with_target;
    s.bilinear = moves_with_target;  // the target's surfaces (Surface::bilinear)
    local_.push_back(s);
  };
  // Four sides, each seen upright from outside: origin top-left, u to the viewer's right (z x n).
  const Eigen::Vector3d normals[4] = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), -Eigen::Vector3d::UnitX(),
                                      -Eigen::Vector3d::UnitY()};
  for (const auto& n : normals) {
    const Eigen::Vector3d right = z.cross(n);
    const double half_width = std::abs(right.dot(h));
    const double half_depth = std::abs(n.dot(h));
    const Eigen::Vector3d center = n * half_depth + z * (size.z() / 2);
    add(center - right * half_width + z * (size.z() / 2), right * (2 * half_width), -z * size.z());
  }
  add(Eigen::Vector3d(-h.x(), h.y(), size.z()), Eigen::Vector3d(2 * h.x(), 0, 0), Eigen::Vector3d(0, -2 * h.y(), 0));
  if (bottom) add(Eigen::Vector3d(-h.x(), -h.y(), 0), Eigen::Vector3d(2 * h.x(), 0, 0), Eigen::Vector3d(0, 2 * h.y(), 0));
}

void Scene::addTargetRobot(const TargetModel& t) {
  addTargetFace(t);
  addTargetBody(t);
  if (t.panel_span_m > 0 && t.panel_height_m > 0) addSolarPanels(t);
  addTargetLeds(t);
  // The target robot under the mockup: a dark base on a low wheel block, filling the gap up to the face.
  const double base_top = t.robot_T_port.translation().z() - t.face_height_m / 2;
  if (base_top > 0.05) addTargetBase(base_top);
}

void Scene::addInPortFrame(const TargetModel& t, Surface s) {
  const Eigen::Isometry3d& rp = t.robot_T_port;
  s.origin = rp * s.origin;
  s.edge_u = rp.linear() * s.edge_u;
  s.edge_v = rp.linear() * s.edge_v;
  s.moves_with_target = true;
  s.bilinear = true;
  local_.push_back(s);
}

void Scene::addTargetFace(const TargetModel& t) {
  cv::Mat face = cv::imread(t.texture_path, cv::IMREAD_COLOR);
  if (face.empty()) {
    throw ConfigError(t.file, "target.face.texture", "cannot read the image '" + t.texture_path + "'");
  }
  const double w = t.face_width_m, h = t.face_height_m;
  // The docking face (x = 0 in the port frame): column u along +y, row v along -z (target.yaml).
  Surface face_surface;
  face_surface.origin = Eigen::Vector3d(0, -w / 2, h / 2);
  face_surface.edge_u = Eigen::Vector3d(0, w, 0);
  face_surface.edge_v = Eigen::Vector3d(0, 0, -h);
  face_surface.texture = makeTexture(face, false);
  face_surface.glossy = true;  // a printed, laminated face: specular highlights (cameras.<band>.specular)
  addInPortFrame(t, face_surface);

  // The inner pattern (target.inner_pattern): a printed tag a hair (kInnerPrintLift_m) in front of the
  // face, so the depth test puts it over the face texture; both bands see the print.
  if (t.inner_pattern.present) {
    constexpr double kInnerPrintLift_m = 2e-4;
    constexpr int kPxPerCell = 16;
    const double edge = t.inner_pattern.size_m * kInnerPrintOverTagSize;
    Surface print;
    print.origin = t.inner_pattern.center_m + Eigen::Vector3d(kInnerPrintLift_m, -edge / 2, edge / 2);
    print.edge_u = Eigen::Vector3d(0, edge, 0);
    print.edge_v = Eigen::Vector3d(0, 0, -edge);
    print.texture = makeTexture(innerPatternPrint(t.inner_pattern, kPxPerCell), false);
    addInPortFrame(t, print);
  }
}

void Scene::addTargetBody(const TargetModel& t) {
  // The box behind the face (its front is the face itself), brushed-foil look.
  const double w = t.face_width_m, h = t.face_height_m, d = t.body_depth_m;
  cv::RNG rng(4242);
  const auto foil = makeTexture(tint(materialDetail("metal", rng, 256), t.body_bgr), true);
  auto body_side = [&](const Eigen::Vector3d& origin, const Eigen::Vector3d& eu, const Eigen::Vector3d& ev) {
    Surface s;
    s.origin = origin;
    s.edge_u = eu;
    s.edge_v = ev;
    s.texture = foil;
    s.repeat_u = eu.norm() / 0.3;
    s.repeat_v = ev.norm() / 0.3;
    addInPortFrame(t, s);
  };
  body_side({-d, w / 2, h / 2}, {0, -w, 0}, {0, 0, -h});       // back
  body_side({0, w / 2, h / 2}, {-d, 0, 0}, {0, 0, -h});        // +y side
  body_side({-d, -w / 2, h / 2}, {d, 0, 0}, {0, 0, -h});       // -y side
  body_side({-d, -w / 2, h / 2}, {0, w, 0}, {d, 0, 0});        // top
  body_side({-d, -w / 2, -h / 2}, {0, w, 0}, {d, 0, 0});       // bottom
}

void Scene::addSolarPanels(const TargetModel& t) {
  // Flat wings beside the box, in the plane x = offset.
  const double w = t.face_width_m;
  cv::Mat solar = solarTexture();
  // Recolour the cells to the configured colour (keep the bus bars).
  solar.setTo(cv::Scalar(t.panel_bgr[0], t.panel_bgr[1], t.panel_bgr[2]), [&] {
    cv::Mat mask;
    cv::inRange(solar, cv::Scalar(110, 40, 20), cv::Scalar(110, 40, 20), mask);
    return mask;
  }());
  const auto solar_tex = makeTexture(solar, false);
  for (int side = -1; side <= 1; side += 2) {
    Surface s;
    const double y0 = side * w / 2;
    s.origin = Eigen::Vector3d(t.panel_offset_x_m, side > 0 ? y0 : y0 - t.panel_span_m, t.panel_height_m / 2);
    s.edge_u = Eigen::Vector3d(0, t.panel_span_m, 0);
    s.edge_v = Eigen::Vector3d(0, 0, -t.panel_height_m);
    s.texture = solar_tex;
    addInPortFrame(t, s);
  }
}

void Scene::addTargetLeds(const TargetModel& t) {
  // IR LEDs at the marker positions, in the face plane exactly where target.yaml puts them, facing
  // out of the face (+x of the port frame); IR cameras only (the renderer draws them as light spots).
  const Eigen::Isometry3d& rp = t.robot_T_port;
  for (const auto& m : t.markers_m) {
    Led led;
    led.centre = rp * m;
    led.normal = rp.linear() * Eigen::Vector3d::UnitX();
    led.radius_m = t.led_radius_m;
    led.moves_with_target = true;
    leds_local_.push_back(led);
  }
}

void Scene::addTargetBase(double base_top) {
  cv::RNG rng_base(99);
  const auto plastic = makeTexture(tint(materialDetail("plastic", rng_base, 128), cv::Vec3b(60, 60, 62)), true);
  Eigen::Isometry3d wheels = Eigen::Isometry3d::Identity();
  addBox(wheels, Eigen::Vector3d(0.22, 0.22, 0.04), nullptr, cv::Vec3b(25, 25, 25), 0, true, false);
  Eigen::Isometry3d deck = Eigen::Isometry3d::Identity();
  deck.translation().z() = 0.04;
  addBox(deck, Eigen::Vector3d(0.34, 0.34, base_top - 0.04), plastic, cv::Vec3b(60, 60, 62), 0.34, true, false);
}

Scene::Scene(const SimSettings& settings, const TargetModel& target, const LightingScenario& lighting, uint64_t seed) {
  // One generator for the whole room, drawn in this order: floor, wall and ceiling textures, posters, clutter.
  cv::RNG rng(seed ^ 0x5eed);
  const RoomConfig& room = settings.room;
  const auto floor_tex = makeTexture(floorTexture(rng), true);
  const auto wall_tex = makeTexture(wallTexture(rng), true);
  const auto ceiling_tex = makeTexture(ceilingTexture(rng), true);
  addTiles(room, 0.0, 1.0, floor_tex, true);
  addTiles(room, room.height_m, 2.0, ceiling_tex, false);
  addWalls(room, wall_tex, rng);
  addCeilingLights(room);
  addClutter(room, rng);
  addTargetRobot(target);
  setLighting(lighting, settings.light_direction, settings.ambient, settings.visible_effects, settings.ir_effects);
  update(Eigen::Isometry3d::Identity());
}

void Scene::addTiles(const RoomConfig& room, double z, double step, const std::shared_ptr<Texture>& tex,
                     bool facing_up) {
  // Floor and ceiling in 1 m (floor) and 2 m (ceiling) pieces: small polygons keep the per-span
  // texture level accurate across a receding plane.
  for (double x = room.x_min_m; x < room.x_max_m - 1e-9; x += step) {
    for (double y = room.y_min_m; y < room.y_max_m - 1e-9; y += step) {
      Surface s;
      const double sx = std::min(step, room.x_max_m - x), sy = std::min(step, room.y_max_m - y);
      s.origin = Eigen::Vector3d(x, y, z);
      s.edge_u = Eigen::Vector3d(sx, 0, 0);
      s.edge_v = Eigen::Vector3d(0, sy, 0);
      if (!facing_up) std::swap(s.edge_u, s.edge_v);
      s.texture = tex;
      // The pattern tiles every 2 m; offsets continue it across pieces.
      s.repeat_u = s.edge_u.norm() / 2.0;
      s.repeat_v = s.edge_v.norm() / 2.0;
      const double ou = (facing_up ? x - room.x_min_m : y - room.y_min_m) / 2.0;
      const double ov = (facing_up ? y - room.y_min_m : x - room.x_min_m) / 2.0;
      s.offset_u = ou - std::floor(ou);
      s.offset_v = ov - std::floor(ov);
      local_.push_back(s);
    }
  }
}

void Scene::addWalls(const RoomConfig& room, const std::shared_ptr<Texture>& wall_tex, cv::RNG& rng) {
  // Walls in 1 m pieces, with a dark skirting board.
  const Eigen::Vector2d corners[4] = {{room.x_min_m, room.y_min_m}, {room.x_max_m, room.y_min_m},
                                      {room.x_max_m, room.y_max_m}, {room.x_min_m, room.y_max_m}};
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector2d a = corners[i], b = corners[(i + 1) % 4];
    const double length = (b - a).norm();
    const Eigen::Vector2d dir = (b - a) / length;
    for (double pos = 0; pos < length - 1e-9; pos += 1.0) {
      const double piece = std::min(1.0, length - pos);
      const Eigen::Vector2d p = a + dir * pos;
      Surface s;
      s.origin = Eigen::Vector3d(p.x(), p.y(), room.height_m);
      s.edge_u = Eigen::Vector3d(dir.x(), dir.y(), 0) * piece;
      s.edge_v = Eigen::Vector3d(0, 0, -room.height_m);
      s.texture = wall_tex;
      s.repeat_u = piece / 2.0;
      s.repeat_v = room.height_m / 2.0;
      s.offset_u = (pos + i * 0.37) / 2.0 - std::floor((pos + i * 0.37) / 2.0);
      local_.push_back(s);
      Surface skirting = s;
      const Eigen::Vector3d inward(-dir.y(), dir.x(), 0);  // corners run counter-clockwise
      skirting.origin = Eigen::Vector3d(p.x(), p.y(), 0.08) + inward * 0.01;
      skirting.edge_v = Eigen::Vector3d(0, 0, -0.08);
      skirting.texture = nullptr;
      skirting.color = cv::Vec3b(70, 70, 75);
      local_.push_back(skirting);
    }
    addWallDecorations(i, a, dir, length, rng);
  }
}

void Scene::addWallDecorations(int wall, const Eigen::Vector2d& a, const Eigen::Vector2d& dir, double length,
                               cv::RNG& rng) {
  // A door on the first wall, posters on the others, 1 cm in front of the wall.
  const Eigen::Vector3d inward(-dir.y(), dir.x(), 0);
  const Eigen::Vector3d along(dir.x(), dir.y(), 0);
  if (wall == 0 && length > 3.0) {
    Surface door;
    door.origin = Eigen::Vector3d(a.x(), a.y(), 2.05) + along * (length * 0.3) + inward * 0.01;
    door.edge_u = along * 0.9;
    door.edge_v = Eigen::Vector3d(0, 0, -2.05);
    door.texture = makeTexture(doorTexture(), false);
    local_.push_back(door);
  }
  const int posters = static_cast<int>(length / 2.5);
  for (int k = 0; k < posters; ++k) {
    Surface poster;
    const double at = (k + 0.5 + rng.uniform(-0.2, 0.2)) * length / posters;
    if (wall == 0 && std::abs(at - length * 0.3 - 0.45) < 1.2) continue;  // not over the door
    const double size = rng.uniform(0.5, 0.9);
    poster.origin = Eigen::Vector3d(a.x(), a.y(), rng.uniform(1.3, 1.8)) + along * at + inward * 0.01;
    poster.edge_u = along * size;
    poster.edge_v = Eigen::Vector3d(0, 0, -size * rng.uniform(0.7, 1.3));
    poster.texture = makeTexture(posterTexture(rng), false);
    local_.push_back(poster);
  }
}

void Scene::addCeilingLights(const RoomConfig& room) {
  // Bright panels just under the ceiling (lit from inside, off in the dark).
  for (double x = room.x_min_m + 1.5; x < room.x_max_m - 1.0; x += 3.0) {
    for (double y = room.y_min_m + 1.5; y < room.y_max_m - 1.0; y += 3.0) {
      Surface lamp;
      lamp.origin = Eigen::Vector3d(x, y, room.height_m - 0.01);
      lamp.edge_u = Eigen::Vector3d(0, 0.6, 0);
      lamp.edge_v = Eigen::Vector3d(1.2, 0, 0);
      lamp.color = cv::Vec3b(250, 252, 255);
      lamp.bands = kBothBands;
      lamp.emission = -1.0;  // marks a lamp: lit by the room-light level, not by shading
      local_.push_back(lamp);
    }
  }
}

void Scene::addClutter(const RoomConfig& room, cv::RNG& rng) {
  for (const auto& c : room.clutter) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(c.x_m, c.y_m, 0);
    pose.linear() = Eigen::AngleAxisd(c.yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const bool busy = c.material == "busy" || c.material == "photo";
    const auto tex = makeTexture(tint(materialDetail(c.material, rng, busy ? 512 : 256), c.color_bgr), true);
    // Materials repeat every 0.5 m (cardboard and busy prints: once per face, so they show whole).
    const double scale = c.material == "cardboard" || busy ? std::max(c.size_x_m, c.size_y_m) : 0.5;
    addBox(pose, Eigen::Vector3d(c.size_x_m, c.size_y_m, c.size_z_m), tex, c.color_bgr, scale, false, false);
  }
}

void Scene::setLighting(const LightingScenario& lighting, const Eigen::Vector3d& light_direction, double ambient,
                        const CameraEffects& visible, const CameraEffects& ir) {
  lighting_ = lighting;
  light_direction_ = light_direction.normalized();
  ambient_ = ambient;
  visible_exposure_ = visible.exposure;
  ir_exposure_ = ir.exposure;
  led_radiance_ = ir.led_radiance;
}

void Scene::update(const Eigen::Isometry3d& world_T_target_robot) {
  if (world_.size() != local_.size()) world_ = local_;
  for (std::size_t i = 0; i < world_.size(); ++i) {
    Surface& s = world_[i];
    const Surface& l = local_[i];
    if (l.moves_with_target) {
      s.origin = world_T_target_robot * l.origin;
      s.edge_u = world_T_target_robot.linear() * l.edge_u;
      s.edge_v = world_T_target_robot.linear() * l.edge_v;
    }
    if (s.emissive) {
      s.gain_visible = lighting_.led_intensity * s.emission * visible_exposure_;
      s.gain_ir = lighting_.led_intensity * s.emission * ir_exposure_;
    } else if (s.emission < 0) {  // lamp
      s.gain_visible = std::min(1.0, lighting_.visible.illumination) * visible_exposure_ * 1.1;
      s.gain_ir = std::min(1.0, lighting_.ir.illumination) * ir_exposure_ * 1.1;
    } else {
      // Lambert with an ambient floor; surfaces are two-sided.
      const double lambert = std::abs(normalOf(s).dot(light_direction_));
      const double shade = ambient_ + (1.0 - ambient_) * lambert;
      s.gain_visible = shade * lighting_.visible.illumination * visible_exposure_;
      s.gain_ir = shade * lighting_.ir.illumination * ir_exposure_;
    }
  }
  if (leds_world_.size() != leds_local_.size()) leds_world_ = leds_local_;
  for (std::size_t i = 0; i < leds_world_.size(); ++i) {
    Led& led = leds_world_[i];
    const Led& local = leds_local_[i];
    if (local.moves_with_target) {
      led.centre = world_T_target_robot * local.centre;
      led.normal = world_T_target_robot.linear() * local.normal;
    }
    led.radiance_ir = lighting_.led_intensity * led_radiance_ * ir_exposure_;
  }
}

}  // namespace docking_sim
