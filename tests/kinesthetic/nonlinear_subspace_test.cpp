// subspace on the contact itself (msgs::ContactKinematics): the exoskeleton's fingertip
// pressing a plane, with the contact's chain built from the device's own planar kinematics
// (joint axes along z through the joint centres). Checked against a brute-force bisection of
// g(chi(q + B alpha / k_a)) along the actuated direction, against linearized_subspace (its
// linearisation at q: equal to first order, apart at depth), and at the actuator's stroke.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <utility>

#include "contact_rows.hpp"
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

// The shipped device with its force clamp out of the way, so that alpha itself shows.
ExoskeletonDevice unclampedExoskeleton() {
    config::ExoskeletonConfig strong = shippedExoskeleton();
    strong.actuator.max_force_n = 1e6;
    return ExoskeletonDevice(strong);
}

using testing::fingertipContact;

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

// The surface the fingertip presses on (its normal in the finger's plane).
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
    const ExoskeletonDevice exo = unclampedExoskeleton();
    const ConfigVector q = pose();
    // This surface is left by flexing the finger (a positive actuator force); the mirrored
    // one by extending it. The side is the geometry's, not read off the renderer.
    for (const auto& [normal_angle, side] :
         {std::pair{kNormalAngle, 1.0}, std::pair{kNormalAngle - std::numbers::pi, -1.0}}) {
        for (const double depth : {0.0005, 0.002, 0.008, 0.02}) {
            const msgs::LinearConstraint row = fingertipContact(config, q, depth, normal_angle);
            RenderOutput out;
            const double alpha = render(exo, RenderingMethod::kSubspace, row, q, &out);
            ASSERT_EQ(out.fault, RenderFault::kNone) << depth;
            EXPECT_FALSE(out.limited);
            EXPECT_TRUE(out.in_contact);
            const double reference = bisectAlongActuator(exo, row, q, side);
            EXPECT_NEAR(alpha, reference, 1e-6 * std::abs(reference))
                << "depth " << depth << " side " << side;
            EXPECT_GE(contactGap(row.contact, out.proxy), 0.0) << "the proxy is on the surface";
            EXPECT_LT(contactGap(row.contact, out.proxy), 1e-9) << "within 1 nm";
        }
    }
}

