#include "haptic/softhand/tracking_input.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <stdexcept>

namespace haptic::softhand {

namespace {

constexpr std::array<config::Finger, 5> kFingers{config::Finger::kThumb, config::Finger::kIndex,
                                                 config::Finger::kMiddle, config::Finger::kRing,
                                                 config::Finger::kLittle};

HandKinematics referenceKinematics(const HandModel& model, const config::HandConfig& hand) {
    if (hand.model != config::HandModel::kFingertip) {
        return HandKinematics(model);
    }
    config::HandConfig finger = hand;
    finger.model = config::HandModel::kFinger;
    finger.resolution = 1;
    return HandKinematics(buildHand(finger, SolverSettings{}));
}

}  // namespace

std::optional<std::string> fromMessage(const msgs::HandPose& message, HandPoseInput& out) {
    for (double value : message.wrist_position_m) {
        if (!std::isfinite(value)) {
            return "wrist_position_m is not finite";
        }
    }
    Eigen::Quaterniond q(message.wrist_orientation_wxyz[0], message.wrist_orientation_wxyz[1],
                         message.wrist_orientation_wxyz[2], message.wrist_orientation_wxyz[3]);
    if (!q.coeffs().allFinite()) {
        return "wrist_orientation_wxyz is not finite";
    }
    if (std::abs(q.norm() - 1.0) > 1e-3) {
        return "wrist_orientation_wxyz is not a unit quaternion (norm " + std::to_string(q.norm()) +
               ")";
    }
    if (message.joint_angles_rad.size() != kHandPoseAngles) {
        return "joint_angles_rad has " + std::to_string(message.joint_angles_rad.size()) +
               " entries, expected 15 (5 fingers x MCP, PIP, DIP)";
    }
    for (std::size_t i = 0; i < kHandPoseAngles; ++i) {
        if (!std::isfinite(message.joint_angles_rad[i])) {
            return "joint_angles_rad[" + std::to_string(i) + "] is not finite";
        }
    }
    out.wrist.position_m =
        Vec3(message.wrist_position_m[0], message.wrist_position_m[1], message.wrist_position_m[2]);
    out.wrist.rotation = q.normalized().toRotationMatrix();
    for (std::size_t i = 0; i < kHandPoseAngles; ++i) {
        out.flexion_rad[i] = message.joint_angles_rad[i];
    }
    return std::nullopt;
}

msgs::HandPose toMessage(const HandPoseInput& pose) {
    msgs::HandPose message;
    const Vec3& p = pose.wrist.position_m;
    message.wrist_position_m = {p.x(), p.y(), p.z()};
    const Eigen::Quaterniond q(pose.wrist.rotation);
    message.wrist_orientation_wxyz = {q.w(), q.x(), q.y(), q.z()};
    for (double angle : pose.flexion_rad) {
        message.joint_angles_rad.push_back(angle);
    }
    return message;
}

TrackedHand::TrackedHand(const HandModel& model, const config::HandConfig& hand)
    : reference_kinematics_(referenceKinematics(model, hand)),
      fingertip_(hand.model == config::HandModel::kFingertip) {
    angle_of_joint_.assign(static_cast<std::size_t>(reference_kinematics_.jointCount()), -1);
    for (std::size_t f = 0; f < kFingers.size(); ++f) {
        const auto chain = reference_kinematics_.chain(kFingers[f]);
        if (!chain) {
            continue;
        }
        for (std::size_t s = 0; s < 3; ++s) {
            angle_of_joint_[static_cast<std::size_t>(chain->joints[s])] =
                static_cast<int>(3 * f + s);
        }
    }
    for (int index : angle_of_joint_) {
        if (index < 0) {
            throw std::logic_error("TrackedHand: a joint that belongs to no finger chain");
        }
    }
    if (fingertip_) {
        // Both distal bones have the same local frame (centre, x along the phalanx, y the
        // flexion axis), so the fingertip simply takes the reference distal's pose.
        reference_distal_ = referenceDistal(hand.finger.value_or(config::Finger::kIndex));
    }
}

int TrackedHand::referencePhalanx(config::Finger finger, int phalanx) const {
    const auto chain = reference_kinematics_.chain(finger);
    if (!chain) {
        throw std::invalid_argument("TrackedHand: the model does not simulate the " +
                                    std::string(config::toString(finger)) + " finger");
    }
    return chain->bones.at(static_cast<std::size_t>(phalanx));
}

void TrackedHand::referencePoses(const HandPoseInput& input, std::vector<BonePose>& poses) const {
    std::array<double, 16> flexion{};
    for (std::size_t j = 0; j < angle_of_joint_.size(); ++j) {
        flexion[j] = input.flexion_rad[static_cast<std::size_t>(angle_of_joint_[j])];
    }
    reference_kinematics_.forward(input.wrist, std::span(flexion.data(), angle_of_joint_.size()),
                                  poses);
}

void TrackedHand::bonePoses(const HandPoseInput& input, std::vector<BonePose>& poses) const {
    referencePoses(input, poses);
    if (fingertip_) {
        const BonePose tip = poses[static_cast<std::size_t>(reference_distal_)];
        poses.assign(1, tip);
    }
}

HandPoseInput TrackedHand::buildPose() const {
    HandPoseInput input;
    input.wrist = reference_kinematics_.buildPose(0);
    return input;
}

// ---- replay ---------------------------------------------------------------------------

ReplayTrack ReplayTrack::parse(std::string_view text, const std::string& source_name) {
    ReplayTrack track;
    constexpr std::size_t kColumns = 8 + kHandPoseAngles;
    std::size_t line_number = 0;
    std::size_t start = 0;
    while (start <= text.size()) {
        const std::size_t end = std::min(text.find('\n', start), text.size());
        std::string line(text.substr(start, end - start));
        start = end + 1;
        ++line_number;
        const auto where = [&](const std::string& reason) {
            return std::runtime_error(source_name + ":" + std::to_string(line_number) + ": " +
                                      reason);
        };
        if (const auto hash = line.find('#'); hash != std::string::npos) {
            line.resize(hash);
        }
        if (line.find_first_not_of(" \t\r") == std::string::npos) {
            if (end == text.size()) {
                break;
            }
            continue;
        }
        std::vector<double> values;
        std::size_t field_start = 0;
        while (field_start <= line.size()) {
            const std::size_t comma = std::min(line.find(',', field_start), line.size());
            const std::string field = line.substr(field_start, comma - field_start);
            field_start = comma + 1;
            const std::size_t first = field.find_first_not_of(" \t\r");
            const std::size_t last = field.find_last_not_of(" \t\r");
            const std::string trimmed =
                first == std::string::npos ? "" : field.substr(first, last - first + 1);
            double value = 0.0;
            std::size_t used = 0;
            try {
                value = std::stod(trimmed, &used);
            } catch (const std::exception&) {
                used = 0;
            }
            if (trimmed.empty() || used != trimmed.size()) {
                throw where("column " + std::to_string(values.size() + 1) + ": '" + trimmed +
                            "' is not a number");
            }
            if (!std::isfinite(value)) {
                throw where("column " + std::to_string(values.size() + 1) + " is not finite");
            }
            values.push_back(value);
            if (comma == line.size()) {
                break;
            }
        }
        if (values.size() != kColumns) {
            throw where("expected " + std::to_string(kColumns) +
                        " columns (t_s, wrist xyz, qw qx qy qz, 15 joint angles), got " +
                        std::to_string(values.size()));
        }
        ReplayFrame frame;
        frame.t_s = values[0];
        if (!track.frames_.empty() && !(frame.t_s > track.frames_.back().t_s)) {
            throw where("t_s " + std::to_string(frame.t_s) + " does not increase");
        }
        frame.pose.wrist.position_m = Vec3(values[1], values[2], values[3]);
        Eigen::Quaterniond q(values[4], values[5], values[6], values[7]);
        if (std::abs(q.norm() - 1.0) > 1e-3) {
            throw where("wrist quaternion is not unit (norm " + std::to_string(q.norm()) + ")");
        }
        frame.pose.wrist.rotation = q.normalized().toRotationMatrix();
        for (std::size_t i = 0; i < kHandPoseAngles; ++i) {
            frame.pose.flexion_rad[i] = values[8 + i];
        }
        track.frames_.push_back(frame);
        if (end == text.size()) {
            break;
        }
    }
    if (track.frames_.empty()) {
        throw std::runtime_error(source_name + ": no frames");
    }
    return track;
}

HandPoseInput ReplayTrack::at(double t_s, bool loop) const {
    const double first = frames_.front().t_s;
    const double duration = frames_.back().t_s - first;
    double t = t_s + first;
    if (loop && duration > 0.0) {
        t = first + std::fmod(std::max(t_s, 0.0), duration);
    }
    if (t <= first || frames_.size() == 1) {
        return frames_.front().pose;
    }
    if (t >= frames_.back().t_s) {
        return frames_.back().pose;
    }
    std::size_t k = 1;
    while (frames_[k].t_s < t) {
        ++k;
    }
    const ReplayFrame& a = frames_[k - 1];
    const ReplayFrame& b = frames_[k];
    const double s = (t - a.t_s) / (b.t_s - a.t_s);
    HandPoseInput out;
    out.wrist.position_m = (1.0 - s) * a.pose.wrist.position_m + s * b.pose.wrist.position_m;
    out.wrist.rotation = Eigen::Quaterniond(a.pose.wrist.rotation)
                             .slerp(s, Eigen::Quaterniond(b.pose.wrist.rotation))
                             .toRotationMatrix();
    for (std::size_t i = 0; i < kHandPoseAngles; ++i) {
        out.flexion_rad[i] = (1.0 - s) * a.pose.flexion_rad[i] + s * b.pose.flexion_rad[i];
    }
    return out;
}

}  // namespace haptic::softhand
