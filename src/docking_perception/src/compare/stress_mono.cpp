// stress_mono: the monocular pose under blur, clutter, glare, occlusion and IR reflections (issue 11),
// rendered by docking_sim's renderer, scored against the truth (detection, errors, covariance coverage,
// confident wrong estimates). Prints one table row per condition; optionally writes JSON.
//
//   stress_mono --target config/target.yaml --visible config/mono_pose_visible.yaml --ir config/mono_pose_ir.yaml
//               [--seeds FIRST:COUNT] [--frames N] [--solver pnp|paper_5point] [--only NAME,...] [--out OUT.json]
//               [--baseline] [--set KEY=VALUE ...] [--dump PREFIX] [--verbose]
//
// --dump: save the first frame of each condition as PREFIX<condition>.png (to look at).
//
// --set: override a key of the mono_pose YAML files (both modes) for experiments.
//
// --baseline: the search without its blur aids and the pose without the checks a setting switches off (no
// half-resolution search, no blurred model, no appearance, ambiguity or sigma checks, no blur gain); the
// covariance floor and the IR blob checks are constants of the method and stay.
//
// Seeds: 100:40 is the tuning range, 500:40 the report range (never used for tuning).
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>

#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "docking_settings/yaml_loader.h"
#include "mono_stress.h"

namespace mono = docking_perception::mono;
namespace stress = docking_perception::stress;

