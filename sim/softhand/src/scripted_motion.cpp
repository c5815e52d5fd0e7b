#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "haptic/softhand/bullet_coupling.hpp"
#include "haptic/softhand/tracking_input.hpp"

namespace haptic::softhand {

namespace {

// 0 -> 1 with zero slope at both ends.
double smooth(double s) {
    s = std::clamp(s, 0.0, 1.0);
    return s * s * (3.0 - 2.0 * s);
}

// Phases of one period (s): descend and press, slide over the edge, lift, return.
constexpr double kPressEnd = 1.0;
constexpr double kSlideEnd = 4.0;
constexpr double kLiftEnd = 4.75;

// Finger posture while pressing (index..little; thumb stays straight): nearly straight,
// curling a little at MCP and PIP as it presses (so the exoskeleton's joints move with the
// press). The DIP stays straight: with DIP flexion the distal phalanx is the finger's
// steepest segment and the tip, not the pad, meets the face.
constexpr std::array<double, 3> kRestFlexion{0.06, 0.04, 0.0};
constexpr std::array<double, 3> kPressFlexion{0.04, 0.03, 0.0};
// The whole hand is pitched so that the distal phalanx meets the face at this angle, tip
// lower: the pad under the thimble's plate presses, and the knuckles stay above the face.
// (With a curled finger and a level hand the tip met the face at ~30 degrees, outside the
// region under the plate, so the thimble never rendered the demo's contact.)
constexpr double kDistalPitchRad = 0.10;
}  // namespace

PressSlideEdgeScript::PressSlideEdgeScript(const TrackedHand& hand,
                                           const config::HandConfig& config,
                                           const config::SceneObject& target, bool loop)
    : hand_(hand), finger_(config.finger.value_or(config::Finger::kIndex)), loop_(loop) {
    const auto* box = std::get_if<config::BoxShape>(&target.shape);
    if (box == nullptr) {
        throw std::invalid_argument("press_slide_edge: target_object '" + target.name +
                                    "' must be a box (it needs a top face and an edge)");
    }
    half_extents_ = Vec3(box->half_extents_m[0], box->half_extents_m[1], box->half_extents_m[2]);
    object_.position_m =
        Vec3(target.pose.position_m[0], target.pose.position_m[1], target.pose.position_m[2]);
    object_.rotation = rotationFromRpy(target.pose.rpy_rad);
    pad_radius_m_ = 0.5 * config.anthropometry.fingertip_diameter_m;
    distal_half_length_m_ = 0.5 * phalanxLengths(finger_, config.anthropometry.hand_length_m)[2];
    (void)hand_.referenceDistal(finger_);  // throws when the finger is not simulated
}

double PressSlideEdgeScript::press(double t_s) const {
    const double t = loop_ ? std::fmod(std::max(t_s, 0.0), kPeriod) : std::clamp(t_s, 0.0, kPeriod);
    if (t < kPressEnd) {
        return smooth(t / kPressEnd);
    }
    if (t < kSlideEnd) {
        return 1.0;
    }
    return 1.0 - smooth((t - kSlideEnd) / (kLiftEnd - kSlideEnd));
}

Vec3 PressSlideEdgeScript::padTargetInObject(double t_s) const {
    const double t = loop_ ? std::fmod(std::max(t_s, 0.0), kPeriod) : std::clamp(t_s, 0.0, kPeriod);
    const double x_start = -0.5 * half_extents_.x();
    const double x_end = half_extents_.x() + 0.010;  // the pad ends beyond the +x edge
    const double top = half_extents_.z();
    double x = x_start;
    if (t >= kPressEnd && t < kSlideEnd) {
        x = x_start + (x_end - x_start) * smooth((t - kPressEnd) / (kSlideEnd - kPressEnd));
    } else if (t >= kSlideEnd && t < kLiftEnd) {
        x = x_end;
    } else if (t >= kLiftEnd) {
        x = x_end + (x_start - x_end) * smooth((t - kLiftEnd) / (kPeriod - kLiftEnd));
    }
    const double p = press(t_s);
    const double z = top + kLiftHeight + (-kPressDepth - kLiftHeight) * p;
    return {x, 0.0, z};
}

std::array<double, kHandPoseAngles> PressSlideEdgeScript::posture(double p) const {
    std::array<double, kHandPoseAngles> flexion{};
    for (std::size_t finger = 1; finger < 5; ++finger) {
        for (std::size_t s = 0; s < 3; ++s) {
            flexion[3 * finger + s] = kRestFlexion[s] + p * kPressFlexion[s];
        }
    }
    return flexion;
}

HandPoseInput PressSlideEdgeScript::at(double t_s) const {
    HandPoseInput input;
    input.flexion_rad = posture(press(t_s));
    input.wrist = {Vec3::Zero(), Mat3::Identity()};
    // Where the lowest point of the distal pad lands with the wrist at the object's origin,
    // in the object frame (the hand is carried with the object's orientation).
    std::vector<BonePose> poses;
    hand_.referencePoses(input, poses);
    const BonePose& distal = poses[static_cast<std::size_t>(hand_.referenceDistal(finger_))];
    const Vec3 curled_axis = distal.rotation * Vec3::UnitX();
    Mat3 pitch = Mat3::Identity();
    const Vec3 level(curled_axis.x(), curled_axis.y(), 0.0);
    if (level.norm() > 1e-6) {
        const Vec3 wanted = std::cos(kDistalPitchRad) * level.normalized() -
                            std::sin(kDistalPitchRad) * Vec3::UnitZ();
        pitch = Eigen::Quaterniond::FromTwoVectors(curled_axis, wanted).toRotationMatrix();
    }
    // The distal bone runs half its length either side of its centre; the lowest point of
    // its tissue is a pad radius below the lower end. Pitching the wrist about its origin
    // carries every bone with it.
    const Vec3 axis = pitch * curled_axis;
    const Vec3 centre = pitch * distal.position_m;
    const Vec3 tip = centre + axis * distal_half_length_m_;
    const Vec3 base = centre - axis * distal_half_length_m_;
    Vec3 lowest = tip.z() < base.z() ? tip : base;
    lowest.z() -= pad_radius_m_;
    const Vec3 wrist_in_object = padTargetInObject(t_s) - lowest;
    input.wrist.position_m = object_.position_m + object_.rotation * wrist_in_object;
    input.wrist.rotation = object_.rotation * pitch;
    return input;
}

// ---- grasp_lift_place_push ------------------------------------------------------------

namespace {

// A lateral (key) pinch: the box is held between the thumb pad and the radial (-y) side of
// the index's proximal phalanx. The model's index has no abduction, so its pad cannot face
// the thumb; its side faces -y at any flexion, and the thumb pad turns to face +y as the
// thumb flexes (pad normal within ~20 degrees of +y over closures 0.3-0.5, scratch search
// over the builder's hand). The index is held nearly straight, tipped down 0.2 rad, so
// that its tip stays above the table; the thumb's three joints close together.
constexpr std::array<double, 3> kIndexHook{0.2, 0.0, 0.0};
constexpr std::array<double, 3> kThumbPerClosure{0.4, 0.4, 0.4};
constexpr double kPadAlongDistal = 0.2;  // of the distal length, from its centre to the tip

// The time within the script's period.
double scriptTime(double t_s, bool loop, double period) {
    return loop ? std::fmod(std::max(t_s, 0.0), period) : std::clamp(t_s, 0.0, period);
}

double ramp(double t, double start, double end) {
    return smooth((t - start) / (end - start));
}

// Rolls the hand about its length (thumb side up). Unrolled, the index's proximal phalanx
// meets the box's +y face about 9 mm above the thumb pad: the pinch is then a couple that
// rolls the box about x until its face leaves the index, and the box slips out during the
// lift. Rolled, both contacts sit at about the same height.
constexpr double kWristRollRad = -0.2;

Mat3 wristRoll() {
    return Eigen::AngleAxisd(kWristRollRad, Vec3::UnitX()).toRotationMatrix();
}

}  // namespace

GraspLiftPlacePushScript::GraspLiftPlacePushScript(const TrackedHand& hand,
                                                   const config::HandConfig& config,
                                                   const config::SceneObject& target, bool loop)
    : hand_(hand), loop_(loop) {
    const auto* box = std::get_if<config::BoxShape>(&target.shape);
    if (box == nullptr) {
        throw std::invalid_argument("grasp_lift_place_push: target_object '" + target.name +
                                    "' must be a box");
    }
    (void)hand_.referenceDistal(config::Finger::kThumb);  // throws when not simulated
    (void)hand_.referenceDistal(config::Finger::kIndex);
    start_ = Vec3(target.pose.position_m[0], target.pose.position_m[1], target.pose.position_m[2]);
    // The pinch goes across the box's world y extent (a yawed box: its footprint's).
    const Mat3 rotation = rotationFromRpy(target.pose.rpy_rad);
    const Vec3 half(box->half_extents_m[0], box->half_extents_m[1], box->half_extents_m[2]);
    half_width_m_ = rotation.row(1).cwiseAbs().dot(half);
    half_length_m_ = rotation.row(0).cwiseAbs().dot(half);
    const double diameter = config.anthropometry.fingertip_diameter_m;
    // Tissue radii as hand_builder.cpp makes them: the thumb 1.15x, the proximal 1.08x.
    thumb_pad_radius_m_ = 0.5 * diameter * 1.15;
    index_side_radius_m_ = 0.5 * diameter * 1.08;
    thumb_pad_offset_m_ = kPadAlongDistal * phalanxLengths(config::Finger::kThumb,
                                                           config.anthropometry.hand_length_m)[2];
    open_ = closureForGap(kOpenGap);
    closed_ = closureForGap(-kSqueeze);
    eased_ = closureForGap(-kSetDownSqueeze);
}

std::array<double, kHandPoseAngles> GraspLiftPlacePushScript::posture(double closure) const {
    std::array<double, kHandPoseAngles> flexion{};  // middle, ring, little straight
    for (std::size_t s = 0; s < 3; ++s) {
        flexion[s] = closure * kThumbPerClosure[s];
        flexion[3 + s] = kIndexHook[s];
    }
    return flexion;
}

Vec3 GraspLiftPlacePushScript::boxInWrist(double closure, double* thumb_surface_y) const {
    HandPoseInput input;
    input.flexion_rad = posture(closure);
    std::vector<BonePose> poses;
    hand_.referencePoses(input, poses);
    const BonePose& thumb =
        poses[static_cast<std::size_t>(hand_.referenceDistal(config::Finger::kThumb))];
    const BonePose& index_proximal =
        poses[static_cast<std::size_t>(hand_.referencePhalanx(config::Finger::kIndex, 0))];
    const Mat3 roll = wristRoll();
    const Vec3 pad =
        roll * (thumb.position_m + thumb.rotation * Vec3(thumb_pad_offset_m_, 0.0, 0.0));
    const Vec3 pad_normal = -(roll * thumb.rotation * Vec3::UnitZ());
    if (thumb_surface_y != nullptr) {
        *thumb_surface_y = (pad + thumb_pad_radius_m_ * pad_normal).y();
    }
    const Vec3 index_start = roll * index_proximal.position_m;
    const double index_face_y = index_start.y() - index_side_radius_m_;
    // The index touches the face from its knuckle to the box's front edge, the thumb at one
    // point: the box centre goes where the line between the pad and the middle of the index
    // contact crosses the box's mid-plane, so that the box hangs under the pinch axis rather
    // than pitching about it.
    const double x = (2.0 * pad.x() + index_start.x() + half_length_m_) / 3.0;
    return {x, index_face_y - half_width_m_, pad.z()};
}

double GraspLiftPlacePushScript::closureForGap(double gap_m) const {
    // Gap between the thumb pad and the box's -y face with the +y face on the index's side.
    // The pad moves towards +y as the thumb closes (closure 0 = straight thumb), so bisect.
    const auto gap = [&](double c) {
        double surface_y = 0.0;
        const Vec3 box = boxInWrist(c, &surface_y);
        return (box.y() - half_width_m_) - surface_y;
    };
    double lo = 0.0;
    double hi = 1.2;
    if (gap(lo) < gap_m || gap(hi) > gap_m) {
        throw std::invalid_argument("grasp_lift_place_push: the box (" +
                                    std::to_string(2.0 * half_width_m_) +
                                    " m across y) does not fit between thumb and index");
    }
    for (int i = 0; i < 40; ++i) {
        const double mid = 0.5 * (lo + hi);
        (gap(mid) > gap_m ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

double GraspLiftPlacePushScript::closure(double t_s) const {
    const double t = scriptTime(t_s, loop_, kPeriod);
    // The grip eases over the end of the set-down and tightens again before the push: pressed
    // onto the table with the full squeeze, the box pitches about the pinch axis and climbs
    // in the grip instead of settling flat.
    return open_ + (closed_ - open_) * (ramp(t, 0.0, kCloseEnd) - ramp(t, kPushEnd, kOpenEnd)) +
           (eased_ - closed_) *
               (ramp(t, kPlaceEnd - 0.4, kPlaceEnd) - ramp(t, kPlaceEnd, kPushStart));
}

Vec3 GraspLiftPlacePushScript::boxTarget(double t_s) const {
    const double t = scriptTime(t_s, loop_, kPeriod);
    const double up =
        kLiftHeight * (ramp(t, kLiftStart, kLiftEnd) - ramp(t, kPlaceStart, kPlaceEnd));
    const double withdraw = kLiftHeight * ramp(t, kOpenEnd, kPeriod);
    return start_ + Vec3(kPushDistance * ramp(t, kPushStart, kPushEnd), 0.0, up + withdraw);
}

HandPoseInput GraspLiftPlacePushScript::at(double t_s) const {
    // Palm down, fingers along +x, the pinch across y (rolled by kWristRollRad): the wrist
    // carries the pinched box's centre along boxTarget.
    HandPoseInput input;
    const double c = closure(t_s);
    input.flexion_rad = posture(c);
    input.wrist.rotation = wristRoll();
    // The wrist stays where the closed pinch holds the box: only the thumb moves while it
    // closes. Placing it for the current closure instead moved the index (already on the box)
    // 8 mm up and back along the face during the close, and friction rolled and lifted the box.
    input.wrist.position_m = boxTarget(t_s) - boxInWrist(closed_, nullptr);
    return input;
}

}  // namespace haptic::softhand
