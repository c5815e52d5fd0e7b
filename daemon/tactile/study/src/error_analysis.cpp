#include "haptic/tactile/error_analysis.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "haptic/tactile/baselines.hpp"

namespace haptic::tactile {

namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;

// Outward normal tilted by angle_rad about the y axis away from -z (towards +x).
Eigen::Vector3d tiltedOutward(double angle_rad) {
    return {-std::sin(angle_rad), 0.0, -std::cos(angle_rad)};
}

}  // namespace

ForceComparison compareWithVirtualContact(const ThimbleKinematics& kinematics,
                                          const FingertipContactModel& finger,
                                          const PadContact& virtual_contact,
                                          const std::optional<PlatformDofs>& dofs) {
    ForceComparison m;
    if (!dofs) {
        return m;
    }
    const auto ik = kinematics.inverse(*dofs);
    if (!ik.ok()) {
        return m;
    }
    // The plate where the servos put it: forward kinematics of the commanded angles.
    const auto fk = kinematics.forward(ik.servo_rad, *dofs);
    if (!fk.ok()) {
        return m;
    }
    const auto device = finger.press(PlateObstacle(fk.pose, kinematics.config().plate_radius_m));
    const Eigen::Vector3d& fv = virtual_contact.force_on_finger_n;
    const Eigen::Vector3d& fd = device.force_on_finger_n;
    m.valid = true;
    m.force_error = (fd - fv).norm() / fv.norm();
    m.magnitude_error = (fd.norm() - fv.norm()) / fv.norm();
    m.direction_error_deg =
        fd.norm() > 0.0
            ? std::acos(std::clamp(fd.normalized().dot(fv.normalized()), -1.0, 1.0)) * kDegPerRad
            : 180.0;
    int both = 0;
    int either = 0;
    for (std::size_t i = 0; i < device.node_in_contact.size(); ++i) {
        both += device.node_in_contact[i] && virtual_contact.node_in_contact[i];
        either += device.node_in_contact[i] || virtual_contact.node_in_contact[i];
    }
    m.jaccard = either > 0 ? static_cast<double>(both) / either : 0.0;
    return m;
}

std::vector<AnalysisCase> standardCases(const PadModelParameters& p, double indentation_m) {
    const Eigen::Vector3d pad_centre(0.0, 0.0, p.contact_height_m - p.pad_radius_m);
    std::vector<AnalysisCase> cases;
    auto plane = [&](double angle_deg, double depth_m, const std::string& name) {
        const Eigen::Vector3d n = tiltedOutward(angle_deg / kDegPerRad);
        // Touches the pad sphere at pad_centre - R n, then moves depth_m into the finger.
        const Eigen::Vector3d point = pad_centre - (p.pad_radius_m - depth_m) * n;
        cases.push_back({name, std::make_unique<HalfSpaceObstacle>(point, n)});
    };
    auto sphere = [&](double radius_m, double angle_deg, const std::string& name) {
        const Eigen::Vector3d n = tiltedOutward(angle_deg / kDegPerRad);
        cases.push_back(
            {name, std::make_unique<SphereObstacle>(
                       pad_centre - (p.pad_radius_m + radius_m - indentation_m) * n, radius_m)});
    };
    for (const int angle : {0, 10, 20, 30}) {
        plane(angle, indentation_m, "plane " + std::to_string(angle) + " deg");
    }
    for (const int radius_mm : {5, 10, 20}) {
        sphere(radius_mm * 1e-3, 0.0, "sphere r=" + std::to_string(radius_mm) + " mm");
    }
    sphere(0.010, 20.0, "sphere r=10 mm, 20 deg");
    // Ridge along y, faces at +-45 degrees from the pad normal.
    const double s = std::sqrt(0.5);
    cases.push_back(
        {"edge 90 deg", std::make_unique<RightAngleEdgeObstacle>(
                            Eigen::Vector3d(0.0, 0.0, p.contact_height_m - indentation_m),
                            Eigen::Vector3d(s, 0.0, -s), Eigen::Vector3d(-s, 0.0, -s))});
    plane(45.0, indentation_m, "plane 45 deg (> max tilt)");
    plane(0.0, 0.006, "plane 6 mm deep (> max indent)");
    return cases;
}

std::vector<CaseResult> runErrorAnalysis(const ThimbleKinematics& kinematics,
                                         const FingertipContactModel& finger,
                                         ContactSurfaceOptimiser& optimiser,
                                         const std::vector<AnalysisCase>& cases,
                                         const AnalysisSettings& settings) {
    std::vector<CaseResult> results;
    for (const AnalysisCase& c : cases) {
        CaseResult r;
        r.name = c.name;
        const PadContact reference = finger.press(*c.object);
        r.virtual_force_n = reference.force_on_finger_n.norm();
        const auto surface = finger.contactSurface(*c.object, settings.samples, settings.weighting);
        optimiser.reset();
        const TactileCommand command = optimiser.solve(surface);
        r.optimiser_report = command.report;
        r.optimiser = compareWithVirtualContact(kinematics, finger, reference, command.dofs);
        const auto area_surface =
            finger.contactSurface(*c.object, settings.samples, SampleWeighting::kArea);
        r.geometric = compareWithVirtualContact(kinematics, finger, reference,
                                                geometricPlaneFit(kinematics, area_surface));
        r.force_normal = compareWithVirtualContact(
            kinematics, finger, reference,
            forceNormalDisplacement(kinematics, surface, reference.force_on_finger_n,
                                    settings.finger_stiffness_n_per_m));
        results.push_back(std::move(r));
    }
    return results;
}

}  // namespace haptic::tactile
