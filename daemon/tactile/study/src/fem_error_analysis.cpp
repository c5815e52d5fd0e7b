#include "haptic/tactile/fem_error_analysis.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "haptic/softhand/device_outputs.hpp"
#include "haptic/tactile/baselines.hpp"

namespace haptic::tactile {

namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

constexpr double kRelaxDtS = 0.005;
constexpr double kAtRestM = 1e-9;  // no node moves more than this in a step: at rest
constexpr double kPlateHalfThicknessM = 0.005;
// The bone held where it was built: stiff enough that a few newtons move it by micrometres.
constexpr double kHoldLinearNPerM = 1e7;
constexpr double kHoldAngularNmPerRad = 1e4;

// Rotation whose z axis (a half-space's outward normal, a box's face) points along `normal`.
Matrix3d facing(const Vector3d& normal) {
    return Eigen::Quaterniond::FromTwoVectors(Vector3d::UnitZ(), normal.normalized())
        .toRotationMatrix();
}

// Outward normal of an object below the pad in D (towards -z, the nail), tilted by `angle`
// about `axis`.
Matrix3d tiltedFacingFinger(double angle_rad, const Vector3d& axis) {
    return facing(Eigen::AngleAxisd(angle_rad, axis) * -Vector3d::UnitZ());
}

FemMethodResult compare(const FemContact& reference, const FemPress& device) {
    FemMethodResult r;
    r.valid = true;
    r.device = device.contact;
    const double fv = reference.force_on_finger_n.norm();
    r.force_error = (device.contact.force_on_finger_n - reference.force_on_finger_n).norm() / fv;
    r.magnitude_error = (device.contact.force_on_finger_n.norm() - fv) / fv;
    r.moment_error_mm = 1e3 * (device.contact.moment_nm - reference.moment_nm).norm() / fv;
    return r;
}

}  // namespace

FemFingertip::FemFingertip(const config::ThimbleConfig& thimble, int resolution, int samples)
    : finger_from_device_(thimble.finger_calibration.T_finger_device),
      resolution_(resolution),
      samples_(samples) {
    hand_.model = config::HandModel::kFingertip;
    hand_.finger = config::Finger::kIndex;
    hand_.resolution = resolution;
    hand_.anthropometry = {0.19, 0.085, 0.016};  // the shipped scenes' hand
    solver_.gravity_m_per_s2 = Vector3d::Zero();
    // A converged quasi-static press, not handsim's real-time budget: the reference must not
    // carry the solver's truncation.
    solver_.pcg_max_iterations = 5000;
    solver_.pcg_relative_tolerance = 1e-8;
    solver_.max_newton_iterations = 10;
    const softhand::HandModel model = build();
    const softhand::TactileOutput output(model, config::Finger::kIndex, finger_from_device_,
                                         softhand::HandBuildOptions{}.tissue);
    const int bone = model.bones.front().body;
    const softhand::BonePose device = output.deviceFrame(
        {model.simulation.bodyPosition(bone), model.simulation.bodyRotation(bone)});
    double lowest = -std::numeric_limits<double>::infinity();
    for (int node : model.simulation.skinNodes()) {
        const Vector3d p =
            device.rotation.transpose() * (model.simulation.nodePosition(node) - device.position_m);
        pad_rest_d_.push_back(p);
        lowest = std::max(lowest, p.z());
    }
    // Under D's origin, where the plate is centred; the pad is a cylinder along x there, so
    // its lowest points form a line and the first one found would sit at either end.
    pad_point_d_ = Vector3d(0.0, 0.0, lowest);
}

softhand::HandModel FemFingertip::build() const {
    softhand::HandModel model = softhand::buildHand(hand_, solver_);
    const int bone = model.bones.front().body;
    model.simulation.setTrackingStiffness(bone, kHoldLinearNPerM, kHoldAngularNmPerRad);
    model.simulation.setTrackingTarget(bone, model.simulation.bodyPosition(bone),
                                       model.simulation.bodyRotation(bone));
    return model;
}

