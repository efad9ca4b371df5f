// compare_mono: on the same rendered frames, our monocular pose (paper_5point and pnp solvers, velocity
// by frame difference and by the Kalman filter; pnp_cold: pnp on each frame alone) beside AprilTag 3
// (tag36h11, estimate_tag_pose) on the tagged target variant rendered with the same poses, noise seed and
// camera. Writes one JSON.
//
//   compare_mono --sequence DIR --target config/target.yaml --mono-config config/mono_pose_visible.yaml
//                [--tagged-sequence DIR --tagged-target config/target_tagged.yaml] [--apriltag-decimate 2]
//                --out OUT.json
//
// DIR: `sim_render --sequence` output (docking_sim). The tag covers the whole face (the features our
// estimator needs), so ours runs on the untagged frames and AprilTag on the tagged ones; the tool
// checks that both sequences carry the same stamps and true poses.
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "docking_perception/mono/mono_pose_estimator.h"
#include "docking_perception/mono/velocity_estimators.h"
#include "error_stats.h"
#include "docking_settings/yaml_loader.h"
#include "sequence_io.h"
#include "tag_pose.h"

namespace dp = docking_perception;
namespace cmp = docking_perception::compare;

namespace {

struct Velocity {
  bool valid = false;
  Eigen::Vector3d linear = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular = Eigen::Vector3d::Zero();
};

struct Outcome {
  bool valid = false;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double ms = 0.0;
  std::string status;  // why not valid
  Velocity filter, frame_difference;
};

std::string num(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

Velocity fromTwist(const dp::mono::TwistWithCovariance& t) {
  Velocity v;
  v.valid = t.valid;
  v.linear = t.linear;
  v.angular = t.angular;
  return v;
}

std::string velocityJson(const std::vector<Outcome>& out, const std::vector<cmp::SequenceFrame>& truth,
                         Velocity Outcome::*member) {
  std::vector<double> lin, ang;
  for (std::size_t i = 0; i < out.size(); ++i) {
    const Velocity& v = out[i].*member;
    if (!out[i].valid || !v.valid) continue;
    lin.push_back((v.linear - truth[i].linear_m_s).norm());
    ang.push_back((v.angular - truth[i].angular_rad_s).norm() * 180.0 / M_PI);
  }
  std::ostringstream s;
  s << "{\"valid_rate\": " << num(static_cast<double>(lin.size()) / static_cast<double>(out.size()))
    << ", \"linear_error_m_s_median\": " << num(cmp::percentile(lin, 0.5))
    << ", \"linear_error_m_s_p95\": " << num(cmp::percentile(lin, 0.95))
    << ", \"angular_error_deg_s_median\": " << num(cmp::percentile(ang, 0.5))
    << ", \"angular_error_deg_s_p95\": " << num(cmp::percentile(ang, 0.95)) << "}";
  return s.str();
}

std::string methodJson(const std::string& name, const std::string& input, const std::vector<Outcome>& out,
                       const std::vector<cmp::SequenceFrame>& truth, bool filter, bool frame_difference) {
  std::vector<double> pos_m, pos_pct, rot_deg, ms;
  int valid = 0;
  for (std::size_t i = 0; i < out.size(); ++i) {
    ms.push_back(out[i].ms);
    if (!out[i].valid) continue;
    ++valid;
    const double e = (out[i].position - truth[i].position_m).norm();
    pos_m.push_back(e);
    pos_pct.push_back(100.0 * e / truth[i].position_m.norm());
    rot_deg.push_back(cmp::rotationErrorDeg(out[i].rotation, truth[i].rotation));
  }
  const double rate = static_cast<double>(valid) / static_cast<double>(out.size());
  // Signed mean position error in the camera frame: a bias shared by every method points at the
  // renderer or the truth, one of a single method at that method.
  Eigen::Vector3d bias = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < out.size(); ++i)
    if (out[i].valid) bias += (out[i].position - truth[i].position_m) / std::max(valid, 1);
  std::ostringstream s;
  s << "    \"" << name << "\": {\"frames\": \"" << input << "\", \"detection_rate\": " << num(rate)
    << ",\n      \"position_error_m\": {\"median\": " << num(cmp::percentile(pos_m, 0.5))
    << ", \"p95\": " << num(cmp::percentile(pos_m, 0.95)) << "}"
    << ", \"position_error_pct_of_range\": {\"median\": " << num(cmp::percentile(pos_pct, 0.5))
    << ", \"p95\": " << num(cmp::percentile(pos_pct, 0.95)) << "}"
    << ", \"position_bias_xyz_m\": [" << num(bias.x()) << ", " << num(bias.y()) << ", " << num(bias.z()) << "]"
    << ",\n      \"orientation_error_deg\": {\"median\": " << num(cmp::percentile(rot_deg, 0.5))
    << ", \"p95\": " << num(cmp::percentile(rot_deg, 0.95)) << "}"
    << ", \"ms_per_frame\": {\"median\": " << num(cmp::percentile(ms, 0.5))
    << ", \"p95\": " << num(cmp::percentile(ms, 0.95)) << "}";
  std::map<std::string, int> failures;
  for (const Outcome& o : out)
    if (!o.valid) ++failures[o.status.empty() ? "not found" : o.status];
  s << ",\n      \"failures\": {";
  bool first_failure = true;
  for (const auto& [reason, count] : failures) {
    std::string escaped;
    for (char c : reason) {
      if (c == '"' || c == '\\') escaped += '\\';
      escaped += c;
    }
    s << (first_failure ? "" : ", ") << "\"" << escaped << "\": " << count;
    first_failure = false;
  }
  s << "}";
  if (filter || frame_difference) {
    s << ",\n      \"velocity\": {";
    if (filter) s << "\"filter\": " << velocityJson(out, truth, &Outcome::filter);
    if (filter && frame_difference) s << ",\n        ";
    if (frame_difference) s << "\"frame_difference\": " << velocityJson(out, truth, &Outcome::frame_difference);
    s << "}";
  }
  s << "}";
  std::printf("  %-13s found %5.1f %%  pos %7.4f m (%6.3f %%) p95 %7.4f m  rot %6.3f deg p95 %6.3f  %6.2f ms\n",
              name.c_str(), 100.0 * rate, cmp::percentile(pos_m, 0.5), cmp::percentile(pos_pct, 0.5),
              cmp::percentile(pos_m, 0.95), cmp::percentile(rot_deg, 0.5), cmp::percentile(rot_deg, 0.95),
              cmp::percentile(ms, 0.5));
  return s.str();
}

cv::Mat readGray(const std::string& path) {
  cv::Mat image = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (image.empty()) throw cmp::SequenceError("cannot read the image " + path);
  return image;
}

int usage() {
  std::cerr << "usage: compare_mono --sequence DIR --target TARGET.yaml --mono-config MONO.yaml --out OUT.json\n"
               "                    [--tagged-sequence DIR --tagged-target TAGGED.yaml] [--apriltag-decimate F]\n";
  return 2;
}

struct Arguments {
  std::string seq_dir, tagged_dir, target_yaml, tagged_yaml, mono_yaml, out_path;
  double decimate = 2.0;
};

/// False on a malformed command line (then usage()).
bool parseArguments(int argc, char** argv, Arguments* a) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (i + 1 >= argc) return false;
    const std::string value = argv[++i];
    if (arg == "--sequence") a->seq_dir = value;
    else if (arg == "--tagged-sequence") a->tagged_dir = value;
    else if (arg == "--target") a->target_yaml = value;
    else if (arg == "--tagged-target") a->tagged_yaml = value;
    else if (arg == "--mono-config") a->mono_yaml = value;
    else if (arg == "--out") a->out_path = value;
    else if (arg == "--apriltag-decimate") a->decimate = std::stod(value);
    else return false;
  }
  if (a->seq_dir.empty() || a->target_yaml.empty() || a->mono_yaml.empty() || a->out_path.empty()) return false;
  return a->tagged_dir.empty() == a->tagged_yaml.empty();
}