// linearized_subspace linearises the same g at q: the two agree to first order in the depth
// (their difference shrinks four times as the depth halves) and differ at depth, where the
// fingertip's arc leaves the tangent line.
TEST(NonlinearSubspace, LinearizedSubspaceIsItsFirstOrder) {
    const auto config = shippedExoskeleton();
    const ExoskeletonDevice exo = unclampedExoskeleton();
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
// is rendered at the stroke's end and reported as limited (not a fault: the device does what
// it can, and the channel keeps booking the spring's energy); at a stroke already past its
// limit on the side the push needs, nothing is pushed.
TEST(NonlinearSubspace, TheProxyStaysWithinTheActuatorsStroke) {
    const auto config = shippedExoskeleton();
    const ExoskeletonDevice exo = unclampedExoskeleton();
    const ConfigVector q = pose();
    const msgs::LinearConstraint row = fingertipContact(config, q, 0.2, kNormalAngle);
    RenderOutput out;
    const double alpha = render(exo, RenderingMethod::kSubspace, row, q, &out);
    EXPECT_EQ(out.fault, RenderFault::kNone);
    EXPECT_TRUE(out.limited);
    ActuatorVector ell;
    exo.actuatorCoordinates(q, ell);
    ActuationMatrix B;
    exo.actuationMatrix(q, B);
    ASSERT_GT(alpha, 0.0);
    EXPECT_NEAR(ell[0] + B.col(0).squaredNorm() * alpha / kTrackingStiffness,
                config.actuator.stroke_max_m, 1e-12);
    EXPECT_LT(contactGap(row.contact, out.proxy), 0.0) << "still inside: out of reach";

    config::ExoskeletonConfig past = config;
    past.actuator.max_force_n = 1e6;
    past.actuator.stroke_max_m = ell[0] - 0.001;  // the stroke already 1 mm past its maximum
    const ExoskeletonDevice at_stop(past);
    const msgs::LinearConstraint shallow = fingertipContact(config, q, 0.001, kNormalAngle);
    EXPECT_EQ(render(at_stop, RenderingMethod::kSubspace, shallow, q, &out), 0.0);
    EXPECT_TRUE(out.limited);
    EXPECT_EQ(out.fault, RenderFault::kNone);

    // Within the force limit too: the shipped 40 N actuator.
    const ExoskeletonDevice shipped(config);
    EXPECT_DOUBLE_EQ(render(shipped, RenderingMethod::kSubspace, row, q, &out),
                     config.actuator.max_force_n);
    EXPECT_TRUE(out.limited);
}

// actuator.stroke_min_m, the stroke's other end: a contact that needs the rod drawn in is
// rendered at the minimum stroke; with the minimum raised above the present stroke, nothing is
// drawn.
TEST(NonlinearSubspace, TheProxyStaysAboveTheActuatorsMinimumStroke) {
    const auto config = shippedExoskeleton();
    const ConfigVector q = pose();
    const double opposite = kNormalAngle - std::numbers::pi;
    const msgs::LinearConstraint row = fingertipContact(config, q, 0.2, opposite);
    RenderOutput out;
    const double alpha = render(unclampedExoskeleton(), RenderingMethod::kSubspace, row, q, &out);
    EXPECT_EQ(out.fault, RenderFault::kNone);
    EXPECT_TRUE(out.limited);
    const ExoskeletonDevice exo(config);
    ActuatorVector ell;
    exo.actuatorCoordinates(q, ell);
    ActuationMatrix B;
    exo.actuationMatrix(q, B);
    ASSERT_LT(alpha, 0.0);
    EXPECT_NEAR(ell[0] + B.col(0).squaredNorm() * alpha / kTrackingStiffness,
                config.actuator.stroke_min_m, 1e-12);

    config::ExoskeletonConfig raised = config;
    raised.actuator.max_force_n = 1e6;
    raised.actuator.stroke_min_m = ell[0] + 0.001;  // the stroke already 1 mm below its minimum
    const msgs::LinearConstraint shallow = fingertipContact(config, q, 0.001, opposite);
    EXPECT_EQ(render(ExoskeletonDevice(raised), RenderingMethod::kSubspace, shallow, q, &out), 0.0);
    EXPECT_TRUE(out.limited);
    EXPECT_EQ(out.fault, RenderFault::kNone);
}

// Two contacts: every contact is checked at the chosen alpha. A clear contact the push drives
// into, or two contacts that need pushes both ways, are infeasible for one actuator.
TEST(NonlinearSubspace, AContactThePushDrivesIntoIsReported) {
    const auto config = shippedExoskeleton();
    const ExoskeletonDevice exo(config);
    const ConfigVector q = pose();
    // Pressed 2 mm into one surface; 0.1 mm clear of the opposite one.
    const std::array<msgs::LinearConstraint, 2> squeezed{
        fingertipContact(config, q, 0.002, kNormalAngle),
        fingertipContact(config, q, -0.0001, kNormalAngle - std::numbers::pi)};
    KinestheticRenderer renderer(exo, parameters(RenderingMethod::kSubspace));
    RenderOutput out;
    const ConfigVector q_dot = ConfigVector::Zero(3);
    renderer.tick(q, q_dot, squeezed, out);
    EXPECT_EQ(out.fault, RenderFault::kInfeasibleConstraints);
    EXPECT_EQ(out.active_constraints, 1);
    EXPECT_LT(contactGap(squeezed[1].contact, out.proxy), 0.0) << "pushed into the second";
    // Pressed into both: pushes both ways.
    const std::array<msgs::LinearConstraint, 2> both{
        fingertipContact(config, q, 0.002, kNormalAngle),
        fingertipContact(config, q, 0.001, kNormalAngle - std::numbers::pi)};
    renderer.tick(q, q_dot, both, out);
    EXPECT_EQ(out.fault, RenderFault::kInfeasibleConstraints);
    EXPECT_EQ(out.active_constraints, 2);
    // One alone is feasible.
    renderer.tick(q, q_dot, std::span(squeezed).first(1), out);
    EXPECT_EQ(out.fault, RenderFault::kNone);
}

// Rows without their contact keep the exact QP on the linear rows (the tests of
// renderer_test.cpp). hapticd rejects bad contact data on receipt
// (DaemonCoreTest.RejectsABadContactBehindAConstraintRow); the renderer does not evaluate it
// either.
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

// A chain whose axes are not parallel (a 3-D finger: abducted MCP, twisted phalanges), with
// g from contactGap against an independent forward kinematics: joint after joint, each
// rotation about its axis as the joints before it have moved it, applied to the point and to
// the axes and anchors further out ("moving frames"); and contactGap's gradient against
// finite differences of that.
struct Chain {
    std::array<Eigen::Vector3d, 3> axis;
    std::array<Eigen::Vector3d, 3> anchor;
    Eigen::Vector3d point;
    Eigen::Vector3d normal;
};

Chain tiltedChain() {
    Chain c;
    c.axis = {Eigen::Vector3d(0.1, 1.0, 0.2).normalized(),
              Eigen::Vector3d(0.0, 1.0, -0.3).normalized(),
              Eigen::Vector3d(-0.2, 1.0, 0.1).normalized()};
    c.anchor = {Eigen::Vector3d(0.0, 0.0, 0.0), Eigen::Vector3d(0.045, 0.004, -0.002),
                Eigen::Vector3d(0.072, 0.006, -0.006)};
    c.point = Eigen::Vector3d(0.090, 0.008, -0.018);
    c.normal = Eigen::Vector3d(0.3, -0.1, 1.0).normalized();
    return c;
}

Eigen::Vector3d movingFramesPoint(const Chain& chain, const ConfigVector& q_ref,
                                  const ConfigVector& q) {
    Chain moved = chain;
    for (int j = 0; j < 3; ++j) {
        const auto k = static_cast<std::size_t>(j);
        const Eigen::AngleAxisd turn(q[j] - q_ref[j], moved.axis[k]);
        const Eigen::Vector3d pivot = moved.anchor[k];
        auto carry = [&](const Eigen::Vector3d& x) -> Eigen::Vector3d {
            return pivot + turn * (x - pivot);
        };
        for (std::size_t further = k + 1; further < 3; ++further) {
            moved.axis[further] = turn * moved.axis[further];
            moved.anchor[further] = carry(moved.anchor[further]);
        }
        moved.point = carry(moved.point);
    }
    return moved.point;
}

msgs::ContactKinematics contactOf(const Chain& chain, const ConfigVector& q_ref, double gap_m) {
    msgs::ContactKinematics c;
    c.joints = 3;
    c.gap_m = gap_m;
    c.normal = {chain.normal.x(), chain.normal.y(), chain.normal.z()};
    for (std::size_t j = 0; j < 3; ++j) {
        c.q_ref_rad[j] = q_ref[static_cast<Eigen::Index>(j)];
        c.axis[j] = {chain.axis[j].x(), chain.axis[j].y(), chain.axis[j].z()};
        const Eigen::Vector3d lever = chain.point - chain.anchor[j];
        c.lever_m[j] = {lever.x(), lever.y(), lever.z()};
    }
    return c;
}

TEST(NonlinearSubspace, TheGapFollowsAChainWithTiltedAxes) {
    const Chain chain = tiltedChain();
    ConfigVector q_ref(3);
    q_ref << 0.2, 0.3, 0.1;
    const msgs::ContactKinematics contact = contactOf(chain, q_ref, -0.001);
    ConfigVector q(3);
    q << 0.65, 0.9, 0.55;
    const double expected =
        chain.normal.dot(movingFramesPoint(chain, q_ref, q) - chain.point) - 0.001;
    ConfigVector gradient;
    EXPECT_NEAR(contactGap(contact, q, &gradient), expected, 1e-12);
    for (int j = 0; j < 3; ++j) {
        ConfigVector plus = q;
        ConfigVector minus = q;
        plus[j] += 1e-6;
        minus[j] -= 1e-6;
        const double numeric = chain.normal.dot(movingFramesPoint(chain, q_ref, plus) -
                                                movingFramesPoint(chain, q_ref, minus)) /
                               2e-6;
        EXPECT_NEAR(gradient[j], numeric, 1e-8) << "joint " << j;
    }
}

// linearized_subspace at a q away from the sim's q_ref: the contact re-linearised there (an
// independent reference from the moving-frames kinematics and finite differences), not the
// sim's row.
TEST(NonlinearSubspace, LinearizedSubspaceLinearisesAtTheCurrentConfiguration) {
    const auto config = shippedExoskeleton();
    const ExoskeletonDevice exo = unclampedExoskeleton();
    const ConfigVector q_ref = pose();
    msgs::LinearConstraint row = fingertipContact(config, q_ref, 0.001, kNormalAngle);
    ConfigVector q = q_ref;
    q[0] -= 0.06;  // the device's finger 0.06 rad off the sim's at the frame, further in
    q[2] -= 0.04;
    // g and its gradient at q, independently: the planar chain as moving frames.
    Chain planar;
    for (std::size_t j = 0; j < 3; ++j) {
        planar.axis[j] = Eigen::Vector3d::UnitZ();
        planar.anchor[j] =
            Eigen::Vector3d(-row.contact.lever_m[j][0], -row.contact.lever_m[j][1], 0.0);
    }
    planar.point = Eigen::Vector3d::Zero();
    planar.normal = Eigen::Vector3d(std::cos(kNormalAngle), std::sin(kNormalAngle), 0.0);
    auto g = [&](const ConfigVector& at) {
        return planar.normal.dot(movingFramesPoint(planar, q_ref, at)) - 0.001;
    };
    ConfigVector grad(3);
    for (int j = 0; j < 3; ++j) {
        ConfigVector plus = q;
        ConfigVector minus = q;
        plus[j] += 1e-7;
        minus[j] -= 1e-7;
        grad[j] = (g(plus) - g(minus)) / 2e-7;
    }
    ActuationMatrix B;
    exo.actuationMatrix(q, B);
    ASSERT_LT(g(q), 0.0) << "still pressed at q";
    const double expected = -g(q) * kTrackingStiffness / grad.dot(B.col(0));
    const double relinearised = render(exo, RenderingMethod::kLinearizedSubspace, row, q);
    EXPECT_NEAR(relinearised, expected, 1e-6 * std::abs(expected));
    msgs::LinearConstraint row_only = row;
    row_only.contact = msgs::ContactKinematics{};
    const double from_the_row = render(exo, RenderingMethod::kLinearizedSubspace, row_only, q);
    EXPECT_GT(std::abs(from_the_row - relinearised), 1e-3 * std::abs(relinearised))
        << "the sim's row, linearised 0.06 rad away, is not the same";
    std::printf("linearized at q: %.4f N (independent %.4f N), from the sim's row %.4f N\n",
                relinearised, expected, from_the_row);
}

}  // namespace
}  // namespace haptic::kinesthetic