namespace {

std::string arg(int argc, char** argv, const std::string& name, const std::string& fallback) {
  for (int i = 1; i + 1 < argc; ++i) {
    if (argv[i] == name) return argv[i + 1];
  }
  return fallback;
}

bool selected(const std::string& only, const std::string& name) {
  if (only.empty()) return true;
  std::stringstream list(only);
  std::string item;
  while (std::getline(list, item, ',')) {
    if (item == name) return true;
  }
  return false;
}

/// --baseline: the blur aids and the checks a setting switches off, off.
void applyBaseline(mono::MonoPoseParams* p) {
  p->use_half_resolution = false;
  p->features.blurred_model_sigma_px = 0.0;
  p->consistency.min_appearance_ncc = -1.0;
  p->consistency.max_ambiguity_deg = 360.0;
  p->consistency.ambiguity_chi2 = 0.0;
  p->consistency.covariance_blur_gain = 0.0;
  p->consistency.max_rotation_sigma_deg = 1e6;
  p->consistency.innovation_window_frames = 0.0;
  p->consistency.confirm_new_orientation = false;
}

/// Sets `key` to `value` in p; false when p has no such key of a supported type.
bool setKey(mono::MonoPoseParams* p, const std::string& key, const std::string& value) {
  bool known = false;
  mono::visitSettings(*p, [&](const docking_settings::SettingInfo&, const std::string& name, auto& field) {
    using Field = std::decay_t<decltype(field)>;
    if (key != name) return;
    known = true;
    if constexpr (std::is_same_v<Field, bool>) field = value == "true" || value == "1";
    else if constexpr (std::is_same_v<Field, int>) field = std::stoi(value);
    else if constexpr (std::is_same_v<Field, double>) field = std::stod(value);
    else if constexpr (std::is_same_v<Field, std::string>) field = value;
    else if constexpr (std::is_same_v<Field, std::vector<int>>) {
      // A comma-separated list ("" or "none": empty).
      field.clear();
      std::stringstream list(value == "none" ? std::string() : value);
      for (std::string item; std::getline(list, item, ',');) field.push_back(std::stoi(item));
    } else known = false;
  });
  return known;
}

/// Every --set KEY=VALUE, on both modes' parameters. 0, or the exit code (reported).
int applySetOverrides(int argc, char** argv, mono::MonoPoseParams* visible, mono::MonoPoseParams* ir) {
  for (int i = 1; i + 1 < argc; ++i) {
    if (std::string(argv[i]) != "--set") continue;
    const std::string assignment = argv[i + 1];
    const size_t eq = assignment.find('=');
    if (eq == std::string::npos) {
      std::cerr << "--set needs KEY=VALUE\n";
      return 2;
    }
    const std::string key = assignment.substr(0, eq);
    const std::string value = assignment.substr(eq + 1);
    bool known = false;
    for (mono::MonoPoseParams* p : {visible, ir}) known = setKey(p, key, value);
    if (!known) {
      std::cerr << "--set: unknown or unsupported key " << key << "\n";
      return 2;
    }
  }
  return 0;
}

struct Options {
  std::string target, visible_yaml, ir_yaml, seeds, solver, only, out_path, dump;
  int frames = 3;
  uint64_t first_seed = 0;
  int trials = 0;
  bool baseline = false, verbose = false;
  mono::MonoPoseParams visible_params, ir_params;
};

bool hasFlag(int argc, char** argv, const std::string& flag) {
  bool found = false;
  for (int i = 1; i < argc; ++i) found = found || std::string(argv[i]) == flag;
  return found;
}

/// The command line and the two modes' parameters (shipped, then --solver, --baseline, --set, checked).
/// 0, or the exit code (reported).
int readOptions(int argc, char** argv, Options* o) {
  o->target = arg(argc, argv, "--target", "config/target.yaml");
  o->visible_yaml = arg(argc, argv, "--visible", "config/mono_pose_visible.yaml");
  o->ir_yaml = arg(argc, argv, "--ir", "config/mono_pose_ir.yaml");
  o->seeds = arg(argc, argv, "--seeds", "100:40");
  o->frames = std::stoi(arg(argc, argv, "--frames", "3"));
  o->solver = arg(argc, argv, "--solver", "pnp");
  o->only = arg(argc, argv, "--only", "");
  o->out_path = arg(argc, argv, "--out", "");
  o->dump = arg(argc, argv, "--dump", "");
  const size_t colon = o->seeds.find(':');
  if (colon == std::string::npos) {
    std::cerr << "--seeds must be FIRST:COUNT\n";
    return 2;
  }
  o->first_seed = std::stoull(o->seeds.substr(0, colon));
  o->trials = std::stoi(o->seeds.substr(colon + 1));
  if (o->first_seed + static_cast<uint64_t>(o->trials) > 9000 && o->first_seed < 10000) {
    std::cerr << "seeds 9000-9999 are reserved for the campaign's final report\n";
    return 2;
  }
  try {
    o->visible_params = docking_settings::shippedSettings<mono::MonoPoseNodeSettings>(o->visible_yaml).core;
    o->ir_params = docking_settings::shippedSettings<mono::MonoPoseNodeSettings>(o->ir_yaml).core;
  } catch (const std::exception& e) {
    std::cerr << "stress_mono: " << e.what() << "\n";
    return 1;
  }
  mono::PoseSolverType solver_type;
  if (!mono::parsePoseSolver(o->solver, &solver_type)) {
    std::cerr << "--solver must be pnp or paper_5point\n";
    return 2;
  }
  o->visible_params.solver = o->solver;
  o->ir_params.solver = o->solver;
  o->verbose = hasFlag(argc, argv, "--verbose");
  o->baseline = hasFlag(argc, argv, "--baseline");
  if (o->baseline) {
    for (mono::MonoPoseParams* p : {&o->visible_params, &o->ir_params}) applyBaseline(p);
  }
  if (const int code = applySetOverrides(argc, argv, &o->visible_params, &o->ir_params)) return code;
  for (const mono::MonoPoseParams* p : {&o->visible_params, &o->ir_params}) {
    try {
      mono::validate(*p);
    } catch (const std::invalid_argument& e) {
      std::cerr << "stress_mono: " << e.what() << "\n";
      return 2;
    }
  }
  return 0;
}

/// --verbose: one line per frame, what the estimator saw (diagnosis while tuning).
void printFrames(const stress::StressRenderer& renderer, const mono::TargetModel& model,
                 const stress::StressCondition& condition, const mono::MonoPoseParams& params, const Options& o) {
  mono::MonoPoseEstimator estimator(model, renderer.camera(), params);
  for (int t = 0; t < o.trials; ++t) {
    const uint64_t seed = o.first_seed + static_cast<uint64_t>(t);
    const stress::TrialPose pose = renderer.drawPose(condition, seed);
    estimator.reset();
    for (int f = 0; f < o.frames; ++f) {
      const stress::StressFrame frame = renderer.render(condition, pose, seed, seed * 16 + static_cast<uint64_t>(f));
      if (condition.region_hint) {
        estimator.setRegionHint(stress::noisyFaceBox(model, renderer.camera(), pose, seed * 16 + f), f / 30.0);
      }
      const mono::MonoPoseResult r = estimator.process(frame.gray, f / 30.0);
      const stress::EstimateScore e = stress::scoreEstimate(r, frame.truth);
      std::printf("  %s seed %llu frame %d range %.2f: %s matches %d inliers %d level %d ncc %.2f blur %.1f spread %.2f "
                  "pos %.2f %% ang %.2f deg z [%.1f %.1f %.1f %.1f %.1f %.1f] dots %d direct %d ecc %.3f %s\n",
                  condition.name.c_str(), static_cast<unsigned long long>(seed), f, e.range_m,
                  r.valid ? "valid" : mono::toString(r.reject_reason), r.feature_matches, r.feature_inliers,
                  r.pyramid_level, r.appearance_ncc, r.blur_sigma_px, r.inlier_spread, e.position_error_pct,
                  e.orientation_error_deg, e.normalized[0], e.normalized[1], e.normalized[2], e.normalized[3],
                  e.normalized[4], e.normalized[5], r.found_by_dots ? 1 : 0, r.used_direct_alignment ? 1 : 0,
                  r.direct_correlation,
                  r.status.c_str());
    }
  }
}

/// The condition's table row.
void printRow(const stress::ConditionSummary& s) {
  std::ostringstream reasons;
  for (const auto& [reason, count] : s.reasons) reasons << reason << ":" << count << " ";
  if (s.orientation_withheld > 0) reasons << "(valid, orientation withheld:" << s.orientation_withheld << ")";
  std::printf("%-36s %6.3f %6.3f %7.3f %7.3f  %5.2f %5.2f %5.2f %5.2f %5.2f %5.2f %4d %6.2f  %s\n", s.name.c_str(),
              s.frames ? static_cast<double>(s.valid) / s.frames : 0.0,
              s.cold_frames ? static_cast<double>(s.cold_valid) / s.cold_frames : 0.0, s.median_position_pct,
              s.median_orientation_deg, s.coverage[0], s.coverage[1], s.coverage[2], s.coverage[3], s.coverage[4],
              s.coverage[5], s.confident_wrong, s.cpu_ms_median, reasons.str().c_str());
  std::fflush(stdout);
}

/// The condition's entry in the JSON report ("name": {...}).
void writeConditionJson(std::ostringstream& json, const stress::ConditionSummary& s) {
  json << "\"" << s.name << "\": {\"frames\": " << s.frames << ", \"valid\": " << s.valid
       << ", \"cold_frames\": " << s.cold_frames << ", \"cold_valid\": " << s.cold_valid
       << ", \"median_position_pct\": " << s.median_position_pct
       << ", \"median_orientation_deg\": " << s.median_orientation_deg << ", \"coverage_3sigma\": [";
  for (int a = 0; a < 6; ++a) json << (a ? ", " : "") << s.coverage[a];
  json << "], \"confident_wrong\": " << s.confident_wrong << ", \"orientation_withheld\": " << s.orientation_withheld
       << ", \"cpu_ms_median\": " << s.cpu_ms_median << "}";
}

}  // namespace

