#pragma once
// Constraint rows as handsim sends them (msgs::LinearConstraint with its contact), on the
// shipped exoskeleton's planar finger, for the kinesthetic tests.

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <cstdint>

#include "haptic/config/device.hpp"
#include "haptic/kinesthetic/contact_gap.hpp"
#include "haptic/kinesthetic/types.hpp"
#include "haptic/msgs/messages.hpp"

namespace haptic::testing {

using kinesthetic::ConfigVector;
using kinesthetic::contactGap;

// A point `along` (0..1) the length of phalanx `phalanx` (0 proximal .. 2 distal) of the
// device's planar finger at q, pressed `depth_m` into a plane whose normal (in the finger's
// plane) makes `normal_angle_rad` with the x axis: the row and its contact as handsim sends
// them (the row is the gap's linearisation at q).
inline msgs::LinearConstraint phalanxContact(const config::ExoskeletonConfig& exo,
                                             const ConfigVector& q, int phalanx, double along,
                                             double depth_m, double normal_angle_rad) {
    msgs::LinearConstraint row;
    msgs::ContactKinematics& c = row.contact;
    c.joints = static_cast<std::int16_t>(phalanx + 1);
    c.gap_m = -depth_m;
    c.normal = {std::cos(normal_angle_rad), std::sin(normal_angle_rad), 0.0};
    std::array<Eigen::Vector2d, 3> centres;
    Eigen::Vector2d joint = Eigen::Vector2d::Zero();
    Eigen::Vector2d point = Eigen::Vector2d::Zero();
    double phi = 0.0;
    for (int k = 0; k <= phalanx; ++k) {
        centres[static_cast<std::size_t>(k)] = joint;
        phi += q[k];
        const Eigen::Vector2d step = exo.finger.phalanx_lengths_m[static_cast<std::size_t>(k)] *
                                     Eigen::Vector2d(std::cos(phi), std::sin(phi));
        point = joint + along * step;
        joint += step;
    }
    for (int j = 0; j <= phalanx; ++j) {
        const auto slot = static_cast<std::size_t>(j);
        c.q_ref_rad[slot] = q[j];
        c.axis[slot] = {0.0, 0.0, 1.0};
        const Eigen::Vector2d lever = point - centres[slot];
        c.lever_m[slot] = {lever.x(), lever.y(), 0.0};
    }
    ConfigVector gradient;
    const double g = contactGap(c, q, &gradient);
    for (int i = 0; i < 3; ++i) {
        row.a[static_cast<std::size_t>(i)] = gradient[i];
    }
    row.b = gradient.dot(q) - g;
    return row;
}

// The fingertip (the end of the distal phalanx).
inline msgs::LinearConstraint fingertipContact(const config::ExoskeletonConfig& exo,
                                               const ConfigVector& q, double depth_m,
                                               double normal_angle_rad) {
    return phalanxContact(exo, q, 2, 1.0, depth_m, normal_angle_rad);
}

}  // namespace haptic::testing