/// Medians of the sequence's truth: range, the face's angle off the line of sight, speeds.
struct TruthSummary {
  double range_m, off_axis_deg, speed_m_s, angular_speed_deg_s;
};

TruthSummary summarizeTruth(const std::vector<cmp::SequenceFrame>& truth) {
  std::vector<double> range;
  for (const auto& f : truth) range.push_back(f.position_m.norm());
  // Angle between the face normal (x of `target`) and the line of sight back to the camera.
  std::vector<double> off_axis;
  for (const auto& f : truth)
    off_axis.push_back(std::acos(std::clamp(f.rotation.col(0).dot(-f.position_m.normalized()), -1.0, 1.0)) *
                       180.0 / M_PI);
  std::vector<double> true_v, true_w;
  for (const auto& f : truth) {
    true_v.push_back(f.linear_m_s.norm());
    true_w.push_back(f.angular_rad_s.norm() * 180.0 / M_PI);
  }
  return {cmp::percentile(range, 0.5), cmp::percentile(off_axis, 0.5), cmp::percentile(true_v, 0.5),
          cmp::percentile(true_w, 0.5)};
}

/// Our estimator with `solver` over the untagged frames, tracking as the node runs; `cold`: each frame alone
/// (reset before it: no track, no hint), the start the node makes when the stereo estimate is missing.
std::vector<Outcome> runOurs(dp::mono::PoseSolverType solver, const dp::mono::TargetModel& model,
                             const cmp::Sequence& seq, const dp::mono::MonoPoseParams& params,
                             const std::vector<cv::Mat>& images, bool cold = false) {
  dp::mono::MonoPoseParams p = params;
  p.solver = dp::mono::toString(solver);
  dp::mono::MonoPoseEstimator estimator(model, seq.camera, p);
  std::vector<Outcome> out;
  for (std::size_t i = 0; i < seq.frames.size(); ++i) {
    if (cold) estimator.reset();
    const dp::mono::MonoPoseResult r = estimator.process(images[i], seq.frames[i].stamp_s);
    Outcome o;
    o.valid = r.valid;
    o.rotation = r.pose.rotation;
    o.position = r.pose.translation;
    o.ms = r.processing_time_ms;
    o.status = r.status;
    o.filter = fromTwist(r.twist_filter);
    o.frame_difference = fromTwist(r.twist_frame_difference);
    out.push_back(o);
  }
  return out;
}

