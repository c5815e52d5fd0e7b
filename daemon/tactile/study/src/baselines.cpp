#include "haptic/tactile/baselines.hpp"

#include <cmath>
#include <limits>

namespace haptic::tactile {

namespace {

Eigen::Vector3d toVector(const std::array<double, 3>& v) {
    return {v[0], v[1], v[2]};
}

}  // namespace

std::optional<PlatformDofs> geometricPlaneFit(const ThimbleKinematics& kinematics,
                                              const msgs::ContactSurface& surface) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    Eigen::Vector3d outward = Eigen::Vector3d::Zero();
    double weight = 0.0;
    for (const msgs::ContactSample& s : surface.samples) {
        if (s.signed_distance_m < 0.0 && s.weight > 0.0) {
            const Eigen::Vector3d n = toVector(s.normal_device);
            centroid += s.weight * (toVector(s.p_device_m) - s.signed_distance_m * n);
            outward += s.weight * n;
            weight += s.weight;
        }
    }
    if (!(weight > 0.0) || outward.norm() < 1e-12) {
        return std::nullopt;
    }
    // The object's outward normal is the direction the plate must push the finger.
    return kinematics.projectToWorkspace(poseForPlane(kinematics, outward, centroid / weight));
}

std::optional<PlatformDofs> forceNormalDisplacement(const ThimbleKinematics& kinematics,
                                                    const msgs::ContactSurface& surface,
                                                    const Eigen::Vector3d& force_on_finger_n,
                                                    double finger_stiffness_n_per_m) {
    const double force = force_on_finger_n.norm();
    if (!(force > 0.0) || !(finger_stiffness_n_per_m > 0.0) || surface.samples.empty()) {
        return std::nullopt;
    }
    const Eigen::Vector3d normal = force_on_finger_n / force;
    double touch = std::numeric_limits<double>::infinity();
    Eigen::Vector3d touch_point = Eigen::Vector3d::Zero();
    for (const msgs::ContactSample& s : surface.samples) {
        const Eigen::Vector3d p = toVector(s.p_device_m);
        if (normal.dot(p) < touch) {
            touch = normal.dot(p);
            touch_point = p;
        }
    }
    const double press_m = force / finger_stiffness_n_per_m;
    return kinematics.projectToWorkspace(
        poseForPlane(kinematics, normal, touch_point + press_m * normal));
}

}  // namespace haptic::tactile