Vector3d FemFingertip::placement(const FemCase& c, double indentation_m) const {
    // The deepest undeformed skin node inside the object, with the object at height z.
    const auto depth = [&](double z) {
        const Vector3d position(c.across_m.x(), c.across_m.y(), z);
        double phi = std::numeric_limits<double>::infinity();
        for (const Vector3d& p : pad_rest_d_) {
            phi = std::min(
                phi,
                softhand::querySurface(c.shape, c.rotation.transpose() * (p - position)).phi_m);
        }
        return -phi;
    };
    // The object lies beyond the pad (+z in D) and comes towards the nail as z falls: walk
    // in from clear of the pad (a bounded shape is not monotone past the finger), then bisect.
    double clear = pad_point_d_.z() + 0.1;
    double inside = clear;
    while (depth(inside) < indentation_m) {
        clear = inside;
        inside -= 2e-4;
        if (inside < pad_point_d_.z() - 0.05) {
            throw std::invalid_argument("FEM error analysis: case '" + c.name +
                                        "' cannot be placed at the indentation asked for");
        }
    }
    for (int i = 0; i < 60; ++i) {
        const double mid = 0.5 * (clear + inside);
        (depth(mid) < indentation_m ? clear : inside) = mid;
    }
    return {c.across_m.x(), c.across_m.y(), 0.5 * (clear + inside)};
}

FemPress FemFingertip::press(const softhand::ColliderShape& shape, const Vector3d& position_d,
                             const Matrix3d& rotation_d) const {
    softhand::HandModel model = build();
    softhand::Simulation& sim = model.simulation;
    softhand::TactileOutputSettings settings;
    settings.max_samples = samples_;
    const softhand::TactileOutput output(model, config::Finger::kIndex, finger_from_device_,
                                         softhand::HandBuildOptions{}.tissue, settings);
    const int bone = model.bones.front().body;
    const softhand::BonePose bone_pose{sim.bodyPosition(bone), sim.bodyRotation(bone)};
    const softhand::BonePose device = output.deviceFrame(bone_pose);
    sim.addCollider({shape, device.position_m + device.rotation * position_d,
                     device.rotation * rotation_d, 0.5});
    FemPress result;
    result.relax_steps = sim.relax(kRelaxDtS, kMaxRelaxSteps, kAtRestM);
    const Vector3d pad_point = device.position_m + device.rotation * pad_point_d_;
    Vector3d force = Vector3d::Zero();
    Vector3d moment = Vector3d::Zero();
    for (const softhand::Simulation::ContactForce& contact : sim.contactForces()) {
        force += contact.force_n;
        moment += (sim.nodePosition(contact.node) - pad_point).cross(contact.force_n);
        result.contact.nodes_in_contact += contact.force_n.norm() > 1e-6 ? 1 : 0;
    }
    result.contact.force_on_finger_n = device.rotation.transpose() * force;
    result.contact.moment_nm = device.rotation.transpose() * moment;
    // The bone is held where it was built: handsim's tracked and simulated bone coincide.
    output.fill(sim, bone_pose, result.surface);
    return result;
}

FemPress FemFingertip::pressPlate(const PlatformPose& pose, double plate_radius_m) const {
    const Vector3d into_finger = pose.plateNormal();
    // The box's face towards the finger is the plate; its z axis is the plate's -normal.
    return press(softhand::Box{Vector3d(plate_radius_m, plate_radius_m, kPlateHalfThicknessM)},
                 pose.position_m - kPlateHalfThicknessM * into_finger, pose.rotation);
}