/// AprilTag on the tagged frames (then tag -> target), velocity by frame differences.
std::vector<Outcome> runAprilTag(const cmp::Sequence& tagged, const Arguments& a, double max_gap_s) {
  const cmp::TagSpec spec = cmp::loadTagSpec(a.tagged_yaml);
  cmp::TagDetector detector(spec, 1, a.decimate);
  dp::mono::FrameDifferenceVelocity difference(max_gap_s);
  std::vector<Outcome> out;
  for (std::size_t i = 0; i < tagged.frames.size(); ++i) {
    const cv::Mat image = readGray(tagged.frames[i].image_path);
    const cmp::TagResult r = detector.detect(image, tagged.camera);
    Outcome o;
    o.valid = r.found;
    o.rotation = r.camera_T_target.linear();
    o.position = r.camera_T_target.translation();
    o.ms = r.processing_time_ms;
    o.status = r.status;
    if (r.found) {
      dp::mono::PoseWithCovariance pose;
      pose.rotation = o.rotation;
      pose.translation = o.position;
      pose.covariance = dp::mono::Matrix6d::Identity() * 1e-6;  // apriltag gives none; unused for the error
      std::string reason;
      difference.update(tagged.frames[i].stamp_s, pose, &reason);
      o.frame_difference = fromTwist(difference.twist());
    }
    out.push_back(o);
  }
  return out;
}

