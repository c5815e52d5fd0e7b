// subspace on the contact itself (msgs::ContactKinematics): the exoskeleton's fingertip
// pressing a plane, with the contact's chain built from the device's own planar kinematics
// (joint axes along z through the joint centres). Checked against a brute-force bisection of
// g(chi(q + B alpha / k_a)) along the actuated direction, against linearized_subspace (its
// linearisation at q: equal to first order, apart at depth), and at the actuator's stroke.

#include <gtest/gtest.h>

#include <cmath>

#include "haptic/config/device.hpp"
#include "haptic/kinesthetic/contact_gap.hpp"
#include "haptic/kinesthetic/device_model.hpp"
#include "haptic/kinesthetic/renderer.hpp"

namespace haptic::kinesthetic {
namespace {

config::ExoskeletonConfig shippedExoskeleton() {
    return config::loadDeviceConfig(std::string(HAPTIC_CONFIG_DIR) + "/devices/exoskeleton.yaml")
        .exoskeleton();
}

constexpr double kTrackingStiffness = 2.0;  // k_a, the shipped value (N m/rad)

// The fingertip of the device's planar finger at q pressed `depth_m` into a plane whose
// normal (in the finger's plane) makes `normal_angle_rad` with the x axis.
msgs::LinearConstraint fingertipContact(const config::ExoskeletonConfig& exo, const ConfigVector& q,
                                        double depth_m, double normal_angle_rad) {
    msgs::LinearConstraint row;
    msgs::ContactKinematics& c = row.contact;
    c.joints = 3;
    c.gap_m = -depth_m;
    c.normal = {std::cos(normal_angle_rad), std::sin(normal_angle_rad), 0.0};
    // Joint centres along the chain; the tip at the end.
    Eigen::Vector2d joint = Eigen::Vector2d::Zero();
    std::array<Eigen::Vector2d, 3> centres;
    double phi = 0.0;
    for (int k = 0; k < 3; ++k) {
        centres[static_cast<std::size_t>(k)] = joint;
        phi += q[k];
        joint += exo.finger.phalanx_lengths_m[static_cast<std::size_t>(k)] *
                 Eigen::Vector2d(std::cos(phi), std::sin(phi));
    }
    for (std::size_t j = 0; j < 3; ++j) {
        c.q_ref_rad[j] = q[static_cast<Eigen::Index>(j)];
        c.axis[j] = {0.0, 0.0, 1.0};
        const Eigen::Vector2d lever = joint - centres[j];
        c.lever_m[j] = {lever.x(), lever.y(), 0.0};
    }
    // The sim's row: g's linearisation at q_ref.
    ConfigVector gradient;
    const double g = contactGap(c, q, &gradient);
    for (int i = 0; i < 3; ++i) {
        row.a[static_cast<std::size_t>(i)] = gradient[i];
    }
    row.b = gradient.dot(q) - g;
    return row;
}

RenderParameters parameters(RenderingMethod method) {
    RenderParameters p;
    p.method = method;
    p.tracking_stiffness = kTrackingStiffness;
    return p;
}

ConfigVector pose() {
    ConfigVector q(3);
    q << 0.5, 0.7, 0.4;
    return q;
}

// The pad presses on a surface facing back against flexion.
constexpr double kNormalAngle = 2.6;

// alpha between 0 and the end of the actuator's stroke on the side `sign` where
// g(chi(q + B alpha / k_a)) crosses zero, by plain bisection, 200 halvings: the brute-force
// reference.
double bisectAlongActuator(const ExoskeletonDevice& exo, const msgs::LinearConstraint& row,
                           const ConfigVector& q, double sign) {
    ActuationMatrix B;
    exo.actuationMatrix(q, B);
    ActuatorVector ell;
    exo.actuatorCoordinates(q, ell);
    const ActuatorLimits limits = exo.actuatorLimits(0);
    const double bound = ((sign > 0.0 ? limits.stroke_max : limits.stroke_min) - ell[0]) *
                         kTrackingStiffness / B.col(0).squaredNorm();
    const ConfigVector direction = B.col(0) / kTrackingStiffness;
    double inside = 0.0;
    double outside = bound;
    for (int i = 0; i < 200; ++i) {
        const double middle = 0.5 * (inside + outside);
        const ConfigVector q_p = q + direction * middle;
        (contactGap(row.contact, q_p) < 0.0 ? inside : outside) = middle;
    }
    return outside;
}

double render(const ExoskeletonDevice& exo, RenderingMethod method,
              const msgs::LinearConstraint& row, const ConfigVector& q,
              RenderOutput* out_copy = nullptr) {
    KinestheticRenderer renderer(exo, parameters(method));
    RenderOutput out;
    const ConfigVector q_dot = ConfigVector::Zero(3);
    renderer.tick(q, q_dot, std::span<const msgs::LinearConstraint>(&row, 1), out);
    if (out_copy != nullptr) {
        *out_copy = out;
    }
    return out.actuator_force[0];
}

TEST(NonlinearSubspace, TheContactRowIsTheLinearisationOfItsGap) {
    const auto config = shippedExoskeleton();
    const ConfigVector q = pose();
    const msgs::LinearConstraint row = fingertipContact(config, q, 0.002, kNormalAngle);
    ASSERT_TRUE(usableContact(row.contact, 3));
    // g against finite differences, at q_ref and away from it.
    for (const double offset : {0.0, 0.2}) {
        ConfigVector q_eval = q;
        q_eval[1] += offset;
        ConfigVector gradient;
        const double g = contactGap(row.contact, q_eval, &gradient);
        for (int j = 0; j < 3; ++j) {
            ConfigVector plus = q_eval;
            ConfigVector minus = q_eval;
            plus[j] += 1e-6;
            minus[j] -= 1e-6;
            const double numeric =
                (contactGap(row.contact, plus) - contactGap(row.contact, minus)) / 2e-6;
            EXPECT_NEAR(gradient[j], numeric, 1e-8) << "joint " << j << " offset " << offset;
        }
        if (offset == 0.0) {
            EXPECT_NEAR(g, -0.002, 1e-15);
        }
    }
    // And g is the fingertip's distance to the plane on the device's own kinematics.
    const ExoskeletonDevice exo(config);
    ConfigVector q_moved = q;
    q_moved[0] += 0.3;
    PointVector tip_ref;
    PointVector tip_moved;
    exo.contactPoint(q, tip_ref);
    exo.contactPoint(q_moved, tip_moved);
    const Eigen::Vector2d normal(std::cos(kNormalAngle), std::sin(kNormalAngle));
    EXPECT_NEAR(contactGap(row.contact, q_moved), normal.dot(tip_moved - tip_ref) - 0.002, 1e-12);
}

TEST(NonlinearSubspace, MatchesABisectionAlongTheActuatedDirection) {
    const auto config = shippedExoskeleton();
    config::ExoskeletonConfig strong = config;
    strong.actuator.max_force_n = 1e6;  // the force clamp out of the way: alpha itself
    const ExoskeletonDevice exo(strong);
    const ConfigVector q = pose();
    for (const double depth : {0.0005, 0.002, 0.008, 0.02}) {
        const msgs::LinearConstraint row = fingertipContact(config, q, depth, kNormalAngle);
        RenderOutput out;
        const double alpha = render(exo, RenderingMethod::kSubspace, row, q, &out);
        ASSERT_EQ(out.fault, RenderFault::kNone) << depth;
        EXPECT_TRUE(out.in_contact);
        EXPECT_LE(out.iterations, 40);
        const double reference = bisectAlongActuator(exo, row, q, alpha > 0.0 ? 1.0 : -1.0);
        EXPECT_NEAR(alpha, reference, 1e-9 * std::abs(reference)) << "depth " << depth;
        EXPECT_GE(contactGap(row.contact, out.proxy), 0.0) << "the proxy is on the surface";
        EXPECT_LT(contactGap(row.contact, out.proxy), 1e-9);
    }
}

// linearized_subspace linearises the same g at q: the two agree to first order in the depth
// (their difference shrinks four times as the depth halves) and differ at depth, where the
// fingertip's arc leaves the tangent line.
TEST(NonlinearSubspace, LinearizedSubspaceIsItsFirstOrder) {
    const auto config = shippedExoskeleton();
    config::ExoskeletonConfig strong = config;
    strong.actuator.max_force_n = 1e6;
    const ExoskeletonDevice exo(strong);
    const ConfigVector q = pose();
    auto difference = [&](double depth) {
        const msgs::LinearConstraint row = fingertipContact(config, q, depth, kNormalAngle);
        const double exact = render(exo, RenderingMethod::kSubspace, row, q);
        const double linear = render(exo, RenderingMethod::kLinearizedSubspace, row, q);
        return std::pair{exact, linear};
    };
    const auto [exact_small, linear_small] = difference(0.0005);
    const auto [exact_half, linear_half] = difference(0.00025);
    const double error_small = std::abs(linear_small - exact_small);
    const double error_half = std::abs(linear_half - exact_half);
    EXPECT_LT(error_small / std::abs(exact_small), 0.01) << "equal to first order";
    EXPECT_NEAR(error_small / error_half, 4.0, 0.4) << "the difference is second order";
    const auto [exact_deep, linear_deep] = difference(0.02);
    EXPECT_GT(std::abs(linear_deep - exact_deep) / std::abs(exact_deep), 0.02)
        << "20 mm deep the arc and the tangent part";
    std::printf("alpha at 0.5 mm: %.4f N subspace, %.4f N linearized; at 20 mm: %.3f N, %.3f N\n",
                exact_small, linear_small, exact_deep, linear_deep);
}

// The proxy stays within the actuator's stroke: a contact deeper than the stroke can reach
// is rendered at the stroke's end and reported infeasible.
TEST(NonlinearSubspace, TheProxyStaysWithinTheActuatorsStroke) {
    const auto config = shippedExoskeleton();
    config::ExoskeletonConfig strong = config;
    strong.actuator.max_force_n = 1e6;
    const ExoskeletonDevice exo(strong);
    const ConfigVector q = pose();
    const msgs::LinearConstraint row = fingertipContact(config, q, 0.2, kNormalAngle);
    RenderOutput out;
    const double alpha = render(exo, RenderingMethod::kSubspace, row, q, &out);
    EXPECT_EQ(out.fault, RenderFault::kInfeasibleConstraints);
    ActuatorVector ell;
    exo.actuatorCoordinates(q, ell);
    ActuationMatrix B;
    exo.actuationMatrix(q, B);
    const double stroke_end =
        alpha > 0.0 ? config.actuator.stroke_max_m : config.actuator.stroke_min_m;
    EXPECT_NEAR(ell[0] + B.col(0).squaredNorm() * alpha / kTrackingStiffness, stroke_end, 1e-12);
    EXPECT_LT(contactGap(row.contact, out.proxy), 0.0) << "still inside: out of reach";
}

// Rows without their contact keep the exact QP on the linear rows (the tests of
// renderer_test.cpp); bad contact data is not evaluated.
TEST(NonlinearSubspace, ARowWithABadContactFallsBackToTheLinearRow) {
    const auto config = shippedExoskeleton();
    const ExoskeletonDevice exo(config);
    const ConfigVector q = pose();
    msgs::LinearConstraint row = fingertipContact(config, q, 0.002, kNormalAngle);
    msgs::LinearConstraint linear_only = row;
    linear_only.contact = msgs::ContactKinematics{};
    const double qp = render(exo, RenderingMethod::kSubspace, linear_only, q);
    for (auto spoil : {+[](msgs::ContactKinematics& c) { c.joints = 5; },
                       +[](msgs::ContactKinematics& c) {
                           c.normal = {0.0, 0.0, 0.0};
                       },
                       +[](msgs::ContactKinematics& c) { c.lever_m[1][0] = std::nan(""); },
                       +[](msgs::ContactKinematics& c) { c.joints = -1; }}) {
        msgs::LinearConstraint bad = row;
        spoil(bad.contact);
        EXPECT_FALSE(usableContact(bad.contact, 3));
        EXPECT_DOUBLE_EQ(render(exo, RenderingMethod::kSubspace, bad, q), qp);
    }
}

}  // namespace
}  // namespace haptic::kinesthetic