int main(int argc, char** argv) {
  cv::setNumThreads(1);
  Options o;
  if (const int code = readOptions(argc, argv, &o)) return code;
  const mono::TargetModel model = mono::TargetModel::loadFromYaml(o.target);
  const stress::StressRenderer renderer(model);

  std::printf("stress_mono: seeds %s, %d frames per trial, solver %s%s\n", o.seeds.c_str(), o.frames,
              o.solver.c_str(), o.baseline ? ", baseline (before issue 11)" : "");
  std::printf("%-36s %6s %6s %7s %7s  %5s %5s %5s %5s %5s %5s %4s %6s  %s\n", "condition", "detect", "cold",
              "pos %r", "ang deg", "cx", "cy", "cz", "crx", "cry", "crz", "CW", "cpu ms", "invalid reasons");
  std::ostringstream json;
  json << "{\"seeds\": \"" << o.seeds << "\", \"frames_per_trial\": " << o.frames << ", \"solver\": \"" << o.solver
       << "\", \"conditions\": {";
  bool first = true;
  for (const stress::StressCondition& condition : stress::standardConditions()) {
    if (!selected(o.only, condition.name)) continue;
    const mono::MonoPoseParams& params = condition.infrared ? o.ir_params : o.visible_params;
    if (!o.dump.empty()) {
      const stress::TrialPose pose = renderer.drawPose(condition, o.first_seed);
      cv::imwrite(o.dump + condition.name + ".png",
                  renderer.render(condition, pose, o.first_seed, o.first_seed * 16).gray);
    }
    if (o.verbose) printFrames(renderer, model, condition, params, o);
    const stress::ConditionSummary s =
        stress::runCondition(renderer, condition, params, o.first_seed, o.trials, o.frames);
    printRow(s);
    json << (first ? "" : ", ");
    writeConditionJson(json, s);
    first = false;
  }
  json << "}}\n";
  if (!o.out_path.empty()) std::ofstream(o.out_path) << json.str();
  return 0;
}