/// The report: the sequence, its truth summary, the settings, then each method's JSON.
std::string reportJson(const cmp::Sequence& seq, const TruthSummary& t, const Arguments& a,
                       const std::string& methods) {
  std::ostringstream json;
  json << "{\n  \"scenario\": \"" << seq.scenario << "\", \"frames\": " << seq.frames.size()
       << ", \"dt_s\": " << num(seq.dt_s) << ",\n  \"range_m\": " << num(t.range_m)
       << ", \"face_off_axis_deg\": " << num(t.off_axis_deg) << ", \"true_speed_m_s\": " << num(t.speed_m_s)
       << ", \"true_angular_speed_deg_s\": " << num(t.angular_speed_deg_s) << ",\n  \"untagged_frames\": \""
       << a.seq_dir << "\", \"tagged_frames\": \"" << a.tagged_dir << "\""
       << ",\n  \"apriltag_quad_decimate\": " << num(a.decimate) << ", \"threads\": 1"
       << ",\n  \"note\": \"ours (paper_5point, pnp; tracking as the node runs) on the untagged target, apriltag "
          "(tag36h11, estimate_tag_pose, then tag -> target) on the tagged variant rendered with the same poses "
          "and noise seed; velocity errors over frames with a valid pose and velocity; ms = thread CPU time\""
       << ",\n  \"methods\": {\n" << methods << "\n  }\n}\n";
  return json.str();
}

}  // namespace

int main(int argc, char** argv) {
  Arguments a;
  if (!parseArguments(argc, argv, &a)) return usage();
  cv::setNumThreads(1);  // one core, as the node runs
  try {
    const cmp::Sequence seq = cmp::readSequence(a.seq_dir);
    const std::vector<cmp::SequenceFrame>& truth = seq.frames;
    std::vector<cv::Mat> images;
    for (const auto& f : truth) images.push_back(readGray(f.image_path));
    // The shipped configuration (the declared defaults with the file's overrides, checked).
    const dp::mono::MonoPoseParams params =
        docking_settings::shippedSettings<dp::mono::MonoPoseNodeSettings>(a.mono_yaml).core;
    const dp::mono::TargetModel model = dp::mono::TargetModel::loadFromYaml(a.target_yaml);
    const TruthSummary summary = summarizeTruth(truth);
    std::printf("%s: %zu frames, range %.3f m, face %.1f deg off the line of sight, |v| %.4f m/s, |w| %.2f deg/s\n",
                seq.scenario.c_str(), truth.size(), summary.range_m, summary.off_axis_deg, summary.speed_m_s,
                summary.angular_speed_deg_s);

    std::ostringstream methods;
    bool first = true;
    for (const dp::mono::PoseSolverType solver : {dp::mono::PoseSolverType::kPaperFivePoint, dp::mono::PoseSolverType::kPnp}) {
      const std::vector<Outcome> out = runOurs(solver, model, seq, params, images);
      methods << (first ? "" : ",\n") << methodJson(dp::mono::toString(solver), "untagged", out, truth, true, true);
      first = false;
    }
    const std::vector<Outcome> cold = runOurs(dp::mono::PoseSolverType::kPnp, model, seq, params, images, true);
    methods << ",\n" << methodJson("pnp_cold", "untagged, each frame alone", cold, truth, false, false);
    if (!a.tagged_dir.empty()) {
      const cmp::Sequence tagged = cmp::readSequence(a.tagged_dir);
      std::string error;
      if (!cmp::sameTrajectory(seq, tagged, 1e-9, 1e-9, &error)) {
        std::cerr << "the tagged sequence is not the same trajectory: " << error << "\n";
        return 1;
      }
      const std::vector<Outcome> out = runAprilTag(tagged, a, params.filter.max_gap_s);
      methods << ",\n" << methodJson("apriltag", "tagged", out, truth, false, true);
    }
    std::ofstream file(a.out_path);
    file << reportJson(seq, summary, a, methods.str());
    if (!file) {
      std::cerr << "cannot write " << a.out_path << "\n";
      return 1;
    }
  } catch (const std::exception& e) {
    std::cerr << "compare_mono: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