std::vector<FemCase> femStandardCases(double indentation_m) {
    constexpr double kDeg = std::numbers::pi / 180.0;
    std::vector<FemCase> cases;
    const auto plane = [&](const std::string& name, double angle_deg, const Vector3d& axis) {
        cases.push_back({name, softhand::HalfSpace{}, tiltedFacingFinger(angle_deg * kDeg, axis),
                         Eigen::Vector2d::Zero(), indentation_m});
    };
    // Tilted across the finger (about its axis, x): the pad's cross-section is round, so the
    // contact stays under the plate. Tilted along it, a plane meets the pad's cylinder at one
    // end first, out of the plate's reach (the 5-degree case shows it).
    for (const int angle : {0, 10, 20, 30}) {
        plane("plane " + std::to_string(angle) + " deg across", angle, Vector3d::UnitX());
    }
    plane("plane 5 deg along", 5.0, Vector3d::UnitY());
    for (const int radius_mm : {5, 10, 20}) {
        cases.push_back({"sphere r=" + std::to_string(radius_mm) + " mm",
                         softhand::Sphere{radius_mm * 1e-3}, Matrix3d::Identity(),
                         Eigen::Vector2d::Zero(), indentation_m});
    }
    cases.push_back({"sphere r=10 mm off-centre", softhand::Sphere{0.010}, Matrix3d::Identity(),
                     Eigen::Vector2d(0.004, 0.003), indentation_m});
    // A block's 90-degree edge across the finger (along y), pointing at the pad.
    cases.push_back({"edge 90 deg across", softhand::Box{Vector3d(0.02, 0.02, 0.02)},
                     Matrix3d(Eigen::AngleAxisd(0.25 * std::numbers::pi, Vector3d::UnitY())),
                     Eigen::Vector2d::Zero(), indentation_m});
    return cases;
}

double femSecantStiffness(const FemFingertip& finger, double indentation_m, double plate_radius_m) {
    PlatformPose flat;
    flat.position_m = finger.padPoint() - Vector3d(0.0, 0.0, indentation_m);
    const FemPress press = finger.pressPlate(flat, plate_radius_m);
    return press.contact.force_on_finger_n.norm() / indentation_m;
}

std::vector<FemCaseResult> runFemErrorAnalysis(const ThimbleKinematics& kinematics,
                                               const OptimiserSettings& settings,
                                               const FemFingertip& finger,
                                               const std::vector<FemCase>& cases,
                                               double finger_stiffness_n_per_m) {
    ContactSurfaceOptimiser optimiser(kinematics, settings);
    const double plate_radius = kinematics.config().plate_radius_m;
    std::vector<FemCaseResult> results;
    for (const FemCase& c : cases) {
        FemCaseResult r;
        r.name = c.name;
        const FemPress reference =
            finger.press(c.shape, finger.placement(c, c.indentation_m), c.rotation);
        r.reference = reference.contact;
        if (!(reference.contact.force_on_finger_n.norm() > 0.0)) {
            throw std::runtime_error("FEM error analysis: case '" + c.name + "' presses nothing");
        }
        const auto evaluate = [&](const std::optional<PlatformDofs>& dofs) {
            if (!dofs) {
                return FemMethodResult{};
            }
            const InverseResult ik = kinematics.inverse(*dofs);
            if (!ik.ok()) {
                return FemMethodResult{};
            }
            // The plate where the servos put it: forward kinematics of the commanded angles.
            const ForwardResult fk = kinematics.forward(ik.servo_rad, *dofs);
            if (!fk.ok()) {
                return FemMethodResult{};
            }
            return compare(reference.contact, finger.pressPlate(fk.pose, plate_radius));
        };
        optimiser.reset();
        const TactileCommand cold = optimiser.solve(reference.surface);
        r.cold_report = cold.report;
        r.cold = evaluate(cold.dofs);
        // Warm: the same press a moment earlier, at two thirds of the depth, solved first.
        const FemPress earlier =
            finger.press(c.shape, finger.placement(c, c.indentation_m * 2.0 / 3.0), c.rotation);
        optimiser.reset();
        (void)optimiser.solve(earlier.surface);
        const TactileCommand warm = optimiser.solve(reference.surface);
        r.warm_report = warm.report;
        r.warm = evaluate(warm.dofs);
        // The plane fit is defined on area weights (centroid and average normal); the pad's
        // samples share its area evenly.
        msgs::ContactSurface area_weighted = reference.surface;
        for (msgs::ContactSample& sample : area_weighted.samples) {
            sample.weight = 1.0;
        }
        r.plane_fit = evaluate(geometricPlaneFit(kinematics, area_weighted));
        r.force_normal = evaluate(forceNormalDisplacement(kinematics, reference.surface,
                                                          reference.contact.force_on_finger_n,
                                                          finger_stiffness_n_per_m));
        results.push_back(std::move(r));
    }
    return results;
}

}  // namespace haptic::tactile
