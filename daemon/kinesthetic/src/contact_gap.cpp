#include "haptic/kinesthetic/contact_gap.hpp"

#include <Eigen/Geometry>
#include <array>
#include <cmath>

namespace haptic::kinesthetic {

namespace {

Eigen::Vector3d vector(const std::array<double, 3>& v) noexcept {
    return {v[0], v[1], v[2]};
}

bool finite(const std::array<double, 3>& v) noexcept {
    return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
}

}  // namespace

bool usableContact(const msgs::ContactKinematics& contact, int dofs) noexcept {
    const int joints = contact.joints;
    if (joints < 1 || joints > static_cast<int>(msgs::kMaxContactJoints) || joints > dofs ||
        !std::isfinite(contact.gap_m) || !finite(contact.normal) ||
        !(vector(contact.normal).norm() > 0.0)) {
        return false;
    }
    for (int j = 0; j < joints; ++j) {
        const auto k = static_cast<std::size_t>(j);
        if (!std::isfinite(contact.q_ref_rad[k]) || !finite(contact.axis[k]) ||
            !finite(contact.lever_m[k]) || !(vector(contact.axis[k]).norm() > 0.0)) {
            return false;
        }
    }
    return true;
}

double contactGap(const msgs::ContactKinematics& contact, const ConfigVector& q,
                  ConfigVector* gradient) noexcept {
    // Frames relative to the contact point at q_ref (p = 0). Forward over the joints, the
    // rigid motion T = (R, t) of the joints so far; each joint's axis and anchor as T has
    // moved them, for the gradient.
    Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
    Eigen::Vector3d t = Eigen::Vector3d::Zero();
    std::array<Eigen::Vector3d, msgs::kMaxContactJoints> axis_now;
    std::array<Eigen::Vector3d, msgs::kMaxContactJoints> anchor_now;
    const int joints = contact.joints;
    for (int j = 0; j < joints; ++j) {
        const auto k = static_cast<std::size_t>(j);
        const Eigen::Vector3d u = vector(contact.axis[k]).normalized();
        const Eigen::Vector3d anchor = -vector(contact.lever_m[k]);
        axis_now[k] = R * u;
        anchor_now[k] = R * anchor + t;
        const Eigen::Matrix3d R_j =
            Eigen::AngleAxisd(q[j] - contact.q_ref_rad[k], u).toRotationMatrix();
        // T o Rot_j: y -> R (anchor + R_j (y - anchor)) + t
        t += R * (anchor - R_j * anchor);
        R = R * R_j;
    }
    const Eigen::Vector3d x = t;  // where the point is at q
    const Eigen::Vector3d normal = vector(contact.normal).normalized();
    if (gradient != nullptr) {
        gradient->setZero(q.size());
        for (int j = 0; j < joints; ++j) {
            const auto k = static_cast<std::size_t>(j);
            (*gradient)[j] = normal.dot(axis_now[k].cross(x - anchor_now[k]));
        }
    }
    return normal.dot(x) + contact.gap_m;
}

}  // namespace haptic::kinesthetic
