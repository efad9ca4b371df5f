// Is the blob the target? The shape check against the mockup of config/target.yaml and the track gate
// (issue 11: at 6 m a background object inside the depth band was reported as the target, valid).
// Synthetic disparity images with known answers; the rendered-stereo versions are in
// test_disparity_pipeline.cpp.
#include <cmath>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "docking_perception/disparity/disparity_detector.h"
#include "painted_disparity.h"
#include "docking_perception/disparity/target_track_gate.h"

namespace docking_perception {
namespace disparity {
namespace {

const std::string kConfigDir = DISPARITY_CONFIG_DIR;

using test::ourGeometry;
using test::paintRect;
using test::detectorWith;
using test::shippedDetector;
using test::shippedParams;
using test::shippedShape;
using test::shippedRig;

// The mockup face-on: panels 0.15 m behind the face on both sides, then the face.
void paintMockup(cv::Mat* disparity, double x, double z) {
  paintRect(disparity, x - 0.30, 0.0, z + 0.15, 0.30, 0.16);
  paintRect(disparity, x + 0.30, 0.0, z + 0.15, 0.30, 0.16);
  paintRect(disparity, x, 0.0, z, 0.30, 0.24);
}

cv::Mat invalidImage() { return cv::Mat(480, 640, CV_32FC1, cv::Scalar(-1.0f)); }

// The shipped configuration without level_floor: these scenes have no floor, and boxes stand anywhere (the
// height gate, part of level_floor, is tested on its own).
DetectorParams checkingParams() {
  DetectorParams params = shippedParams();
  params.level_floor = false;
  return params;
}

// Whether the detector accepts `params` with `shape` and `rig` (the shipped ones by default).
bool allowed(const DetectorParams& params, const TargetShape& shape = shippedShape(),
             const RigGeometry& rig = shippedRig()) {
  try {
    validate(params, shape, rig);
    return true;
  } catch (const std::invalid_argument&) {
    return false;
  }
}

TEST(ShapeBounds, TheShippedMockupSpansBoxEdgeOnToFaceAndPanels) {
  const ShapeBounds bounds = shapeBounds(TargetShape{});
  EXPECT_NEAR(bounds.min_width_m, 0.30, 0.01);  // the box alone, edge-on... its depth 0.30
  EXPECT_NEAR(bounds.max_width_m, 0.90, 0.01);  // face-on: panel + face + panel
  EXPECT_NEAR(bounds.min_height_m, 0.24, 1e-9);
  EXPECT_NEAR(bounds.max_height_m, 0.24, 1e-9);
}

TEST(ShapeBounds, ReadFromTheShippedTargetYaml) {
  const TargetShape shape = loadTargetShape(kConfigDir + "/target.yaml");
  EXPECT_DOUBLE_EQ(shape.face_width_m, 0.30);
  EXPECT_DOUBLE_EQ(shape.face_height_m, 0.24);
  EXPECT_DOUBLE_EQ(shape.body_depth_m, 0.30);
  EXPECT_DOUBLE_EQ(shape.panel_span_m, 0.30);
  EXPECT_DOUBLE_EQ(shape.panel_height_m, 0.16);
  EXPECT_THROW(loadTargetShape(kConfigDir + "/no_such_target.yaml"), std::runtime_error);
  EXPECT_THROW(loadTargetShape(kConfigDir + "/disparity_detector.yaml"), std::runtime_error);
}

TEST(ShapeCheck, ParametersAreValidated) {
  TargetShape no_face = shippedShape();
  no_face.face_width_m = 0.0;
  EXPECT_FALSE(allowed(checkingParams(), no_face));
  EXPECT_TRUE(allowed(checkingParams()));
}

// The scene: the target at 6 m and a box of another size at the same depth to the side.
class BoxBesideTheTarget : public ::testing::TestWithParam<double> {};

TEST_P(BoxBesideTheTarget, IsNotReportedAndTheTargetIs) {
  const double side_m = GetParam();
  cv::Mat disparity = invalidImage();
  paintRect(&disparity, side_m, -0.1, 6.1, 0.9, 0.7);  // a cabinet, larger than the target
  paintMockup(&disparity, 0.0, 6.0);
  // Before: the largest blob of the band is the cabinet.
  DetectorParams old_params = checkingParams();
  old_params.shape_check_enabled = false;
  const Detection before = detectorWith(old_params).detect(disparity, ourGeometry());
  ASSERT_TRUE(before.found);
  EXPECT_GT(std::abs(before.position_m.x()), 1.0) << "the unchecked detector took the cabinet";

  const Detection after = detectorWith(checkingParams()).detect(disparity, ourGeometry());
  ASSERT_TRUE(after.found) << after.reason;
  EXPECT_NEAR(after.position_m.x(), 0.0, 0.05);
  // At 6 m the face layer's noise floor (kFaceMinBandPx, 0.25 px) takes the panels in: 0.15 m deep.
  EXPECT_NEAR(after.position_m.z(), 6.0, 0.2);
  EXPECT_GE(after.not_target_shaped_skipped, 1);
}

INSTANTIATE_TEST_SUITE_P(SideOffsets, BoxBesideTheTarget, ::testing::Values(-2.0, -1.5, 1.5, 2.0));

TEST(ShapeCheck, OnlyAnotherObjectInViewIsInvalidWithTheReason) {
  for (const auto& size : {std::make_pair(0.9, 0.7), std::make_pair(0.25, 0.9),
                           std::make_pair(1.6, 0.24)}) {
    cv::Mat disparity = invalidImage();
    paintRect(&disparity, 1.8, 0.0, 6.0, size.first, size.second);
    const Detection result = detectorWith(checkingParams()).detect(disparity, ourGeometry());
    EXPECT_FALSE(result.found) << size.first << " x " << size.second;
    EXPECT_EQ(result.outcome, StageOutcome(BandSearchOutcome::kNotTargetShaped)) << result.reason;
    EXPECT_FALSE(result.reason.empty());
    EXPECT_FALSE(result.mask.empty()) << "the rejected blob is kept for the debug image";
  }
}

TEST(ShapeCheck, NearerObjectsOfOtherSizesAreLookedBehind) {
  // A person walking by at 2.5 m, a box at 4 m, a wall segment at 3 m: the target at 6 m is found.
  cv::Mat disparity = invalidImage();
  paintMockup(&disparity, 0.3, 6.0);
  paintRect(&disparity, -1.5, 0.0, 4.0, 0.7, 0.6);    // box nearer than the target, to the side
  paintRect(&disparity, 1.2, -0.3, 3.0, 0.4, 0.8);    // wall segment / door frame
  paintRect(&disparity, -0.9, -0.4, 2.5, 0.45, 1.2);  // a person (cut by the image edge? no)
  const Detection result = detectorWith(checkingParams()).detect(disparity, ourGeometry());
  ASSERT_TRUE(result.found) << result.reason;
  EXPECT_NEAR(result.position_m.x(), 0.3, 0.05);
  EXPECT_NEAR(result.position_m.z(), 6.0, 0.2);
  EXPECT_GE(result.near_objects_skipped, 2);
}

TEST(ShapeCheck, TargetAtAnyRangeAndYawSizePasses) {
  // Face-on and edge-on outlines at 2-6 m (edge-on: the box side 0.30 deep, panels edge-on).
  for (double z : {2.0, 3.0, 4.0, 6.0}) {
    cv::Mat face_on = invalidImage();
    paintMockup(&face_on, 0.1, z);
    const Detection a = detectorWith(checkingParams()).detect(face_on, ourGeometry());
    EXPECT_TRUE(a.found) << z << ": " << a.reason;
    cv::Mat edge_on = invalidImage();
    paintRect(&edge_on, 0.1, 0.0, z, 0.30, 0.24);
    const Detection b = detectorWith(checkingParams()).detect(edge_on, ourGeometry());
    EXPECT_TRUE(b.found) << z << ": " << b.reason;
  }
}

TEST(ShapeCheck, ATargetCutByTheBorderStopsTheSearch) {
  // The target at 1.0 m reaching out of the image on the left: it is rejected as touching the border,
  // never looked behind to a mockup-sized box farther away.
  cv::Mat disparity = invalidImage();
  paintMockup(&disparity, 1.2, 5.0);    // a box of the mockup's size and shape, behind
  paintMockup(&disparity, -0.85, 1.0);  // the target, all but its right panel out of view
  const Detection result = detectorWith(checkingParams()).detect(disparity, ourGeometry());
  EXPECT_FALSE(result.found);
  EXPECT_EQ(result.outcome, StageOutcome(PlausibilityOutcome::kBlobTouchesBorder)) << result.reason;
  EXPECT_LT(result.position_m.z(), 2.0);
}

TEST(SearchHint, PrefersTheTargetShapedBlobInsideTheGate) {
  // Two mockup-sized boxes at the same depth: without a hint the larger/nearer is taken; with the
  // track's hint on the other one, that one.
  cv::Mat disparity = invalidImage();
  paintMockup(&disparity, -1.0, 5.0);
  paintMockup(&disparity, 1.0, 5.1);
  const DisparityDetector detector = detectorWith(checkingParams());
  SearchHint hint;
  hint.valid = true;
  hint.position_m = Eigen::Vector3d(1.0, 0.0, 5.1);
  hint.radius_m = 0.5;
  const Detection with_hint = detector.detect(disparity, ourGeometry(), 0.0, 1e9, cv::Rect(), hint);
  ASSERT_TRUE(with_hint.found) << with_hint.reason;
  EXPECT_NEAR(with_hint.position_m.x(), 1.0, 0.05);
  EXPECT_FALSE(with_hint.outside_hint);
  hint.position_m = Eigen::Vector3d(-1.0, 0.0, 5.0);
  const Detection other = detector.detect(disparity, ourGeometry(), 0.0, 1e9, cv::Rect(), hint);
  ASSERT_TRUE(other.found) << other.reason;
  EXPECT_NEAR(other.position_m.x(), -1.0, 0.05);
  // A hint where nothing is: the first target-shaped blob, flagged as outside the hint.
  hint.position_m = Eigen::Vector3d(0.0, 0.0, 3.0);
  const Detection outside = detector.detect(disparity, ourGeometry(), 0.0, 1e9, cv::Rect(), hint);
  ASSERT_TRUE(outside.found);
  EXPECT_TRUE(outside.outside_hint);
}

// --- Track gate.
Detection foundAt(double x, double z) {
  Detection detection;
  detection.found = true;
  detection.outcome = PlausibilityOutcome::kPassed;
  detection.position_m = Eigen::Vector3d(x, 0.0, z);
  detection.covariance_m2 = Eigen::Matrix3d::Identity() * 0.05 * 0.05;
  return detection;
}

TEST(TargetTrackGate, AJumpOfMetresIsRejectedUntilConfirmed) {
  TrackGateParams params;
  params.confirm_frames = 5;
  TargetTrackGate gate(params);
  double t = 100.0;
  const double dt = 1.0 / 15.0;
  for (int i = 0; i < 10; ++i, t += dt) {
    EXPECT_TRUE(gate.apply(t, foundAt(0.0, 6.0)).found);
  }
  // A box 2 m to the side: rejected with the reason for confirm_frames - 1 frames, then confirmed.
  for (int i = 1; i < params.confirm_frames; ++i, t += dt) {
    const Detection jumped = gate.apply(t, foundAt(2.0, 6.0));
    EXPECT_FALSE(jumped.found) << i;
    EXPECT_EQ(jumped.outcome, StageOutcome(TrackOutcome::kOffTrack));
    EXPECT_FALSE(jumped.reason.empty());
  }
  EXPECT_TRUE(gate.apply(t, foundAt(2.0, 6.0)).found) << "seen confirm_frames times in a row";
  EXPECT_NEAR(gate.trackPosition().x(), 2.0, 1e-9);
}

TEST(TargetTrackGate, AlternatingJumpsAreNeverConfirmed) {
  TargetTrackGate gate{TrackGateParams{}};
  double t = 0.0;
  const double dt = 1.0 / 15.0;
  gate.apply(t, foundAt(0.0, 6.0));
  for (int i = 0; i < 20; ++i) {
    t += dt;
    EXPECT_TRUE(gate.apply(t, foundAt(0.0, 6.0)).found);
    t += dt;
    EXPECT_FALSE(gate.apply(t, foundAt(2.0, 6.0)).found) << "the flicker to the box is never valid";
  }
}

TEST(TargetTrackGate, AMovingTargetStaysInsideTheGate) {
  TargetTrackGate gate{TrackGateParams{}};
  const double dt = 1.0 / 15.0;
  for (int i = 0; i < 150; ++i) {  // 10 s at 0.3 m/s towards the cameras
    const double t = i * dt;
    EXPECT_TRUE(gate.apply(t, foundAt(0.2, 6.0 - 0.3 * t)).found) << t;
  }
}

TEST(TargetTrackGate, TimeoutAndStampsGoingBackwardsStartANewTrack) {
  TargetTrackGate gate{TrackGateParams{}};  // the track lives 2 s without a confirmed detection
  gate.apply(10.0, foundAt(0.0, 6.0));
  Detection lost;
  gate.apply(11.0, lost);  // nothing found
  EXPECT_TRUE(gate.apply(12.5, foundAt(2.0, 6.0)).found) << "2.5 s without a confirmed detection";
  EXPECT_TRUE(gate.apply(5.0, foundAt(-1.0, 4.0)).found) << "a bag restarted: a new track";
  EXPECT_FALSE(gate.hint(100.0).valid) << "no hint from a stale track";
  EXPECT_TRUE(gate.hint(5.1).valid);
}

TEST(TargetTrackGate, DisabledPassesEverythingAndBadParamsAreNamed) {
  TrackGateParams params;
  params.gate_enabled = false;
  TargetTrackGate gate(params);
  gate.apply(0.0, foundAt(0.0, 6.0));
  EXPECT_TRUE(gate.apply(0.1, foundAt(3.0, 6.0)).found);
  params.confirm_frames = 0;
  EXPECT_THROW(gate.setParams(params), std::invalid_argument);
}

// Issue 11, eval_real_clutter_far_{4,6}m: the target merged with a box beside it at its depth into one
// blob the mockup cannot be; its band was looked behind and a target-sized patch of the room 0.85 m
// above the optical axis, 2 m farther and 3 m to the side, was reported valid. On the test bed the
// port is at camera height: such a patch is not the target.
TEST(HeightGate, APatchFarAboveTheAxisBehindAMergedBlobIsNotTheTarget) {
  cv::Mat disparity = invalidImage();
  paintRect(&disparity, 3.4, -0.85, 6.8, 0.45, 0.35);  // the patch high on the far wall
  paintRect(&disparity, 0.65, -0.38, 6.2, 0.40, 1.0);  // a box touching the mockup's panel
  paintMockup(&disparity, 0.0, 6.0);
  DetectorParams params = checkingParams();  // before: no gate
  params.split_depth_step_m = 0.0;  // the split (shipped) finds the target in the merged blob: the gate alone
  const Detection before = detectorWith(params).detect(disparity, ourGeometry());
  ASSERT_TRUE(before.found) << "the scene no longer reproduces the failure: " << before.reason;
  EXPECT_GT(before.position_m.x(), 3.0);

  params.level_floor = true;
  const Detection after = detectorWith(params).detect(disparity, ourGeometry());
  EXPECT_FALSE(after.found) << "taken at (" << after.position_m.transpose() << ")";
  EXPECT_EQ(after.outcome, StageOutcome(BandSearchOutcome::kNotTargetShaped)) << after.reason;

  const Detection shipped = detectorWith(shippedParams()).detect(disparity, ourGeometry());
  ASSERT_TRUE(shipped.found) << shipped.reason;
  EXPECT_NEAR(shipped.position_m.x(), 0.0, 0.05) << "with the split, the target itself";
}

TEST(HeightGate, TheTargetAtCameraHeightPassesAndOneOnAShelfDoesNot) {
  cv::Mat disparity = invalidImage();
  paintMockup(&disparity, 0.4, 5.0);
  const DetectorParams params = shippedParams();
  const Detection result = detectorWith(params).detect(disparity, ourGeometry());
  ASSERT_TRUE(result.found) << result.reason;
  EXPECT_NEAR(result.position_m.x(), 0.4, 0.05);
  // The same mockup 0.5 m above the axis (a shelf): not where the port of a target on the floor is.
  cv::Mat raised = invalidImage();
  paintRect(&raised, 0.1, -0.5, 5.15, 0.30, 0.16);
  paintRect(&raised, 0.7, -0.5, 5.15, 0.30, 0.16);
  paintRect(&raised, 0.4, -0.5, 5.0, 0.30, 0.24);
  const Detection shelf = detectorWith(params).detect(raised, ourGeometry());
  EXPECT_FALSE(shelf.found);
  EXPECT_EQ(shelf.outcome, StageOutcome(BandSearchOutcome::kNotTargetShaped)) << shelf.reason;
}

// The floor cut and the height gate follow the rig: cameras 1 m above the floor and the port at 0.5 m
// (robot.yaml, target.yaml) put the port 0.5 m below the axis, where the shipped rig's floor cut drops it.
TEST(HeightGate, FollowsTheCamerasAndThePortsHeights) {
  cv::Mat lowered = invalidImage();
  paintRect(&lowered, 0.1, 0.5, 5.15, 0.30, 0.16);
  paintRect(&lowered, 0.7, 0.5, 5.15, 0.30, 0.16);
  paintRect(&lowered, 0.4, 0.5, 5.0, 0.30, 0.24);
  RigGeometry high_cameras = shippedRig();
  high_cameras.camera_height_m = 1.0;
  high_cameras.port_height_m = 0.5;
  const Detection found =
      DisparityDetector(shippedParams(), shippedShape(), high_cameras).detect(lowered, ourGeometry());
  ASSERT_TRUE(found.found) << found.reason;
  EXPECT_NEAR(found.position_m.y(), 0.5, 0.05);
  EXPECT_FALSE(shippedDetector().detect(lowered, ourGeometry()).found) << "below the shipped rig's floor cut";
}

// The limits level_floor, the band and the shape check derive from config/robot.yaml, config/target.yaml and
// config/stereo_image_proc.yaml: on the shipped rig, the values the detector was tuned with.
TEST(RigLimits, DerivedFromTheShippedRig) {
  const RigGeometry rig = shippedRig();
  EXPECT_DOUBLE_EQ(rig.camera_height_m, 0.25);
  EXPECT_DOUBLE_EQ(rig.port_height_m, 0.25);
  EXPECT_EQ(rig.matcher_window_px, 15);
  const RigLimits limits = rigLimits(shippedShape(), rig);
  EXPECT_EQ(limits.floor_cut_m, 0.15);  // the face's lower edge 0.12 m below the axis, plus 0.03 m
  EXPECT_EQ(limits.port_y_m, 0.0);
  EXPECT_EQ(limits.band_depth_m, 0.5);    // the 0.30 m box plus 0.2 m
  EXPECT_EQ(limits.shape_margin_px, 8.0);
  EXPECT_THROW(loadRigGeometry(kConfigDir + "/no_such_robot.yaml", kConfigDir + "/target.yaml", 15),
               std::runtime_error);
  EXPECT_THROW(loadRigGeometry(kConfigDir + "/target.yaml", kConfigDir + "/target.yaml", 15), std::runtime_error);
}

TEST(RigLimits, AFloorCutBelowTheFloorIsRefusedUnlessThereIsNoFloor) {
  RigGeometry low_cameras = shippedRig();
  low_cameras.camera_height_m = 0.1;  // the face's lower edge (0.12 m below the port) is under the floor
  low_cameras.port_height_m = 0.1;
  EXPECT_FALSE(allowed(shippedParams(), shippedShape(), low_cameras));
  EXPECT_TRUE(allowed(checkingParams(), shippedShape(), low_cameras));
  try {
    validate(shippedParams(), shippedShape(), low_cameras);
  } catch (const docking_settings::ConfigError& e) {
    EXPECT_EQ(e.key(), "level_floor");
  }
}

// Issue 11, eval_real_specular_2m: glare left part of the face at 2 m (narrower than the mockup can be);
// its band was looked behind and a box stack 1.4 m farther, of the mockup's size, was reported valid. A
// blob that may be the degraded target stops the search.
TEST(DegradedTarget, ABlobOfTheMockupsSizeIsNotLookedBehind) {
  cv::Mat disparity = invalidImage();
  paintRect(&disparity, -0.6, 0.0, 3.4, 0.30, 0.28);  // the box stack behind, to the left
  paintRect(&disparity, -0.07, 0.0, 2.0, 0.16, 0.24);  // the face's left half, the rest under glare
  DetectorParams params = checkingParams();
  params.stop_behind_target_sized = false;  // before
  const Detection before = detectorWith(params).detect(disparity, ourGeometry());
  ASSERT_TRUE(before.found) << "the scene no longer reproduces the failure: " << before.reason;
  EXPECT_NEAR(before.position_m.z(), 3.4, 0.2);

  params.stop_behind_target_sized = true;
  const Detection after = detectorWith(params).detect(disparity, ourGeometry());
  EXPECT_FALSE(after.found) << "taken at (" << after.position_m.transpose() << ")";
  EXPECT_EQ(after.outcome, StageOutcome(BandSearchOutcome::kNotTargetShaped)) << after.reason;
  EXPECT_NEAR(after.shape.range_z_m, 2.0, 0.1) << "the reported blob is the degraded face";
}

// Issue 11, eval_far_3m_on: block matching's mismatched strip along the target's left edge, 16 px wide and
// a little nearer than the face, is within the mockup's upper bounds and fails only its width: taken for a
// degraded target it stopped the search in front of the target. Narrower than degraded_min_width_fraction
// of the mockup's edge-on width, it is looked behind.
TEST(DegradedTarget, AStripAlongAnOccludingEdgeIsLookedBehind) {
  cv::Mat disparity = invalidImage();
  paintMockup(&disparity, 0.2, 3.0);
  const double strip_m = 16.0 * 2.4 / 550.0;  // 16 px at 2.4 m: 0.07 m, 0.23 of the edge-on 0.30 m
  paintRect(&disparity, 0.2 - 0.48 - strip_m / 2, 0.0, 2.4, strip_m, 0.24);
  DetectorParams params = checkingParams();
  params.stop_behind_target_sized = true;
  params.degraded_min_width_fraction = 0.0;  // before
  const Detection before = detectorWith(params).detect(disparity, ourGeometry());
  EXPECT_FALSE(before.found) << "the scene no longer reproduces the failure: found at ("
                             << before.position_m.transpose() << ")";
  EXPECT_NEAR(before.shape.range_z_m, 2.4, 0.1) << "the search stopped at the strip";

  params.degraded_min_width_fraction = 0.5;
  ASSERT_TRUE(allowed(params));
  const Detection after = detectorWith(params).detect(disparity, ourGeometry());
  ASSERT_TRUE(after.found) << after.reason;
  EXPECT_NEAR(after.position_m.x(), 0.2, 0.05);
  EXPECT_NEAR(after.position_m.z(), 3.0, 0.1);
  params.degraded_min_width_fraction = 1.5;
  EXPECT_FALSE(allowed(params));
}

TEST(DegradedTarget, LargerNearerObjectsAreStillLookedBehind) {
  // A cabinet (taller than the mockup) at 4 m: the target at 6 m behind it is still found.
  cv::Mat disparity = invalidImage();
  paintMockup(&disparity, 0.3, 6.0);
  paintRect(&disparity, -1.2, -0.2, 4.0, 0.6, 0.9);
  DetectorParams params = checkingParams();
  params.stop_behind_target_sized = true;
  const Detection result = detectorWith(params).detect(disparity, ourGeometry());
  ASSERT_TRUE(result.found) << result.reason;
  EXPECT_NEAR(result.position_m.x(), 0.3, 0.05);
}

// Issue 11, eval_real_clutter_far_4m: the target at 4 m in front of a box 0.35 m behind it, and a box
// 0.1 m nearer beside it standing against that box: all three in one depth band, one blob of
// 1.6 x 1.2 m that the mockup cannot be. The target stands 0.35 m in front of everything around it:
// split out at its own depth, it is the mockup.
void paintTargetAmongBoxes(cv::Mat* disparity) {
  paintRect(disparity, -0.25, -0.35, 4.35, 0.8, 1.2);  // the box behind, up to 0.95 m above the axis
  paintRect(disparity, -0.8, -0.25, 3.9, 0.4, 1.0);    // the box beside, nearer, against it
  paintMockup(disparity, 0.0, 4.0);
}

TEST(MergedBlob, WithoutTheSplitTheTargetIsNotFound) {
  cv::Mat disparity = invalidImage();
  paintTargetAmongBoxes(&disparity);
  DetectorParams params = checkingParams();
  params.split_depth_step_m = 0.0;  // before
  const Detection before = detectorWith(params).detect(disparity, ourGeometry());
  EXPECT_FALSE(before.found) << "the scene no longer reproduces the merge: found at ("
                             << before.position_m.transpose() << ")";
  EXPECT_EQ(before.merged_blobs_split, 0);
}

TEST(MergedBlob, TheTargetIsSplitFromTheBoxesAroundIt) {
  cv::Mat disparity = invalidImage();
  paintTargetAmongBoxes(&disparity);
  DetectorParams params = checkingParams();
  params.split_depth_step_m = 0.15;
  const Detection result = detectorWith(params).detect(disparity, ourGeometry());
  ASSERT_TRUE(result.found) << result.reason;
  EXPECT_EQ(result.merged_blobs_split, 1);
  EXPECT_NEAR(result.position_m.x(), 0.0, 0.03);
  EXPECT_NEAR(result.position_m.y(), 0.0, 0.03);
  EXPECT_NEAR(result.position_m.z(), 4.0, 0.05);
  EXPECT_LT(result.shape.width_m, 1.0) << "the reported blob is the mockup, not the merged one";
}

// A target-sized bump 5 cm proud of a box's face (block-matching noise on a busy texture): at its own
// level it has the mockup's shape, but 0.15 m deeper it is the whole box, so it is not split out.
TEST(MergedBlob, ABumpOnABoxIsNotSplitOut) {
  cv::Mat disparity = invalidImage();
  paintRect(&disparity, 0.0, -0.2, 4.0, 1.2, 0.9);
  paintRect(&disparity, 0.1, -0.05, 3.95, 0.35, 0.24);
  DetectorParams params = checkingParams();
  params.split_depth_step_m = 0.15;
  const Detection result = detectorWith(params).detect(disparity, ourGeometry());
  EXPECT_FALSE(result.found) << "bump taken at (" << result.position_m.transpose() << ")";
  EXPECT_EQ(result.outcome, StageOutcome(BandSearchOutcome::kNotTargetShaped)) << result.reason;
  EXPECT_EQ(result.merged_blobs_split, 0);
}

// The target against a box at its own depth (no depth step between them) cannot be told apart: the
// blob stays merged and is reported not target-shaped, never a guess.
TEST(MergedBlob, ATargetFlushWithABoxStaysInvalid) {
  cv::Mat disparity = invalidImage();
  paintRect(&disparity, 0.65, -0.25, 4.05, 0.5, 1.0);  // against the right panel, same depth
  paintMockup(&disparity, 0.0, 4.0);
  DetectorParams params = checkingParams();
  params.split_depth_step_m = 0.15;
  const Detection result = detectorWith(params).detect(disparity, ourGeometry());
  EXPECT_FALSE(result.found) << "taken at (" << result.position_m.transpose() << ")";
  EXPECT_EQ(result.outcome, StageOutcome(BandSearchOutcome::kNotTargetShaped)) << result.reason;
}

TEST(MergedBlob, TheSplitStepIsValidated) {
  DetectorParams params = checkingParams();
  params.split_depth_step_m = -0.1;
  EXPECT_FALSE(allowed(params));
  params.split_depth_step_m = 0.15;
  EXPECT_TRUE(allowed(params));
}

}  // namespace
}  // namespace disparity
}  // namespace docking_perception
